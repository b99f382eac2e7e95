"""Figures of the uncertainty study: P(best) with its intervals, recovery-time distributions, Sobol bars.

Each takes the tables of :class:`whipple_kick.studies.uncertainty.UncertaintyStudy`
(plain DataFrames, so a study's CSV files read back draw the same figures) and
returns a :class:`matplotlib.figure.Figure` on its own Agg canvas, or writes it
to ``path`` as PNG.
"""
import math

import numpy as np

from whipple_kick.simulate.criteria import CRITERIA

from .plotting import _written

#: Colours of the two criteria.
_COLOURS = {"settling": "tab:blue", "last_peak": "tab:orange"}
#: Each criterion's short name (:data:`whipple_kick.simulate.criteria.CRITERIA`).
_CRITERION_TEXT = {key: c.short for key, c in CRITERIA.items()}


def _figure(n_panels, height=3.6):
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    fig = Figure(figsize=(4.0 * n_panels + 0.5, height))
    FigureCanvasAgg(fig)
    return fig, fig.subplots(1, n_panels, squeeze=False)[0]


def p_best_figure(p_best, path=None, title=None, dpi=120):
    """P(best) per pressure, one panel per rear load, both criteria side by side, 95 % intervals as bars.

    The measured best pressure (thesis Table 8.9) is marked with a star above its bars.
    """
    loads = list(dict.fromkeys(p_best["fz_n"]))
    fig, axes = _figure(len(loads))
    criteria = list(dict.fromkeys(p_best["criterion"]))
    width = 0.8 / max(len(criteria), 1)
    for ax, fz in zip(axes, loads, strict=True):
        at = p_best[(p_best["fz_n"] == fz) & p_best["pressure_kpa"].notna()]
        pressures = sorted(set(at["pressure_kpa"]))
        x = np.arange(len(pressures))
        for k, criterion in enumerate(criteria):
            rows = at[at["criterion"] == criterion].set_index("pressure_kpa").loc[pressures]
            p = rows["p"].to_numpy(dtype=float)
            err = np.vstack([p - rows["low"].to_numpy(dtype=float), rows["high"].to_numpy(dtype=float) - p])
            ax.bar(x + (k - (len(criteria) - 1) / 2) * width, p, width, yerr=np.clip(err, 0, None), capsize=3,
                   color=_COLOURS.get(criterion), label=_CRITERION_TEXT.get(criterion, criterion))
        measured = [i for i, pr in enumerate(pressures)
                    if bool(at[at["pressure_kpa"] == pr]["measured_best"].any())]
        for i in measured:
            ax.plot(i, 0.95, marker="*", color="k", markersize=12)
        ax.set_xticks(x, [f"{pr:g}" for pr in pressures])
        ax.set_ylim(0, 1)
        ax.set_xlabel("pressure [kPa]  (star: measured best, Table 8.9)")
        ax.set_title(f"rear load {fz:g} N")
    axes[0].set_ylabel("P(best)")
    axes[0].legend(fontsize=8, loc="upper left")
    if title:
        fig.suptitle(title, fontsize=10)
    fig.tight_layout()
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
    axes[0].set_ylabel(f"{_CRITERION_TEXT[criterion]} [s]")
    if title:
        fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    return _written(fig, path, dpi)


def sobol_figure(sobol, criterion="settling", pair=None, path=None, title=None, dpi=120):
    """First-order and total Sobol indices (95 % intervals) of one paired difference, one panel per load.

    ``pair`` is (pressure a, pressure b) [kPa]; default the first pair in the table.
    """
    at = sobol[sobol["criterion"] == criterion]
    if pair is None and len(at):
        pair = (at["pressure_a_kpa"].iloc[0], at["pressure_b_kpa"].iloc[0])
    loads = list(dict.fromkeys(at["fz_n"])) or [math.nan]
    fig, axes = _figure(len(loads), height=4.2)
    for ax, fz in zip(axes, loads, strict=True):
        rows = at[(at["fz_n"] == fz) & (at["pressure_a_kpa"] == pair[0]) & (at["pressure_b_kpa"] == pair[1])] \
            if pair is not None else at.iloc[:0]
        y = np.arange(len(rows))
        ax.barh(y - 0.2, rows["ST"], 0.4, xerr=rows["ST_conf"], capsize=2, color="tab:red", label="total")
        ax.barh(y + 0.2, rows["S1"], 0.4, xerr=rows["S1_conf"], capsize=2, color="tab:gray", label="first order")
        ax.set_yticks(y, list(rows["input"]), fontsize=8)
        ax.invert_yaxis()
        ax.axvline(0, color="k", lw=0.5)
        ax.set_xlabel("Sobol index")
        ax.set_title(f"rear load {fz:g} N" if np.isfinite(fz) else "no indices")
    axes[0].legend(fontsize=8, loc="lower right")
    if title is None and pair is not None:
        title = f"what the {pair[1]:g} - {pair[0]:g} kPa difference of the {_CRITERION_TEXT[criterion]} hinges on"
    if title:
        fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    return _written(fig, path, dpi)
