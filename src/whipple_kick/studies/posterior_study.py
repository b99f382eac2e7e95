"""The answer under the calibration's posterior: which pressure recovers fastest, per rear load.

The uncertainty study (:mod:`whipple_kick.studies.uncertainty`) asks it under
the priors; this asks it under what the measurements leave
(:mod:`whipple_kick.studies.calibration`):

* **Rows**: ``M`` rows drawn without replacement (seeded) from a calibration's
  ``posterior.csv``; each sets the calibrated fields (``settings.json`` names
  them).
* **The inputs not calibrated** (speed, the rear-load share; the hip stiffness
  when it was not calibrated) are **sampled** per row from the uncertainty
  file (each row its own draw, the same draw at every pressure and load), and
  the file's ``[fixed]`` fields set the run (smooth 150 mm kick, 6 s). The
  posterior was conditioned at the calibration's fixed speed (2 m/s) and
  load share; these inputs barely move the oscillation features, and
  sampling them keeps their spread in the answer rather than pinning it at
  one value.
* **The modelling choices** (rider model: ``rider_body`` and ``lqr_model``;
  kick direction; friction; tyre transient) are the calibration's own
  (``settings.json``), never sampled: a posterior is conditional on them, so
  the answer is reported per option (one calibration per option), never
  pooled under invented odds.
* **Pairing** (common random numbers): each row is run at every pressure and
  every load; a difference between pressures is never a difference of inputs.
* **P(best)** per pressure per load and criterion (the recovery time and the
  thesis' last-peak time, :data:`whipple_kick.simulate.criteria.CRITERIA`)
  with the uncertainty study's rules: a run that fell or did not recover ranks
  after every run that recovered, a row where none recovered is the ``none``
  share, ties split the credit, a row with a failed run at a load is left out
  of that load (counted in ``rows_failed``); the 95 % Wilson interval of
  :func:`whipple_kick.studies.uncertainty.p_best_interval` (the rows here are
  independent posterior draws, for which it is made).

The runs go through the sweep engine (:func:`whipple_kick.studies.sweep_engine.sweep`):
in parallel on its pool or any executor (Dask's), with its progress bar, and
kept in ``<calibration folder>/posterior_runs``, so a run stopped half-way
resumes.

Example
-------
Skipped as a doctest: M x 9 kick runs of 6 s (``tests/studies/test_posterior_study.py`` runs a small one).

>>> from whipple_kick.studies import posterior_study
>>> study = posterior_study.run("calibration_out", samples=32)     # doctest: +SKIP
>>> print(posterior_study.format_study(study))                    # doctest: +SKIP
"""
import dataclasses
import json
import math
import pathlib

import numpy as np
import pandas as pd

from whipple_kick import fileio
from whipple_kick.errors import InputError, check_range
from whipple_kick.library import experiments, thesis, uncertain
from whipple_kick.simulate import criteria
from whipple_kick.simulate.scenario import Scenario

from . import calibration
from .recommend import _num, pressure_grid
from .sweep_engine import check_some_ok, make_cases, sweep
from .uncertainty import _best_share, p_best_interval

#: The sweep folder the runs are kept in, inside the calibration's folder.
RUNS = "posterior_runs"
#: The p_best table's columns (the uncertainty study's format).
P_BEST_COLUMNS = ["fz_n", "criterion", "pressure_kpa", "p", "low", "high", "rows", "rows_failed", "measured_best"]
#: What the study writes into the calibration's folder.
FILES = ("p_best.csv", "posterior_rows.csv", "posterior_outcomes.csv", "answer.txt")
#: Beside a prior study's P(best) (``--prior-study DIR``).
BESIDE_PRIOR = "p_best_beside_prior.csv"


@dataclasses.dataclass
class PosteriorStudy:
    """Result of :func:`run`.

    Attributes
    ----------
    settings : dict
        The calibration's ``settings.json`` (its fields and modelling choices).
    rows : pandas.DataFrame
        One row per drawn posterior row: ``row``, ``posterior_index`` (its line in posterior.csv), the
        calibrated fields, the sampled ones.
    outcomes : pandas.DataFrame
        One row per (row, load, pressure): ``row``, ``fz_n``, ``pressure_kpa``, ``case_id``, ``status``,
        ``error``, ``fell`` and both criteria's columns.
    p_best : pandas.DataFrame
        :data:`P_BEST_COLUMNS` (``pressure_kpa`` NaN: the ``none`` share).
    beside_prior : pandas.DataFrame or None
        ``p_best`` with a prior study's ``p``, ``low``, ``high``, ``rows`` beside it (suffix ``_prior``).
    verdict, notes : list of str
    """

    settings: dict
    rows: object
    outcomes: object
    p_best: object
    beside_prior: object
    verdict: list
    notes: list
    samples: int = 0
    seed: int = 0

    def write(self, folder):
        """``p_best.csv``, ``posterior_rows.csv``, ``posterior_outcomes.csv``, ``answer.txt`` (and
        :data:`BESIDE_PRIOR`) into ``folder``; the paths."""
        folder = pathlib.Path(folder)
        tables = [("p_best", self.p_best), ("posterior_rows", self.rows), ("posterior_outcomes", self.outcomes)]
        if self.beside_prior is not None:
            tables.append((BESIDE_PRIOR[:-4], self.beside_prior))
        paths = []
        for name, frame in tables:
            path = folder / f"{name}.csv"
            fileio.write_atomic(path, frame.to_csv(index=False))
            paths.append(path)
        path = folder / "answer.txt"
        head = [f"P(best) under the posterior: {self.samples} rows (seed {self.seed}), "
                + ", ".join(f"{k} {v}" for k, v in self.settings["choices"].items())]
        fileio.write_atomic(path, "\n".join(head + self.verdict + [""] + self.notes) + "\n")
        return paths + [path]


def read_calibration(folder):
    """A calibration's ``posterior.csv`` and ``settings.json`` from its folder: ``(posterior, settings)``.

    Raises
    ------
    InputError
        One line: no folder, no or an empty posterior (nothing plausible: no answer under it), no settings,
        a posterior column that the settings do not name.
    """
    folder = pathlib.Path(folder)
    if not folder.is_dir():
        raise InputError(f"--posterior {folder}: no such folder (give the --out folder of calibrate)")
    post, setf = folder / "posterior.csv", folder / calibration.SETTINGS_FILE
    for path in (post, setf):
        if not path.is_file():
            raise InputError(f"--posterior {folder}: no {path.name} in it: not a calibrate --out folder")
    try:
        settings = json.loads(setf.read_text())
    except ValueError:
        settings = None
    if (not isinstance(settings, dict) or settings.get("format") != calibration.SETTINGS_FORMAT
            or not isinstance(settings.get("fields"), dict) or not isinstance(settings.get("choices"), dict)):
        raise InputError(f"--posterior {folder}: {setf.name} is not calibrate's (format "
                         f"{calibration.SETTINGS_FORMAT!r})")
    fields, choices = settings["fields"], settings["choices"]
    try:
        posterior = pd.read_csv(post)
    except (ValueError, pd.errors.EmptyDataError):
        raise InputError(f"--posterior {folder}: posterior.csv is not a table") from None
    if posterior.empty:
        raise InputError(f"--posterior {folder}: posterior.csv has no rows (no input matched the measurements: "
                         "there is no answer under this posterior)")
    missing = [n for n in fields if n not in posterior]
    if missing or not np.isfinite(posterior[list(fields)].to_numpy(float)).all():
        raise InputError(f"--posterior {folder}: posterior.csv lacks column(s) {', '.join(missing)} or holds a "
                         "non-number")
    return posterior, {"fields": fields, "choices": choices, **settings}


def draw_rows(posterior, fields, samples, seed, spec, base):
    """``samples`` posterior rows (without replacement, seeded) with the uncertainty file's inputs that are not
    calibrated sampled per row: a DataFrame of scenario values per row (and ``posterior_index``)."""
    rng = np.random.default_rng(seed)
    if samples > len(posterior):
        raise InputError(f"--samples = {samples} is more than the posterior's {len(posterior)} rows")
    pick = rng.choice(len(posterior), samples, replace=False)
    rows = pd.DataFrame({f: posterior[n].to_numpy(float)[pick] for n, f in fields.items()})
    calibrated = set(fields.values())
    for inp in spec.inputs:
        if inp.distribution == "choice" or inp.field is None or inp.field in calibrated:
            continue
        if inp.field.startswith(uncertain.BICYCLE_PREFIX):
            raise InputError(f"{spec.path}: inputs.{inp.name}: a measured bicycle's parameters are not sampled "
                             "under a posterior (its runs keep the calibration's bicycle)")
        rows[inp.field] = inp.ppf(rng.random(samples))
    rows.insert(0, "posterior_index", pick)
    rows.insert(0, "row", np.arange(samples))
    return rows


def study_base(settings, spec, tyre=None):
    """The scenario every run changes: the uncertainty file's ``[fixed]`` fields and the calibration's
    modelling choices (which win: the posterior is conditional on them)."""
    base = Scenario(**({} if tyre is None else {"tyre": tyre}))
    return base.with_changes(**{**spec.fixed, **settings["choices"]})


def cases(rows, loads, pressures, base):
    """The sweep's overrides: every row at every load and pressure (the same row values at each), and the
    (row, load, pressure) of each."""
    out, keys = [], []
    for fz in loads:
        for _, r in rows.iterrows():
            values = {k: float(v) for k, v in r.items() if k not in ("row", "posterior_index")}
            for field in base.with_changes(**values).unused_fields():   # e.g. the hip stiffness of a rigid rider
                values.pop(field, None)
            for p in pressures:
                out.append({**values, "fz_n": float(fz), "pressure_kpa": float(p)})
                keys.append((int(r["row"]), float(fz), float(p)))
    return out, keys


def p_best_table(outcomes, loads, pressures, measured_best=None):
    """P(best) per load, criterion and pressure (and ``none``) from ``outcomes`` (module docstring's rules).

    Parameters
    ----------
    outcomes : pandas.DataFrame
        ``row, fz_n, pressure_kpa, status, fell`` and each criterion's column, one line per run.
    loads, pressures : sequences of float
    measured_best : dict, optional
        ``{load: best pressure}`` (default: thesis Table 8.9).

    Returns
    -------
    (pandas.DataFrame of :data:`P_BEST_COLUMNS`, list of notes)
    """
    if measured_best is None:
        measured_best = {fz: b["best_pressure"] for fz, b in experiments.load().best.items()}
    out, notes = [], []
    for fz in loads:
        at = outcomes[outcomes["fz_n"] == fz].sort_values(["row", "pressure_kpa"])
        at = at.set_index(["row", "pressure_kpa"]).reindex(
            pd.MultiIndex.from_product([sorted(set(at["row"])), list(pressures)]))
        n = len(at) // len(pressures)
        shape = (n, len(pressures))
        failed = (at["status"].to_numpy() != "ok").reshape(shape)
        fell = at["fell"].map(lambda v: v is True or _num(v) == 1.0).to_numpy(bool).reshape(shape) & ~failed
        row_failed = failed.any(axis=1)
        if row_failed.any():
            notes.append(f"{fz:g} N: {int(row_failed.sum())} of {n} rows left out (a run failed)")
        best = measured_best.get(fz)
        for key, crit in criteria.CRITERIA.items():
            values = at[crit.column].map(_num).to_numpy(float).reshape(shape)
            times = np.where(np.isfinite(values) & ~fell & ~failed, values, np.inf)
            lost = int(np.count_nonzero(~np.isfinite(times) & ~failed))
            if lost:
                notes.append(f"{fz:g} N, {key}: {lost} of {times.size} runs without a value ({int(fell.sum())} "
                             "fell, the rest did not recover or gave no peak): ranked after every run with one")
            p, low, high = p_best_interval(_best_share(times[~row_failed]))
            for k, pk in enumerate([*pressures, math.nan]):
                out.append({"fz_n": float(fz), "criterion": key, "pressure_kpa": pk, "p": float(p[k]),
                            "low": float(low[k]), "high": float(high[k]), "rows": int((~row_failed).sum()),
                            "rows_failed": int(row_failed.sum()), "measured_best": bool(best == pk)})
    return pd.DataFrame(out, columns=P_BEST_COLUMNS), notes


def beside_prior(p_best, folder):
    """``p_best`` with a prior study's (``recommend-pressure --uncertain --out DIR``: its ``p_best.csv``)
    ``p``, ``low``, ``high``, ``rows`` beside it, suffixed ``_prior`` (NaN where the prior study lacks the
    load or pressure)."""
    path = pathlib.Path(folder) / "p_best.csv"
    if not path.is_file():
        raise InputError(f"--prior-study {folder}: no p_best.csv in it (give the --out folder of "
                         "recommend-pressure --uncertain)")
    prior = pd.read_csv(path)
    need = {"fz_n", "criterion", "pressure_kpa", "p", "low", "high", "rows"}
    if not need <= set(prior):
        raise InputError(f"--prior-study {folder}: p_best.csv lacks {', '.join(sorted(need - set(prior)))}")
    prior = prior[["fz_n", "criterion", "pressure_kpa", "p", "low", "high", "rows"]]
    # merge matches NaN with NaN: the "none" shares meet
    return p_best.merge(prior, on=["fz_n", "criterion", "pressure_kpa"], how="left", suffixes=("", "_prior"))


def run(folder, samples=32, seed=0, loads=thesis.LOADS_N, pressures=thesis.PRESSURES_KPA,
        spec=uncertain.DEFAULT, prior_study=None, tyre=None, runs=None, **sweep_options):
    """P(best) under a calibration's posterior (module docstring).

    Parameters
    ----------
    folder : path
        A ``calibrate --out`` folder (posterior.csv, settings.json).
    samples : int
        Posterior rows ``M``, each run at every pressure and load.
    seed : int
        Seeds the draw of rows and of the inputs not calibrated.
    loads, pressures : sequences of float
        Rear loads [N] and pressures [kPa] (default the thesis').
    spec : str, path or UncertainSet
        The uncertainty file: its ``[fixed]`` fields and the inputs not calibrated.
    prior_study : path, optional
        A prior uncertainty study's folder: its P(best) beside (``beside_prior``).
    tyre : str, optional
        The tyre (default the scenario's).
    runs : path, optional
        The sweep folder keeping the runs (rerun to resume; default ``folder``'s :data:`RUNS`).
    **sweep_options
        :func:`whipple_kick.studies.sweep_engine.sweep`'s (``workers``, ``executor``, ``progress``).

    Returns
    -------
    PosteriorStudy
    """
    samples = int(check_range("--samples", samples, 2, 1e5, "posterior rows"))
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise InputError(f"seed = {seed!r} is outside the allowed range: a whole number >= 0")
    posterior, settings = read_calibration(folder)
    spec = spec if isinstance(spec, uncertain.UncertainSet) else uncertain.load(spec)
    loads = list(dict.fromkeys(check_range("rear-tyre load fz", f, 0.0, None, "N", low_open=True) for f in loads))
    base = study_base(settings, spec, tyre)
    # within the tyre's measured range, checked here: inside the sweep a bad pressure would fail every run at it
    pressures, _ = pressure_grid(base.tyre, list(pressures), coefficient_set=base.coefficient_set)
    if len(pressures) < 2 or not loads:
        raise InputError(f"P(best) compares pressures at some load: {len(pressures)} pressure(s), "
                         f"{len(loads)} load(s) given")
    rows = draw_rows(posterior, settings["fields"], samples, seed, spec, base)
    overrides, keys = cases(rows, loads, pressures, base)
    for k in range(0, len(overrides), len(pressures)):   # one per row and load (before any run)
        try:
            base.with_changes(**overrides[k]).validate()
        except InputError as exc:
            raise InputError(f"posterior row {keys[k][0]} at {keys[k][1]:g} N: {exc}") from None
    prior = None if prior_study is None else pathlib.Path(prior_study)
    if prior is not None and not (prior / "p_best.csv").is_file():
        beside_prior(pd.DataFrame(columns=P_BEST_COLUMNS), prior)   # its one-line refusal, before the runs
    ids = [cid for _, _, cid in make_cases(cases=overrides, base=base)]
    sweep_options["folder"] = pathlib.Path(folder) / RUNS if runs is None else pathlib.Path(runs)
    sweep_options.setdefault("progress", False)
    sweep_options.setdefault("extend", True)   # a new posterior's rows join the earlier ones' runs (reused if equal)
    sweep_options.setdefault("trajectory_columns", None)
    table = sweep(cases=overrides, base=base, **sweep_options)
    check_some_ok(table)
    by_id = table.set_index("case_id")
    wanted = ["status", "error", "fell", *(c.column for c in criteria.CRITERIA.values())]
    for col in wanted:
        if col not in by_id:
            by_id[col] = np.nan
    outcomes = pd.concat([pd.DataFrame(keys, columns=["row", "fz_n", "pressure_kpa"]),
                          pd.DataFrame({"case_id": ids}), by_id.loc[ids, wanted].reset_index(drop=True)], axis=1)
    p_best, notes = p_best_table(outcomes, loads, pressures)
    sampled = [c for c in overrides[0] if c not in ("fz_n", "pressure_kpa", *settings["fields"].values())]
    notes.insert(0, f"sampled per row from {spec.path}: {', '.join(sampled) or 'nothing'}; fixed: "
                 + ", ".join(f"{k} {v}" for k, v in spec.fixed.items()))
    study = PosteriorStudy(settings, rows, outcomes, p_best, None if prior is None else beside_prior(p_best, prior),
                           [], notes, samples, int(seed))
    study.verdict = verdict_lines(study)
    return study


def verdict_lines(study):
    """One line per load and criterion: each pressure's P(best) with its interval, the measured best."""
    lines = []
    for (fz, key), part in study.p_best.groupby(["fz_n", "criterion"], sort=False):
        shares = ", ".join(f"{'none' if math.isnan(r['pressure_kpa']) else format(r['pressure_kpa'], 'g') + ' kPa'}"
                           f" {r['p']:.2f} ({r['low']:.2f}-{r['high']:.2f})" for _, r in part.iterrows())
        best = part[part["measured_best"]]["pressure_kpa"]
        lines.append(f"{fz:g} N, {criteria.CRITERIA[key].short}: {shares}"
                     + (f"; measured best {best.iloc[0]:g} kPa" if len(best) else ""))
    return lines


def format_study(study):
    """The answer as the command prints it."""
    c = study.settings["choices"]
    head = (f"P(best) under the posterior ({study.samples} rows, each run at every pressure and load; "
            f"95 % Wilson intervals), conditional on: {', '.join(f'{k} {v}' for k, v in c.items())}")
    out = [head, *("  " + line for line in study.verdict)]
    if study.beside_prior is not None:
        out.append("beside the prior study's P(best) (which samples the modelling choices under its file's odds):")
        for _, r in study.beside_prior[study.beside_prior["pressure_kpa"].notna()].iterrows():
            prior = ("not in the prior study" if not np.isfinite(r["p_prior"])
                     else f"{r['p_prior']:.2f} ({r['low_prior']:.2f}-{r['high_prior']:.2f})")
            out.append(f"  {r['fz_n']:g} N {r['criterion']} {r['pressure_kpa']:g} kPa: posterior {r['p']:.2f}, "
                       f"prior {prior}")
    return "\n".join(out + [*("  note: " + n for n in study.notes)])


def from_folder(folder):
    """A finished study's p_best table and answer from a calibration folder (``p_best.csv``), or None."""
    path = pathlib.Path(folder) / "p_best.csv"
    if not path.is_file():
        return None
    frame = pd.read_csv(path)
    if list(frame.columns) != P_BEST_COLUMNS:
        raise InputError(f"--posterior {folder}: p_best.csv is not this study's (columns {', '.join(P_BEST_COLUMNS)})")
    return frame
