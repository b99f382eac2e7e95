"""Figures of the uncertainty study: P(best) with its intervals, recovery-time distributions, paired rows, Sobol bars.

Each takes the tables of :class:`whipple_kick.studies.uncertainty.UncertaintyStudy`
(plain DataFrames, so a study's CSV files read back draw the same figures) and
returns a :class:`matplotlib.figure.Figure` on its own Agg canvas, or writes it
to ``path`` as PNG.
"""
import math

import numpy as np
import pandas as pd

from whipple_kick.simulate.criteria import CRITERIA

from .plotting import _written

#: Colours of the two criteria.
_COLOURS = {"settling": "tab:blue", "last_peak": "tab:orange"}


def _criterion_text(criterion):
    """A criterion's short name, read when drawn: a criterion declared after this module's import has one too
    (:data:`whipple_kick.simulate.criteria.CRITERIA`)."""
    return CRITERIA[criterion].short if criterion in CRITERIA else criterion


def _figure(n_panels, height=3.6, rows=1):
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    fig = Figure(figsize=(4.0 * n_panels + 0.5, height * rows))
    FigureCanvasAgg(fig)
    axes = fig.subplots(rows, n_panels, squeeze=False)
    return fig, (axes[0] if rows == 1 else axes)


def p_best_figure(p_best, path=None, title=None, dpi=120):
    """P(best) per pressure and the ``none`` share (no pressure recovered), one panel per rear load, both
    criteria side by side, 95 % intervals as bars.

    The measured best pressure (thesis Table 8.9) is marked with a star above its bars' intervals; the legend
    sits below the panels, where it hides no bar and no star.
    """
    loads = list(dict.fromkeys(p_best["fz_n"]))
    fig, axes = _figure(len(loads), height=3.9)
    criteria = list(dict.fromkeys(p_best["criterion"]))
    width = 0.8 / max(len(criteria), 1)
    for ax, fz in zip(axes, loads, strict=True):
        at = p_best[p_best["fz_n"] == fz]
        pressures = sorted(set(at["pressure_kpa"].dropna()))
        x = np.arange(len(pressures) + 1)   # the last: none recovered
        top = np.zeros(len(x))
        for k, criterion in enumerate(criteria):
            rows = at[at["criterion"] == criterion]
            named = rows[rows["pressure_kpa"].notna()].set_index("pressure_kpa").loc[pressures].reset_index()
            rows = pd.concat([named, rows[rows["pressure_kpa"].isna()]], ignore_index=True)
            p = rows["p"].to_numpy(dtype=float)
            low, high = rows["low"].to_numpy(dtype=float), rows["high"].to_numpy(dtype=float)
            err = np.vstack([p - low, high - p])
            bars = ax.bar(x + (k - (len(criteria) - 1) / 2) * width, p, width, yerr=np.clip(err, 0, None), capsize=3,
                          color=_COLOURS.get(criterion), label=_criterion_text(criterion))
            bars[-1].set_hatch("//")
            bars[-1].set_alpha(0.6)
            top = np.maximum(top, np.where(np.isfinite(high), high, p))
        measured = [i for i, pr in enumerate(pressures)
                    if bool(at[at["pressure_kpa"] == pr]["measured_best"].any())]
        for i in measured:
            ax.plot(i, min(top[i] + 0.06, 1.08), marker="*", color="k", markersize=12, linestyle="none")
        ax.set_xticks(x, [*(f"{pr:g}" for pr in pressures), "none"])
        ax.set_ylim(0, 1.12)
        ax.set_xlabel("pressure [kPa]  (star: measured best, Table 8.9)")
        ax.set_title(f"rear load {fz:g} N")
    axes[0].set_ylabel("P(best)")
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, fontsize=8, loc="lower center", ncol=len(labels) + 1, frameon=False)
    if title:
        fig.suptitle(title, fontsize=10)
    fig.tight_layout(rect=(0, 0.07, 1, 1))
    return _written(fig, path, dpi)


def distribution_figure(outcomes, criterion="settling", path=None, title=None, dpi=120):
    """Recovery-time distribution per pressure (violins of the recovered runs), one panel per load.

    The share of runs that did not recover (fell, not settled within the run, failed) is written above each violin.
    """
    col = CRITERIA[criterion].column
    loads = list(dict.fromkeys(outcomes["fz_n"]))
    fig, axes = _figure(len(loads))
    base = outcomes[outcomes["block"].isin(["A", "B"])]
    for ax, fz in zip(axes, loads, strict=True):
        at = base[base["fz_n"] == fz]
        pressures = sorted(set(at["pressure_kpa"]))
        data, lost = [], []
        for p in pressures:
            rows = at[at["pressure_kpa"] == p]
            v = rows[col].to_numpy(dtype=float)
            ok = np.isfinite(v) & ~rows["fell"].to_numpy(dtype=bool) & (rows["status"] == "ok").to_numpy()
            data.append(v[ok] if ok.any() else np.array([math.nan]))
            lost.append(1.0 - ok.mean() if len(ok) else math.nan)
        positions = np.arange(len(pressures))
        drawable = [k for k, d in enumerate(data) if np.isfinite(d).sum() > 1]
        if drawable:
            ax.violinplot([data[k] for k in drawable], positions=positions[drawable], showmedians=True)
        top = max((np.nanmax(d) for d in data if np.isfinite(d).any()), default=1.0)
        for k, share in enumerate(lost):
            ax.text(positions[k], top * 1.05, f"{100 * share:.0f} % not recovered", ha="center", fontsize=8)
        ax.set_ylim(0, top * 1.15)
        ax.set_xticks(positions, [f"{p:g}" for p in pressures])
        ax.set_xlabel("pressure [kPa]")
        ax.set_title(f"rear load {fz:g} N")
    axes[0].set_ylabel(f"{_criterion_text(criterion)} [s]")
    if title:
        fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    return _written(fig, path, dpi)


def sobol_figure(sobol, criterion="settling", pair=None, path=None, title=None, dpi=120):
    """First-order and total Sobol indices (95 % intervals) of which of two pressures recovers first: a column
    of panels per load, a row per pair of pressures.

    ``pair`` is (pressure a, pressure b) [kPa] for one pair at every load, or ``{load: pair}`` for each load's
    own pair (e.g. its two most probable best); default every pair. Each panel's title gives the share of rows
    where one or neither run recovered (the output gives them no time: docs/uncertainty.md).
    """
    at = sobol[sobol["criterion"] == criterion]
    loads = list(dict.fromkeys(at["fz_n"])) or [math.nan]
    every = list(dict.fromkeys(zip(at["pressure_a_kpa"], at["pressure_b_kpa"], strict=True)))

    def pairs_at(fz):
        if pair is None:
            return every
        chosen = pair.get(fz) if isinstance(pair, dict) else pair
        return [tuple(sorted(chosen))] if chosen is not None else []
    n_rows = max([len(pairs_at(fz)) for fz in loads] + [1])
    fig, axes = _figure(len(loads), height=3.6, rows=n_rows)
    axes = np.atleast_2d(axes).reshape(n_rows, len(loads))
    for c, fz in enumerate(loads):
        chosen = pairs_at(fz)
        for r in range(n_rows):
            ax = axes[r, c]
            if r >= len(chosen) or not np.isfinite(fz):
                ax.set_axis_off()
                ax.set_title("no indices" if not np.isfinite(fz) else "")
                continue
            a, b = chosen[r]
            rows = at[(at["fz_n"] == fz) & (at["pressure_a_kpa"] == a) & (at["pressure_b_kpa"] == b)]
            y = np.arange(len(rows))
            ax.barh(y - 0.2, rows["ST"], 0.4, xerr=rows["ST_conf"], capsize=2, color="tab:red", label="total")
            ax.barh(y + 0.2, rows["S1"], 0.4, xerr=rows["S1_conf"], capsize=2, color="tab:gray", label="first order")
            ax.set_yticks(y, list(rows["input"]), fontsize=8)
            ax.invert_yaxis()
            ax.axvline(0, color="k", lw=0.5)
            ax.set_xlabel("Sobol index")
            head = f"{fz:g} N: {a:g} vs {b:g} kPa"
            if len(rows) and "rows" in rows:
                n = rows["rows"].iloc[0]
                head += (f"\none not recovered {100 * rows['rows_one_not_recovered'].iloc[0] / n:.0f} %, neither "
                         f"{100 * rows['rows_neither_recovered'].iloc[0] / n:.0f} %")
            ax.set_title(head, fontsize=9)
    if title is None:
        title = f"what decides which pressure recovers first by the {_criterion_text(criterion)}"
    return _finish(fig, axes, title, path, dpi)


def paired_figure(outcomes, criterion="settling", path=None, title=None, dpi=120):
    """The paired rows: each row's time at one pressure against its time at another (one point per row of the
    base matrices), a column of panels per load, a row per pair of pressures.

    Below the diagonal the second pressure recovered first. A run that did not recover (fell, not settled
    within the run, failed) has no time: it is drawn on the band beyond the axis' largest time, marked
    "not recovered", never at a time. Each panel gives P(first pressure first), P(second first) and the share
    where neither recovered.
    """
    col = CRITERIA[criterion].column
    base = outcomes[outcomes["block"].isin(["A", "B"])]
    loads = list(dict.fromkeys(base["fz_n"]))
    pressures = sorted(set(base["pressure_kpa"]))
    pairs = [(a, b) for k, a in enumerate(pressures) for b in pressures[k + 1:]]
    fig, axes = _figure(len(loads), height=3.6, rows=max(len(pairs), 1))
    axes = np.atleast_2d(axes).reshape(max(len(pairs), 1), len(loads))
    for c, fz in enumerate(loads):
        at = base[base["fz_n"] == fz]
        ok = (np.isfinite(at[col].to_numpy(dtype=float)) & ~at["fell"].to_numpy(dtype=bool)
              & (at["status"] == "ok").to_numpy())
        t = np.where(ok, at[col].to_numpy(dtype=float), np.inf)
        table = {p: t[(at["pressure_kpa"] == p).to_numpy()] for p in pressures}
        finite = np.concatenate([v[np.isfinite(v)] for v in table.values()])
        low, high = (float(finite.min()), float(finite.max())) if finite.size else (0.0, 1.0)
        low = max(0.0, low - 0.1 * (high - low + 0.1))
        edge = high + 0.1 * (high - low + 0.1)   # the band of runs that did not recover
        for r, (a, b) in enumerate(pairs):
            ax = axes[r, c]
            ta, tb = table[a], table[b]
            draw_a, draw_b = np.where(np.isfinite(ta), ta, edge), np.where(np.isfinite(tb), tb, edge)
            lost = ~np.isfinite(ta) | ~np.isfinite(tb)
            ax.scatter(draw_a[~lost], draw_b[~lost], s=10, color=_COLOURS.get(criterion), label="both recovered")
            ax.scatter(draw_a[lost], draw_b[lost], s=18, marker="x", color="k", label="one or both not recovered")
            pad = 0.04 * (edge - low)
            ax.plot([low, edge], [low, edge], color="k", lw=0.5)
            ax.axvspan(edge - pad, edge + pad, color="0.9")
            ax.axhspan(edge - pad, edge + pad, color="0.9")
            ax.set_xlim(low, edge + pad)
            ax.set_ylim(low, edge + pad)
            n = len(ta)
            first_a, first_b = float(np.mean(ta < tb)) if n else math.nan, float(np.mean(tb < ta)) if n else math.nan
            neither = float(np.mean(~np.isfinite(ta) & ~np.isfinite(tb))) if n else math.nan
            ax.text(0.03, 0.9, f"{a:g} first {first_a:.2f}\n{b:g} first {first_b:.2f}\nneither {neither:.2f}",
                    transform=ax.transAxes, va="top", fontsize=8)
            ax.text(edge, (low + edge) / 2, "not recovered", rotation=90, fontsize=7, va="center", ha="center")
            ax.set_xlabel(f"{_criterion_text(criterion)} at {a:g} kPa [s]")
            ax.set_ylabel(f"at {b:g} kPa [s]")
            ax.set_title(f"rear load {fz:g} N ({n} paired rows)", fontsize=9)
    if title is None:
        title = f"paired rows: {_criterion_text(criterion)} at two pressures on the same inputs"
    return _finish(fig, axes, title, path, dpi)


def _finish(fig, axes, title, path, dpi):
    """A grid figure's legend (the first panel's, below the panels: it hides nothing), title and layout."""
    handles, labels = axes[0, 0].get_legend_handles_labels()
    if handles:
        fig.legend(handles, labels, fontsize=8, loc="lower center", ncol=2, frameon=False)
    fig.suptitle(title, fontsize=10)
    fig.tight_layout(rect=(0, 0.05 / axes.shape[0], 1, 1))
    return _written(fig, path, dpi)
