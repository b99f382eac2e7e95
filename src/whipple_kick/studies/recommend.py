"""The pressure recommender: which inflation pressure recovers fastest after a kick, and how sure that is.

:func:`recommend_pressure` sweeps a tyre's pressures for one rear load
(:func:`whipple_kick.studies.sweep_engine.sweep`) and returns the pressure with the
shortest recovery time (yaw, roll and steer rates settled; or the thesis'
last-peak rule, Section 8.3 and Table 8.9), with the margin to the second
best and whether that margin is clear of the model's own spread. The
``recommend-pressure`` command prints :func:`format_recommendation`.

Example
-------
Skipped as a doctest: three 6 s kick runs in a process pool, several seconds
(``tests/studies/test_recommend.py`` runs it).

>>> from whipple_kick import recommend
>>> rec = recommend.recommend_pressure(635)              # doctest: +SKIP
>>> rec.best_pressure_kpa, rec.margin_s, rec.verdict     # doctest: +SKIP
"""
import dataclasses
import math

import numpy as np

from whipple_kick.errors import InputError, check_range
from whipple_kick.library import tyres
from whipple_kick.simulate import criteria
from whipple_kick.simulate.criteria import CRITERIA  # the one table: every declared criterion
from whipple_kick.simulate.scenario import Scenario

from .sweep_engine import check_some_ok, sweep

# --------------------------------------------------------------- the pressure recommender

#: Spread [s] of each criterion's value, below which a difference between pressures is not to be trusted
#: (:attr:`whipple_kick.simulate.criteria.Criterion.spread_s`, where it is declared and measured). A margin
#: between the best and the second-best pressure below the spread is "no clear optimum". The probability of
#: each pressure being best over the inputs nothing pins down is the uncertainty study's
#: (``recommend-pressure --uncertain``, :mod:`whipple_kick.studies.uncertainty`), which uses no fixed spread.
CRITERION_SPREAD_S = criteria.attribute("spread_s")


def criterion_key(criterion):
    """The :data:`CRITERIA` key of ``criterion`` (``"last-peak"`` as the CLI spells it is accepted)."""
    key = str(criterion).replace("-", "_")
    if key not in CRITERIA:
        raise InputError(f"criterion = {criterion!r} is unknown; choose one of "
                         f"{', '.join(k.replace('_', '-') for k in CRITERIA)}")
    return key


@dataclasses.dataclass
class Recommendation:
    """Result of :func:`recommend_pressure` for one rear load.

    Attributes
    ----------
    fz_n : float
        Static rear-tyre load [N].
    tyre : str
    best_pressure_kpa : float or None
        Pressure [kPa] ranked first (None if no case recovered or there is nothing to choose).
    best_measured_kpa : float or None
        The same among the measured pressures only.
    criterion : str
        Key of :data:`CRITERIA` the pressures were ranked by.
    margin_s : float or None
        Second-best minus best value of the criterion [s] (None with fewer
        than two pressures that recovered).
    spread_s : float
        :data:`CRITERION_SPREAD_S` of the criterion [s].
    verdict : str
        ``"clear"`` (margin >= spread, or the only pressure that recovered),
        ``"no clear optimum"`` (margin below the spread), ``"nothing to
        choose"`` (one pressure), ``"none recovered"``, or ``"incomplete"``
        when a case failed (it has no result, so it may have been the best:
        ``best_pressure_kpa`` is then the best of the others, never "clear").
    table : pandas.DataFrame
        One row per pressure: ``pressure_kpa``, ``measured``,
        ``recovery.time_s`` [s], ``last_peak_time_s`` [s], the yaw, roll and
        steer rates' settling times [s], ``n_peaks``, ``damping_ratio_1_3``,
        ``period_s``, ``peaks.max_abs_roll_absolute_rad``, ``fell``, ``status``,
        ``error``, ``rank``.
    failed : int
        Cases (pressures) of this load that failed: no result, ranked after every fall.
    """

    fz_n: float
    tyre: str
    best_pressure_kpa: float | None
    best_measured_kpa: float | None
    criterion: str
    margin_s: float | None
    spread_s: float
    verdict: str
    table: "object"
    failed: int = 0


def tyre_pressures(tyre="T03", coefficient_set="table7_9"):
    """Measured pressures [kPa] of a tyre's coefficient set."""
    files = tyres._tyre_files()
    if tyre not in files:
        raise InputError(f"tyre = {tyre!r} is unknown; choose one of {', '.join(files)}")
    data = tyres.read_tyre_file(files[tyre])
    if coefficient_set not in data.sets:
        raise InputError(f"coefficient_set = {coefficient_set!r} does not exist for tyre {tyre}; "
                         f"choose one of {', '.join(data.sets)}")
    return sorted(float(p) for p in data.sets[coefficient_set])


def pressure_grid(tyre="T03", pressures=None, fine=False, step_kpa=10.0, coefficient_set="table7_9"):
    """Pressures [kPa] to try and which of them were measured.

    Returns
    -------
    pressures : list of float
        Sorted; the measured ones (or ``pressures``), plus with ``fine`` a
        grid of ``step_kpa`` between the smallest and largest measured
        pressure (interpolated tyres, :func:`whipple_kick.library.tyres.load`).
    measured : set of float
    """
    measured = tyre_pressures(tyre, coefficient_set)
    if pressures is None:
        chosen = measured
    else:
        # Checked here: inside the sweep a bad pressure would only fail its case.
        chosen = sorted({check_range(f"pressure of tyre {tyre}", p, measured[0], measured[-1], "kPa")
                         for p in pressures})
    if not chosen:
        raise InputError("give at least one pressure (kPa)")
    out = set(chosen)
    if fine:
        step = float(step_kpa)
        if not (math.isfinite(step) and step > 0):
            raise InputError(f"pressure step = {step_kpa!r} kPa must be > 0 kPa")
        n = int(math.floor((measured[-1] - measured[0]) / step + 1e-9))
        out.update(round(measured[0] + k * step, 9) for k in range(n + 1))
    return sorted(out), set(measured)


def _did_not_recover(table):
    """Rows that fell or failed (never ranked ahead of a run that did not)."""
    return _outcome_class(table) > 0


def _outcome_class(table):
    """0 a run that did not fall, 1 a fall (a result: the pressure lost the bicycle), 2 a failed case (no result)."""
    fell = table["fell"].map(lambda v: v is True or _num(v) == 1.0).to_numpy()
    failed = (table["status"] != "ok").to_numpy()
    return np.where(failed, 2, np.where(fell, 1, 0))


def _rank(table, criterion):
    """Row order: runs that neither fell nor failed first, by the criterion's columns (missing last), then the
    falls, then the failed cases (which have no result to rank: never ranked like a fall)."""
    keys = [np.where(np.isfinite(v), v, np.inf)
            for v in (table[col].map(_num).to_numpy(dtype=float) for col in CRITERIA[criterion].columns)]
    return np.lexsort(keys[::-1] + [_outcome_class(table)])


def _ranked_values(rows, criterion):
    """(pressures, values) of the rows with a value of the criterion, best first."""
    order = _rank(rows, criterion)
    values = rows[CRITERIA[criterion].column].map(_num).to_numpy(dtype=float)[order]
    ok = np.isfinite(values) & ~_did_not_recover(rows)[order]
    return rows["pressure_kpa"].to_numpy(dtype=float)[order][ok], values[ok]


def _verdict(rows, criterion):
    """(best pressure, margin, verdict) of one load's rows (see :class:`Recommendation`)."""
    if len(rows) == 1:
        return None, None, "nothing to choose"
    pressures, values = _ranked_values(rows, criterion)
    margin = float(values[1] - values[0]) if pressures.size > 1 else None
    best = float(pressures[0]) if pressures.size else None
    if (rows["status"] != "ok").any():
        return best, margin, "incomplete"   # a failed case has no result: it may have been the best
    if best is None:
        return None, None, "none recovered"
    if margin is None:
        return best, None, "clear"   # the only pressure that recovered
    return best, margin, "clear" if margin >= CRITERION_SPREAD_S[criterion] else "no clear optimum"


#: Columns of :attr:`Recommendation.table` after the criteria's (:func:`_recommendation_columns`).
_RESPONSE_COLUMNS = (
    "recovery.signals.yaw_rate.time_s", "recovery.signals.roll_rate.time_s", "recovery.signals.steer_rate.time_s",
    "n_peaks", "damping_ratio_1_3", "period_s", "peaks.max_abs_roll_absolute_rad", "fell", "status", "error")


def _recommendation_columns():
    """Columns of :attr:`Recommendation.table`: the pressure, whether measured, each declared criterion's, the
    response's."""
    return ("pressure_kpa", "measured", *dict.fromkeys(c.column for c in CRITERIA.values()), *_RESPONSE_COLUMNS)


def recommend_pressures(loads, tyre="T03", pressures=None, fine=False, step_kpa=10.0, base=None,
                        criterion="settling", **sweep_options):
    """:func:`recommend_pressure` for several rear loads in one sweep.

    Returns
    -------
    list of Recommendation
        In the order of ``loads``.

    Raises
    ------
    whipple_kick.studies.sweep_engine.SweepFailed
        Every case failed (then there is nothing to recommend from).
    """
    base = Scenario() if base is None else base
    criterion = criterion_key(criterion)
    loads = [check_range("rear-tyre load fz", f, 0.0, None, "N", low_open=True) for f in loads]
    if not loads:
        raise InputError("give at least one rear load fz (N)")
    grid, measured = pressure_grid(tyre, pressures, fine, step_kpa, base.coefficient_set)
    sweep_options.setdefault("progress", False)
    table = sweep({"fz_n": loads, "pressure_kpa": grid}, base=dataclasses.replace(base, tyre=tyre),
                  **sweep_options)
    check_some_ok(table)   # "none recovered" would be a verdict on a sweep that never ran a case
    out = []
    for fz in loads:
        rows = table[table["fz_n"] == fz].copy()
        rows["measured"] = rows["pressure_kpa"].isin(measured)
        columns = _recommendation_columns()
        for col in columns:
            if col not in rows:   # every case failed: no result columns at all
                rows[col] = np.nan
        rows = rows[list(columns)].sort_values("pressure_kpa").reset_index(drop=True)
        rows["rank"] = np.argsort(_rank(rows, criterion)) + 1
        best, margin, verdict = _verdict(rows, criterion)
        best_measured = _verdict(rows[rows["measured"]].reset_index(drop=True), criterion)[0]
        out.append(Recommendation(fz, tyre, best, best_measured, criterion, margin,
                                  CRITERION_SPREAD_S[criterion], verdict, rows,
                                  failed=int((rows["status"] != "ok").sum())))
    return out


def recommend_pressure(fz_n, tyre="T03", pressures=None, fine=False, step_kpa=10.0, base=None,
                       criterion="settling", **sweep_options):
    """The inflation pressure with the fastest recovery after a kick, and how sure that is.

    Runs ``base`` (default: the thesis' kick on the default bicycle with a
    rider for ``fz_n`` and the LQR rider) at each pressure and ranks the
    cases by the recovery time (:func:`whipple_kick.simulate.analysis.recovery`: yaw,
    roll and steer rates all within 5 % of their first peaks), ties broken by
    the thesis' last-peak time; ``criterion="last_peak"`` ranks by the
    thesis' rule (last yaw-rate peak above 8 % of the largest, Table 8.9)
    instead. A run that fell or failed never ranks ahead of one that did not.
    The margin between the best and the second-best pressure is compared with
    the spread a 1 % change of the tyre coefficients or of the integration
    tolerance produces (:data:`CRITERION_SPREAD_S`): below it the verdict is
    "no clear optimum"; with one pressure there is "nothing to choose".
    docs/sweeps.md compares the result with thesis Table 8.9.

    Parameters
    ----------
    fz_n : float
        Static rear-tyre load [N].
    tyre : str
        Tyre on both wheels (default T03, the kick-plate bicycle's).
    pressures : sequence of float, optional
        Pressures [kPa] to try (default: the tyre's measured ones, T03:
        300, 400, 500). Both tyres get the same pressure, as in the experiment.
    fine : bool
        Add a grid every ``step_kpa`` between the smallest and largest
        measured pressure (tyres interpolated between the measured ones).
    step_kpa : float
        Step of the fine grid [kPa].
    base : Scenario, optional
        Everything else about the run (``fz_n``, ``tyre`` and the pressure
        are set here).
    criterion : {"settling", "last_peak"}
        What "fastest recovery" means (:data:`CRITERIA`; "last-peak" is accepted).
    **sweep_options
        Passed to :func:`sweep` (``folder``, ``extend``, ``executor``,
        ``workers``, ``progress``, ...).

    Returns
    -------
    Recommendation

    Example
    -------
    Skipped as a doctest: three 6 s kick runs in a process pool, several seconds.

    >>> from whipple_kick import recommend
    >>> rec = recommend.recommend_pressure(635)              # doctest: +SKIP
    >>> rec.best_pressure_kpa, rec.margin_s, rec.verdict     # doctest: +SKIP
    """
    return recommend_pressures([fz_n], tyre, pressures, fine, step_kpa, base, criterion,
                               **sweep_options)[0]


def _num(value):
    """A table cell as a float (NaN for None, NaN or text)."""
    try:
        return float(value)
    except (TypeError, ValueError):
        return math.nan


def format_recommendation(rec):
    """Plain-text table and recommendation of one :class:`Recommendation`."""
    def cell(value, fmt, scale=1.0):
        v = _num(value) * scale
        return fmt.format(v) if math.isfinite(v) else "-"

    column = CRITERIA[rec.criterion].column
    lines = [f"rear load {rec.fz_n:g} N, tyre {rec.tyre}: recovery after the kick, "
             f"ranked by the {CRITERIA[rec.criterion].text}",
             f"{'p [kPa]':>8} {'meas.':>5} {'recovery [s]':>12} {'yaw/roll/steer settle [s]':>25} "
             f"{'last peak [s]':>13} {'zeta 1-3':>8} {'max roll [deg]':>14} {'rank':>4}  note"]
    for _, r in rec.table.iterrows():
        if r["status"] != "ok":
            note = f"failed: {r['error']}"
        elif r["fell"] is True or _num(r["fell"]) == 1.0:
            note = "fell"
        elif not math.isfinite(_num(r[column])):
            note = "not recovered"
        else:
            note = "best" if r["pressure_kpa"] == rec.best_pressure_kpa else ""
        settle = "/".join(cell(r[f"recovery.signals.{name}.time_s"], "{:.2f}")
                          for name in ("yaw_rate", "roll_rate", "steer_rate"))
        lines.append(
            f"{r['pressure_kpa']:8g} {'yes' if r['measured'] else '':>5} "
            f"{cell(r['recovery.time_s'], '{:.3f}'):>12} {settle:>25} "
            f"{cell(r['last_peak_time_s'], '{:.3f}'):>13} {cell(r['damping_ratio_1_3'], '{:.4f}'):>8} "
            f"{cell(r['peaks.max_abs_roll_absolute_rad'], '{:.2f}', 180.0 / math.pi):>14} {int(r['rank']):4d}  {note}")
    head = f"recommendation for {rec.fz_n:g} N: "
    if rec.verdict == "nothing to choose":
        only = float(rec.table["pressure_kpa"].iloc[0])
        lines.append(head + f"nothing to choose: only {only:g} kPa was run"
                     + (f" ({rec.tyre} was measured at one pressure)" if rec.table["measured"].all() else ""))
    elif rec.verdict == "none recovered":
        lines.append(head + "none (no pressure recovered within the run)")
    elif rec.verdict == "incomplete":
        failed = ", ".join(f"{p:g}" for p in rec.table.loc[rec.table["status"] != "ok", "pressure_kpa"])
        text = (f"none: {rec.failed} of {len(rec.table)} cases failed ({failed} kPa; no result, so any of them may "
                "be the best)")
        if rec.best_pressure_kpa is not None:
            best = rec.table[rec.table["pressure_kpa"] == rec.best_pressure_kpa].iloc[0]
            text += f"; the best of the others is {rec.best_pressure_kpa:g} kPa ({_num(best[column]):.3f} s)"
        lines.append(head + text + "; see the failed cases' errors above")
    else:
        best = rec.table[rec.table["pressure_kpa"] == rec.best_pressure_kpa].iloc[0]
        text = f"{rec.best_pressure_kpa:g} kPa ({_num(best[column]):.3f} s)"
        if rec.margin_s is None:
            text += "; the only pressure that recovered"
        else:
            text += (f", {rec.margin_s:.3f} s ahead of the second best; "
                     f"spread from a 1 % change of the tyre coefficients or of rtol: {rec.spread_s:.3f} s")
            if rec.verdict == "no clear optimum":
                text = f"no clear optimum: {text} (margin below the spread)"
        if rec.best_measured_kpa is not None and rec.best_measured_kpa != rec.best_pressure_kpa:
            text += f"; best measured pressure {rec.best_measured_kpa:g} kPa"
        lines.append(head + text)
    return "\n".join(lines)


# --------------------------------------------------------------- what the answer depends on

def dependence(best_by_variant, what):
    """Say whether the best pressure changes between variants of one choice.

    Parameters
    ----------
    best_by_variant : dict
        ``{variant label: best pressure [kPa] or None}``, e.g.
        ``{"kicks to the right": 500.0, "kicks to the left": 300.0}``.
    what : str
        The choice the variants differ in ("direction", "tyre transient").

    Returns
    -------
    str
        E.g. ``"500 kPa for kicks to the right, 300 kPa for kicks to the left: the answer depends on
        the direction"``, or ``"500 kPa whatever the direction"``.

    Example
    -------
    >>> dependence({"kicks to the right": 500.0, "kicks to the left": 500.0}, "direction")
    '500 kPa whatever the direction'
    """
    if not best_by_variant:
        raise InputError(f"no variants of the {what} to compare")
    known = {label: p for label, p in best_by_variant.items() if p is not None}
    if not known:
        return f"no pressure recovered in any {what}"
    parts = ", ".join(f"{p:g} kPa for {label}" if p is not None else f"none for {label}"
                      for label, p in best_by_variant.items())
    if len(set(known.values())) == 1 and len(known) == len(best_by_variant):
        return f"{next(iter(known.values())):g} kPa whatever the {what}"
    return f"{parts}: the answer depends on the {what}"


def recommend_variants(loads, variants, **options):
    """:func:`recommend_pressures` for each variant of the run, and whether the best pressure depends on it.

    Parameters
    ----------
    loads : sequence of float
        Rear loads [N].
    variants : dict
        ``{(kick direction, tyre transient): base Scenario}``.
    **options
        Passed to :func:`recommend_pressures` (``tyre``, ``pressures``, ``criterion``, sweep options).

    Returns
    -------
    recs : dict
        ``{variant: [Recommendation per load]}``.
    verdicts : list of str
        Per load: how the best pressure changes with the direction (at each
        tyre transient) and with the tyre transient (at each direction),
        by :func:`dependence`; a best pressure within the model's spread is
        marked "(no clear optimum)"; empty with one variant.
    """
    recs = {key: recommend_pressures(loads, base=base, **options) for key, base in variants.items()}
    directions = list(dict.fromkeys(d for d, _ in variants))
    forms = list(dict.fromkeys(f for _, f in variants))

    def verdict(recs_by_label, what):
        # A best pressure whose margin is below the model's spread is named, so a "dependence" between
        # two such answers is not read as more than it is.
        text = dependence({label: rec.best_pressure_kpa for label, rec in recs_by_label.items()}, what)
        unsure = [label for label, rec in recs_by_label.items() if rec.verdict == "no clear optimum"]
        failed = [f"{label} ({rec.failed} failed)" for label, rec in recs_by_label.items() if rec.failed]
        return (text + (f" (no clear optimum for {', '.join(unsure)})" if unsure else "")
                + (f" (incomplete: cases failed for {', '.join(failed)})" if failed else ""))

    verdicts = []
    for k, rec in enumerate(recs[next(iter(recs))]):
        if len(directions) > 1:
            for form in forms:
                by = {f"kicks to the {d}": recs[d, form][k] for d in directions}
                verdicts.append(f"{rec.fz_n:g} N, {form} transient: {verdict(by, 'direction')}")
        if len(forms) > 1:
            for d in directions:
                by = {f"the {form} form": recs[d, form][k] for form in forms}
                verdicts.append(f"{rec.fz_n:g} N, kicks to the {d}: {verdict(by, 'tyre transient')}")
    return recs, verdicts
