"""How sure is the answer: which pressure recovers fastest, with its probability, and what it hinges on.

The uncertainty study runs the kick at every pressure for every
rear load on inputs sampled from an uncertainty file
(:mod:`whipple_kick.library.uncertain`), and reports:

* **P(best)** per pressure per load, for both criteria (the recovery time
  ``recovery.time_s`` and the thesis' last-peak time ``last_peak_time_s``),
  with a 95 % Wilson score interval (:func:`p_best_interval` says why);
* the recovery-time distribution per pressure, the **paired differences**
  between pressures, and the fall, not-recovered and failure rates;
* **Sobol indices** (first order and total, with SALib's 95 % intervals) of the
  paired recovery-time difference between each two pressures: what the
  answer hinges on;
* the measured best pressures (thesis Table 8.9) beside P(best), and whether
  the model's uncertainty admits the measured ranking.

Sampling and pairing. SALib's Saltelli-Sobol' design (``SALib.sample.sobol``,
first order and total, so ``N (D + 2)`` rows for ``N`` base samples and
``D`` inputs) on the unit cube, mapped through each input's inverse CDF.
**Each row is one set of inputs run at every pressure and every load**
(common random numbers): a difference between pressures is never a
difference of inputs. P(best), the distributions and the differences use the
``2N`` rows of the design's two base matrices (A and B: each a sample of the
inputs); the Sobol analysis uses every row, as it must.

Falls and failures (never dropped silently):

* a run that **fell**, or that **did not recover** by the run's end
  (criterion value missing), ranks after every run that recovered; in a row
  where no pressure recovered nothing is best (the ``none`` share of P(best));
  ties split the credit;
* a run that **failed** numerically is counted; a row with a failure at a
  load is left out of that load's P(best) and differences, and the count is
  printed;
* for the Sobol analysis (which needs every row) a run that fell, did not
  recover or failed counts as taking the whole run (its time is censored at
  the run's duration); the counts are printed beside the indices.

Example
-------
Skipped as a doctest: hundreds of kick runs (``tests/studies/test_uncertainty.py``
runs a small one; ``scripts/uncertainty_study.py`` the measured one).

>>> from whipple_kick import uncertainty
>>> study = uncertainty.run_study(samples=16, seed=0)     # doctest: +SKIP
>>> print("\\n".join(study.verdict))                      # doctest: +SKIP
"""
import dataclasses
import itertools
import math

import numpy as np

from whipple_kick.errors import InputError, check_range
from whipple_kick.library import thesis, uncertain
from whipple_kick.simulate import criteria
from whipple_kick.simulate.scenario import DEFAULTS, MECHANISM_FIELDS, UNITS, Scenario

from .recommend import _num, pressure_grid
from .sweep_engine import check_some_ok, make_cases, sweep

#: Thesis Chapter 8's pressures [kPa] and rear loads [N] (:mod:`whipple_kick.library.thesis`).
PRESSURES = thesis.PRESSURES_KPA
LOADS = thesis.LOADS_N
#: The recovery criteria (:data:`whipple_kick.simulate.criteria.CRITERIA`): ``CRITERIA[key].column`` is the
#: table column of each.
CRITERIA = criteria.CRITERIA
#: Bootstrap resamples of the paired differences' intervals.
BOOTSTRAP = 2000
#: Confidence level of every interval.
CONFIDENCE = 0.95
#: A measured best pressure is "admitted" by the model's uncertainty when the upper end of the
#: interval of its probability is at least this (one chance in twenty).
ADMIT_PROBABILITY = 0.05
#: Combinations of the choices' options :func:`check_inputs` looks at (beyond, a mechanism reached only
#: by a later combination would be refused).
_MAX_COMBINATIONS = 4096
#: Scenario fields a study sets itself: an uncertain input may not set them.
_STUDY_FIELDS = ("fz_n", "pressure_kpa", "pressure_front_kpa", "pressure_rear_kpa", "rider_mass_kg")
@dataclasses.dataclass
class UncertaintyStudy:
    """Result of :func:`run_study`.

    Attributes
    ----------
    spec : whipple_kick.library.uncertain.UncertainSet
    samples, seed : int
        SALib's base sample count ``N`` and the seed.
    inputs : pandas.DataFrame
        One row per sample row: ``sample``, ``block`` (``A``, ``B`` or ``AB<i>``), each input's value
        (a choice's label).
    outcomes : pandas.DataFrame
        One row per (sample row, load, pressure): ``sample``, ``fz_n``, ``pressure_kpa``, ``block``,
        ``case_id`` (the sweep's: a design row that repeats another, e.g. a choice column swapped for
        the same option, is one case, run once), ``status``, ``error``, ``fell``, both criteria's
        columns, ``fell``, ``status``, ``error``, ``run.wall_s``, ``run.cpu_s`` (the run in its worker) and
        ``numerics.integration_wall_s`` (its integration).
    p_best : pandas.DataFrame
        ``fz_n``, ``criterion``, ``pressure_kpa`` (NaN: the ``none`` share), ``p``, ``low``, ``high``,
        ``rows`` (rows used), ``rows_failed`` (left out), ``measured_best``.
    distributions, differences, rates, sobol, measured : pandas.DataFrame
        See :func:`run_study`.
    verdict : list of str
        One line per load: how sure, and what it hinges on.
    notes : list of str
        Counts of what was censored or left out, constant outputs.
    """

    spec: object
    samples: int
    seed: int
    inputs: object
    outcomes: object
    p_best: object
    distributions: object
    differences: object
    rates: object
    sobol: object
    measured: object
    verdict: list
    notes: list

    def write(self, folder):
        """Write every table as CSV into ``folder``; returns the paths."""
        import pathlib

        from whipple_kick import fileio
        folder = pathlib.Path(folder)
        folder.mkdir(parents=True, exist_ok=True)
        paths = []
        for name in ("inputs", "outcomes", "p_best", "distributions", "differences", "rates", "sobol",
                     "measured"):
            path = folder / f"{name}.csv"
            fileio.write_atomic(path, getattr(self, name).to_csv(index=False))
            paths.append(path)
        path = folder / "verdict.txt"
        fileio.write_atomic(path, "\n".join(self.verdict + [""] + self.notes) + "\n")
        return paths + [path]


def check_inputs(spec, base):
    """Refuse, before any run, what the file gets wrong, in one line naming the file's key.

    An input or ``[fixed]`` entry that names no scenario field (with the fields' names) or one the study
    sets; an input whose ``unit`` is not its field's (:data:`whipple_kick.simulate.scenario.UNITS`); a
    ``[fixed]`` value, a choice's option or a continuous input's bound (an untruncated normal's farthest
    sample) that the scenario refuses (its message names the value, the allowed range and the unit); an
    input that no sample's mechanism reads (it would be ignored). ``base`` is the scenario the file
    changes, with or without its ``[fixed]`` fields.

    Raises
    ------
    InputError
        One line naming the key and the problem.
    """
    for inp in spec.inputs:
        if inp.field and inp.field.startswith(uncertain.BICYCLE_PREFIX) and spec.measured_bicycle is None:
            raise InputError(f"{spec.path}: inputs.{inp.name}: a measured bicycle's parameters are sampled from a "
                             "[bicycle] table (measured = ..., parameters = [...]), not named as inputs")
    for field in spec.fixed:
        if field not in DEFAULTS:
            raise InputError(f"{spec.path}: fixed.{field}: {field!r} is no scenario field{_close(field)}; the "
                             f"fields: {', '.join(DEFAULTS)}")
        if field in _STUDY_FIELDS:
            raise InputError(f"{spec.path}: fixed.{field}: the study sets {field} itself")
    for inp in _scenario_inputs(spec):
        for field in inp.fields:
            if field not in DEFAULTS:
                raise InputError(f"{spec.path}: inputs.{inp.name}: {field!r} is no scenario field{_close(field)} "
                                 f"(see help(whipple_kick.Scenario))")
            if field in _STUDY_FIELDS:
                raise InputError(f"{spec.path}: inputs.{inp.name}: the study sets {field} itself "
                                 f"(pressures and loads are its grid)")
        if inp.distribution != "choice":
            unit = UNITS.get(inp.field)
            if unit is None:
                raise InputError(f"{spec.path}: inputs.{inp.name}: {inp.field} is not a number: a {inp.distribution} "
                                 f"distribution cannot give it (a choice can: options with a value each)")
            if " ".join(inp.unit.split()) != unit:
                raise InputError(f"{spec.path}: inputs.{inp.name}.unit: {inp.unit!r} is not the unit of {inp.field}, "
                                 f"{unit!r}: give the distribution in {unit}")
    plain = base
    for k, field in enumerate(spec.fixed):   # in file order, each with those before it (a table after its profile)
        _check_changes(f"{spec.path}: fixed.{field}", plain, dict(itertools.islice(spec.fixed.items(), k + 1)))
    base = base.with_changes(**spec.fixed)
    for inp in spec.inputs:
        for k, option in enumerate(inp.options):
            _check_changes(f"{spec.path}: inputs.{inp.name}.options[{k}] ({option.label})", base, option.values)
    candidates = _candidates(spec, base)
    for inp in _scenario_inputs(spec):
        for field in inp.fields:
            if not any(_reads(sc, field) for sc in candidates):
                what = " and ".join(f"{m} ({cond})" for m, cond, _, names in MECHANISM_FIELDS if field in names)
                raise InputError(f"{spec.path}: inputs.{inp.name}: {field} is read only by {what}, which no sample "
                                 "uses: it would be ignored")
    combinations = [base.with_changes(**values) for values in _combinations(spec)]
    for inp in _scenario_inputs(spec):
        if inp.distribution != "choice":
            _check_ends(spec, inp, combinations)


def _reads(scenario, field):
    """Whether every mechanism that reads ``field`` (:data:`~whipple_kick.simulate.scenario.MECHANISM_FIELDS`) is
    in use in ``scenario`` (a field no mechanism owns is always read)."""
    return all(active(scenario) for _, _, active, names in MECHANISM_FIELDS if field in names)


def _close(field):
    """" (did you mean ...?)" for a misspelt scenario field, or ""."""
    import difflib
    close = difflib.get_close_matches(field, DEFAULTS, n=1)
    return f" (did you mean {close[0]!r}?)" if close else ""


def _check_changes(where, base, changes):
    """``base`` with ``changes`` passes the run's checks (the fields the changed mechanisms do not read left at
    ``base``'s, as a sample row leaves them); else InputError ``<where>: <the check's message>``."""
    from whipple_kick.simulate import assembly
    scenario = base.with_changes(**changes)
    unread = {f: getattr(base, f) for f in scenario.unused_fields() if f in changes}
    try:
        assembly.preflight(scenario.with_changes(**unread))
    except InputError as exc:
        raise InputError(f"{where}: {exc}") from None


def _check_ends(spec, inp, combinations):
    """A continuous input's bounds (an untruncated normal's farthest samples) pass the run's checks, with the
    first combination of the choices' options that is valid and reads the input's field."""
    ends = []
    for end, bound, u in (("low", inp.low, uncertain._EDGE), ("high", inp.high, 1.0 - uncertain._EDGE)):
        if bound is not None:
            ends.append((f"inputs.{inp.name}.{end}", float(bound)))
        else:   # an untruncated normal: as far as the sampling goes
            value = float(inp.ppf([u])[0])
            ends.append((f"inputs.{inp.name} (a normal not truncated {'below' if end == 'low' else 'above'}: its "
                         f"samples reach {value:g} {inp.unit}; give '{end}')", value))
    for base in combinations:
        if not _reads(base, inp.field):
            continue
        try:
            _check_changes("", base, {})
        except InputError:
            continue   # a combination the scenario refuses whatever this input: each sample row says so
        for where, value in ends:
            _check_changes(f"{spec.path}: {where}", base, {inp.field: value})
        return


def _combinations(spec):
    """The fields each combination of the choices' options sets (at most :data:`_MAX_COMBINATIONS`)."""
    choices = [i for i in spec.inputs if i.distribution == "choice"]
    for combo in itertools.islice(itertools.product(*(i.options for i in choices)), _MAX_COMBINATIONS):
        values = {}
        for option in combo:
            values.update(option.values)
        yield values


def _candidates(spec, base):
    """One scenario per combination of the choices' options (continuous inputs at their medians): what the
    samples can switch on. At most :data:`_MAX_COMBINATIONS`."""
    medians = {i.field: float(i.ppf([0.5])[0]) for i in _scenario_inputs(spec) if i.distribution != "choice"}
    return [base.with_changes(**{**spec.fixed, **medians, **values}) for values in _combinations(spec)]


def sample(spec, samples, seed):
    """SALib's Saltelli-Sobol' design on the unit cube: ``(unit rows, block labels)``.

    ``N (D + 2)`` rows in SALib's order (per base point: A, AB1 ... ABD, B).
    """
    import warnings

    from SALib.sample import sobol as sobol_sample
    samples = int(check_range("samples", samples, 2, 1e6, "(base samples N)"))
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise InputError(f"seed = {seed!r} is outside the allowed range: a whole number >= 0")
    d = len(spec.inputs)
    with warnings.catch_warnings():
        # SALib warns when N is not a power of 2 (the Sobol' sequence's balance); any N is valid.
        warnings.simplefilter("ignore", UserWarning)
        unit = sobol_sample.sample(spec.problem(), samples, calc_second_order=False, seed=int(seed))
    blocks = ["A", *(f"AB{i + 1}" for i in range(d)), "B"] * samples
    return unit, blocks


def _scenario_inputs(spec):
    """The inputs that set scenario fields (not a measured bicycle's parameters)."""
    return [i for i in spec.inputs if not (i.field or "").startswith(uncertain.BICYCLE_PREFIX)]


def sampled_bicycle(measured, values):
    """The measured bicycle with some parameters changed, written once as a BicycleParameters folder.

    Parameters
    ----------
    measured : str
        The bicycle the ``[bicycle]`` table names (shipped name or BicycleParameters path).
    values : dict
        ``{"bicycle.<name>": value}``: benchmark names, or ``bicycle.seating.<length>``.

    Returns
    -------
    str
        The folder (in the per-user cache, named by a hash of the bicycle's content and the values, so a row
        that repeats another shares it), which a scenario's ``bicycle`` names.
    """
    import hashlib
    import json
    import os
    import pathlib
    import shutil

    from whipple_kick.library import bicycleparameters, bicycles
    from whipple_kick.model import cache

    bike = bicycleparameters.load_bicycle(measured)
    changes = {k[len(uncertain.BICYCLE_PREFIX):]: float(v) for k, v in values.items()}
    benchmark, geometry = dict(bike.benchmark), dict(bike.geometry or {})
    for name, value in changes.items():
        if name.startswith("seating."):
            geometry[name[len("seating."):]] = value
        elif name in benchmark:
            benchmark[name] = value
        else:
            raise InputError(f"bicycle parameter {name!r} of {measured!r} cannot be sampled "
                             "(only benchmark names and seating lengths)")
    key = hashlib.sha256(json.dumps([sorted(bike.benchmark.items()), sorted(geometry.items()),
                                     sorted(changes.items()), bike.includes_rider], sort_keys=True).encode())
    folder = cache.cache_dir() / "sampled_bicycles" / key.hexdigest()[:20]
    target = folder / "bicycles" / "Sampled"
    if not target.is_dir():
        sampled = bicycles.Bicycle(
            name="Sampled", benchmark=benchmark, parameterisation="benchmark", includes_rider=bike.includes_rider,
            source=f"{bike.source}; sampled by the uncertainty study", description=bike.description,
            uncertainties=dict(bike.uncertainties), geometry=geometry or None, defaults=dict(bike.defaults))
        staging = folder.with_name(f"{folder.name}.tmp-{os.getpid()}")
        bicycleparameters.write_folder(sampled, staging, name="Sampled")
        try:
            os.replace(staging, folder)   # atomic: another process sees the whole folder or none
        except OSError:   # another process wrote it first
            shutil.rmtree(staging, ignore_errors=True)
    return str(pathlib.Path(target))


def row_values(spec, unit_row, base):
    """The scenario fields of one sample row, less those the row's own mechanisms do not read.

    A conditional input (the hip stiffness with the leaning body) is sampled in every row, as the
    Sobol design needs, but set only in the rows whose mechanism reads it
    (:meth:`~whipple_kick.simulate.scenario.Scenario.unused_fields`): elsewhere it keeps the base
    value, so no run is given a field it ignores (which the scenario refuses).
    """
    values = spec.values(unit_row)
    sampled = {k: values.pop(k) for k in list(values) if k.startswith(uncertain.BICYCLE_PREFIX)}
    if sampled:
        values["bicycle"] = sampled_bicycle(spec.measured_bicycle, sampled)
    for field in base.with_changes(**values).unused_fields():
        values.pop(field, None)
    return values


def study_cases(spec, unit, loads, pressures, base):
    """The sweep's overrides: every row at every load and pressure, and the (row, load, pressure) of each."""
    cases, keys = [], []
    rows = [row_values(spec, u, base) for u in unit]
    for fz in loads:
        for r, values in enumerate(rows):
            for p in pressures:
                cases.append({**values, "fz_n": float(fz), "pressure_kpa": float(p)})
                keys.append((r, float(fz), float(p)))
    return cases, keys


def run_study(spec=uncertain.DEFAULT, samples=64, seed=0, loads=LOADS, pressures=PRESSURES, base=None,
              **sweep_options):
    """Run the uncertainty study (see the module's docstring) and analyse it.

    Parameters
    ----------
    spec : str, path or UncertainSet
        The uncertainty file (default: the thesis' kick-plate experiment's).
    samples : int
        SALib's base sample count ``N``: ``N (D + 2)`` rows, each run at every
        pressure and load. A power of 2 keeps the Sobol' sequence balanced.
    seed : int
        Seeds the Sobol' scrambling and every bootstrap: the same seed gives the same tables.
    loads, pressures : sequence of float
        Rear loads [N] (separate studies on the same rows) and pressures [kPa].
    base : Scenario, optional
        What the inputs and the file's ``[fixed]`` fields change (default ``Scenario()``).
    **sweep_options
        Passed to :func:`whipple_kick.studies.sweep_engine.sweep` (``folder`` to
        keep and resume the runs, ``executor``, ``workers``, ``progress``).

    Returns
    -------
    UncertaintyStudy
    """
    if not isinstance(spec, uncertain.UncertainSet):
        spec = uncertain.load(spec)
    base = Scenario() if base is None else base
    check_inputs(spec, base)   # before the [fixed] fields are applied: one may name no field
    base = base.with_changes(**spec.fixed)
    loads = list(dict.fromkeys(check_range("rear-tyre load fz", f, 0.0, None, "N", low_open=True) for f in loads))
    if not loads:
        raise InputError("the study needs at least one rear load (N)")
    # Within the tyre's measured range (checked here: inside the sweep a bad pressure would fail every run at it).
    pressures, measured = pressure_grid(base.tyre, list(pressures), coefficient_set=base.coefficient_set)
    if len(pressures) < 2:
        from whipple_kick.library import tyres
        others = [f"{name} ({_kpa(p)})" for name, p, _ in tyres.available() if len(p) > 1]
        raise InputError(f"the study compares pressures: it needs at least two, got {_kpa(pressures)}; tyre "
                         f"{base.tyre} ({base.coefficient_set}) was measured at {_kpa(measured)} only, and a "
                         f"pressure must lie within its measured range: choose a tyre measured at two or more "
                         f"({', '.join(others)})")
    unit, blocks = sample(spec, samples, seed)
    cases, keys = study_cases(spec, unit, loads, pressures, base)
    for k in range(0, len(cases), len(pressures)):   # one per row and load: the pressures do not change validity
        try:
            base.with_changes(**cases[k]).validate()
        except InputError as exc:
            raise InputError(f"{spec.path}: sample row {keys[k][0]} ({spec.labels(unit[keys[k][0]])}): {exc}") \
                from None
    ids = [cid for _, _, cid in make_cases(cases=cases, base=base)]
    sweep_options.setdefault("progress", False)
    sweep_options.setdefault("trajectory_columns", None)   # thousands of runs: the table, not the time histories
    table = sweep(cases=cases, base=base, **sweep_options)
    check_some_ok(table)
    return analyse(spec, samples, seed, unit, blocks, keys, ids, table, base.duration)


def _kpa(pressures):
    """Pressures as a message lists them: "300, 400 kPa"."""
    return ", ".join(f"{p:g}" for p in sorted(pressures)) + " kPa"


def analyse(spec, samples, seed, unit, blocks, keys, ids, table, duration):
    """The study's tables from its sweep ``table`` (rows found by case id: a repeated case runs once)."""
    import pandas as pd

    from whipple_kick.library import experiments
    inputs = pd.DataFrame([{"sample": r, "block": blocks[r], **spec.labels(u)} for r, u in enumerate(unit)])
    by_id = table.set_index("case_id")
    wanted = ["status", "error", "fell", *(c.column for c in CRITERIA.values()), "run.wall_s", "run.cpu_s", "numerics.integration_wall_s"]
    for col in wanted:
        if col not in by_id:
            by_id[col] = np.nan
    rows = by_id.loc[ids, wanted].reset_index(drop=True)
    outcomes = pd.concat([pd.DataFrame(keys, columns=["sample", "fz_n", "pressure_kpa"]),
                          pd.DataFrame({"block": [blocks[r] for r, _, _ in keys], "case_id": ids}), rows], axis=1)
    outcomes["fell"] = outcomes["fell"].map(lambda v: v is True or _num(v) == 1.0)
    loads = list(dict.fromkeys(k[1] for k in keys))
    pressures = list(dict.fromkeys(k[2] for k in keys))
    n_rows = len(unit)
    base_rows = np.array([b in ("A", "B") for b in blocks])
    measured = experiments.load().best
    rng_seed = int(seed)
    p_best, dists, diffs, rates, sobol, meas, notes = [], [], [], [], [], [], []
    a_rows = np.array([b == "A" for b in blocks])
    b_rows = np.array([b == "B" for b in blocks])
    for k, inp in enumerate(spec.inputs):
        # A choice whose option is the same in A and B of every base point is never varied by the design
        # (at a small N the Sobol' sequence can do that: the shipped file's friction column at N = 8).
        if np.array_equal(inp.ppf(unit[a_rows, k]), inp.ppf(unit[b_rows, k])):
            notes.append(f"{inp.name}: the design never varies it at N = {samples} (the same value in A and B of "
                         "every base point): its Sobol indices are 0 by construction, not a finding; use a larger N")
    winners = {}
    for fz in loads:
        at = outcomes[outcomes["fz_n"] == fz]
        failed = at["status"].to_numpy() != "ok"
        fell = at["fell"].to_numpy(dtype=bool) & ~failed
        shape = (n_rows, len(pressures))
        failed_m, fell_m = failed.reshape(shape), fell.reshape(shape)
        row_failed = failed_m.any(axis=1)
        for p_k, p in enumerate(pressures):
            rates.append({"fz_n": fz, "pressure_kpa": p, "runs": n_rows, "failed": int(failed_m[:, p_k].sum()),
                          "fell": int(fell_m[:, p_k].sum()),
                          **{f"not_recovered_{c}": int((~failed_m[:, p_k] & ~fell_m[:, p_k] & ~np.isfinite(
                              at[col].map(_num).to_numpy(dtype=float).reshape(shape)[:, p_k])).sum())
                             for c, col in ((key, c.column) for key, c in CRITERIA.items())}})
        best_p = measured.get(fz, {}).get("best_pressure")
        for criterion, col in ((key, c.column) for key, c in CRITERIA.items()):
            values = at[col].map(_num).to_numpy(dtype=float).reshape(shape)
            times = np.where(np.isfinite(values) & ~fell_m & ~failed_m, values, np.inf)
            use = base_rows & ~row_failed
            if row_failed[base_rows].any():
                notes.append(f"{fz:g} N, {criterion}: {int(row_failed[base_rows].sum())} of {int(base_rows.sum())} "
                             "rows left out of P(best) and the differences (a run failed)")
            share = _best_share(times[use])
            winners[fz, criterion] = (np.flatnonzero(use), share)
            rng = np.random.default_rng(rng_seed)
            mean, low, high = p_best_interval(share)
            for k, p in enumerate([*pressures, math.nan]):
                p_best.append({"fz_n": fz, "criterion": criterion, "pressure_kpa": p,
                               "p": float(mean[k]), "low": float(low[k]), "high": float(high[k]),
                               "rows": int(use.sum()),
                               "rows_failed": int((base_rows & row_failed).sum()),
                               "measured_best": bool(best_p == p)})
            for k, p in enumerate(pressures):
                ok = times[use][:, k]
                ok = ok[np.isfinite(ok)]
                q = np.quantile(ok, [0.05, 0.25, 0.5, 0.75, 0.95]) if ok.size else [math.nan] * 5
                dists.append({"fz_n": fz, "criterion": criterion, "pressure_kpa": p, "recovered": int(ok.size),
                              "rows": int(use.sum()), "mean_s": float(ok.mean()) if ok.size else math.nan,
                              **{f"q{int(100 * level):02d}_s": float(v)
                                 for level, v in zip((0.05, 0.25, 0.5, 0.75, 0.95), q, strict=True)}})
            for (i, pi), (j, pj) in itertools.combinations(enumerate(pressures), 2):
                a, b = times[use][:, i], times[use][:, j]
                both = np.isfinite(a) & np.isfinite(b)
                d = b[both] - a[both]
                faster = (a < b).astype(float) + 0.5 * (a == b)   # P(pi recovers before pj); neither: half
                lo, hi = _bootstrap_means(d[:, None], rng) if d.size else ([math.nan], [math.nan])
                flo, fhi = _bootstrap_means(faster[:, None], rng) if faster.size else ([math.nan], [math.nan])
                diffs.append({"fz_n": fz, "criterion": criterion, "pressure_a_kpa": pi, "pressure_b_kpa": pj,
                              "pairs_both_recovered": int(d.size),
                              "mean_b_minus_a_s": float(d.mean()) if d.size else math.nan,
                              "low_s": lo[0], "high_s": hi[0],
                              "median_b_minus_a_s": float(np.median(d)) if d.size else math.nan,
                              "p_a_faster": float(faster.mean()) if faster.size else math.nan,
                              "p_a_faster_low": flo[0], "p_a_faster_high": fhi[0]})
            censored = np.where(np.isfinite(times), times, duration)
            n_cens = int((~np.isfinite(times)).sum())
            if n_cens:
                notes.append(f"{fz:g} N, {criterion}: {n_cens} of {times.size} runs censored at {duration:g} s "
                             f"for the Sobol analysis ({int(fell_m.sum())} fell, {int(failed_m.sum())} failed, "
                             "the rest not recovered)")
            for (i, pi), (j, pj) in itertools.combinations(enumerate(pressures), 2):
                y = censored[:, j] - censored[:, i]
                if np.ptp(y) == 0.0:
                    notes.append(f"{fz:g} N, {criterion}: the {pj:g}-{pi:g} kPa difference is the same in every "
                                 "row: no Sobol indices")
                    continue
                for name, s1, s1c, st, stc in _sobol(spec, y, rng_seed):
                    sobol.append({"fz_n": fz, "criterion": criterion, "pressure_a_kpa": pi, "pressure_b_kpa": pj,
                                  "input": name, "S1": s1, "S1_conf": s1c, "ST": st, "ST_conf": stc})
    p_best = pd.DataFrame(p_best)
    sobol = pd.DataFrame(sobol, columns=["fz_n", "criterion", "pressure_a_kpa", "pressure_b_kpa", "input", "S1",
                                         "S1_conf", "ST", "ST_conf"])
    for criterion in CRITERIA:
        meas.extend(_against_measurement(winners, criterion, loads, pressures, measured, p_best, rng_seed))
    study = UncertaintyStudy(spec, samples, seed, inputs, outcomes, p_best, pd.DataFrame(dists), pd.DataFrame(diffs),
                             pd.DataFrame(rates), sobol,
                             pd.DataFrame(meas, columns=["criterion", "fz_n", "measured_best_kpa", "p", "low", "high",
                                                         "admitted"]), [], notes)
    study.verdict = verdict_lines(study)
    return study


def _best_share(times):
    """Per row, each pressure's share of "best" (ties split) and, last column, 1 where none recovered."""
    n, m = times.shape
    out = np.zeros((n, m + 1))
    if not n:
        return out
    low = times.min(axis=1)
    none = ~np.isfinite(low)
    tie = (times == low[:, None]) & ~none[:, None]
    out[:, :m] = tie / np.maximum(tie.sum(axis=1), 1)[:, None]
    out[:, m] = none
    return out


def p_best_interval(share):
    """Mean share per column and its Wilson score interval (:data:`CONFIDENCE`): ``(p, low, high)`` arrays.

    Each pressure's P(best) is a proportion of rows, so the Wilson interval
    fits it (a tie's half credit counts as half a success). It is used rather
    than a bootstrap because at the study's small N a pressure that is never
    (or always) best would get a bootstrap interval of zero width, [0, 0],
    where Wilson's says how large the probability could still be (0.19 for 0
    of 16 rows). The rows are quasi-random (Sobol') points, not independent
    draws; their error is smaller than independent sampling's, so the interval
    is conservative.
    """
    from scipy import stats
    share = np.asarray(share, dtype=float)
    n = share.shape[0]
    p = share.mean(axis=0) if n else np.full(share.shape[1], math.nan)
    z = stats.norm.ppf(0.5 + CONFIDENCE / 2.0)
    if not n:
        return p, p.copy(), p.copy()
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * np.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return p, np.clip(centre - half, 0.0, 1.0), np.clip(centre + half, 0.0, 1.0)


def _bootstrap_means(values, rng):
    """Percentile-bootstrap interval (:data:`CONFIDENCE`) of each column's mean over rows."""
    values = np.asarray(values, dtype=float)
    n = len(values)
    if n == 0:
        return [math.nan] * values.shape[1], [math.nan] * values.shape[1]
    idx = rng.integers(0, n, size=(BOOTSTRAP, n))
    means = values[idx].mean(axis=1)
    tail = 100.0 * (1.0 - CONFIDENCE) / 2.0
    return list(np.percentile(means, tail, axis=0)), list(np.percentile(means, 100.0 - tail, axis=0))


def sobol_indices(spec, y, seed=0):
    """First-order and total Sobol indices of ``y`` (one value per row of :func:`sample`'s design).

    Returns
    -------
    list of (input name, S1, S1 interval half-width, ST, ST interval half-width)
        SALib's ``SALib.analyze.sobol`` with :data:`CONFIDENCE` bootstrap intervals.
    """
    return _sobol(spec, np.asarray(y, dtype=float), seed)


def _sobol(spec, y, seed):
    from SALib.analyze import sobol as sobol_analyze
    # SALib seeds its bootstrap only when ``if seed:`` holds: seed 0 would draw from NumPy's global state
    # (intervals that change from run to run). Seed s is passed as s + 1.
    res = sobol_analyze.analyze(spec.problem(), y, calc_second_order=False, conf_level=CONFIDENCE,
                                seed=int(seed) + 1, print_to_console=False)
    return [(name, float(res["S1"][k]), float(res["S1_conf"][k]), float(res["ST"][k]), float(res["ST_conf"][k]))
            for k, name in enumerate(spec.names)]


def _against_measurement(winners, criterion, loads, pressures, measured, p_best, seed):
    """Per load and jointly: P(the measured best is the model's best), and whether the uncertainty admits it."""
    out = []
    joint = None
    for fz in loads:
        best = measured.get(fz, {}).get("best_pressure")
        if best is None or best not in pressures:
            continue
        rows, share = winners[fz, criterion]
        col = share[:, pressures.index(best)]
        series = dict(zip(rows, col, strict=True))
        joint = series if joint is None else {r: joint[r] * v for r, v in series.items() if r in joint}
        row = p_best[(p_best["fz_n"] == fz) & (p_best["criterion"] == criterion) & (p_best["pressure_kpa"] == best)]
        p, hi = float(row["p"].iloc[0]), float(row["high"].iloc[0])
        out.append({"criterion": criterion, "fz_n": fz, "measured_best_kpa": best, "p": p,
                    "low": float(row["low"].iloc[0]), "high": hi, "admitted": bool(hi >= ADMIT_PROBABILITY)})
    if joint:
        p, lo, hi = p_best_interval(np.array(list(joint.values()))[:, None])
        out.append({"criterion": criterion, "fz_n": math.nan, "measured_best_kpa": math.nan,
                    "p": float(p[0]), "low": float(lo[0]), "high": float(hi[0]),
                    "admitted": bool(hi[0] >= ADMIT_PROBABILITY)})
    return out


def verdict_lines(study, criterion="settling"):
    """One line per load: the most probable best pressure with its interval, and the input it hinges on most."""
    lines = []
    pb = study.p_best[(study.p_best["criterion"] == criterion) & study.p_best["pressure_kpa"].notna()]
    for fz, rows in pb.groupby("fz_n", sort=False):
        top = rows.sort_values("p", ascending=False)
        first = top.iloc[0]
        text = (f"{fz:g} N: {first['pressure_kpa']:g} kPa recovers fastest ({criterion}) with P = {first['p']:.2f} "
                f"[{first['low']:.2f}, {first['high']:.2f}]")
        if len(top) > 1:
            second = top.iloc[1]
            pair = sorted((first["pressure_kpa"], second["pressure_kpa"]))
            s = study.sobol[(study.sobol["fz_n"] == fz) & (study.sobol["criterion"] == criterion)
                            & (study.sobol["pressure_a_kpa"] == pair[0]) & (study.sobol["pressure_b_kpa"] == pair[1])]
            text += f", next {second['pressure_kpa']:g} kPa ({second['p']:.2f})"
            if len(s):
                key = s.sort_values("ST", ascending=False).iloc[0]
                text += (f"; the {pair[1]:g}-{pair[0]:g} kPa difference hinges most on {key['input']} "
                         f"(total Sobol {key['ST']:.2f} +- {key['ST_conf']:.2f})")
        lines.append(text)
    m = study.measured[study.measured["criterion"] == "last_peak"] if len(study.measured) else study.measured
    joint = m[m["fz_n"].isna()] if len(m) else m
    if len(joint):
        j = joint.iloc[0]
        lines.append(f"measured ranking (Table 8.9, last peak): P = {j['p']:.2f} [{j['low']:.2f}, {j['high']:.2f}] "
                     f"that the model gives it at every load: {'admitted' if j['admitted'] else 'not admitted'} "
                     f"by the model's uncertainty (N = {study.samples}, {len(study.inputs)} rows)")
    return lines


def format_study(study):
    """Plain-text tables: P(best) beside the measured best, rates, and the verdict."""
    lines = [f"uncertainty study: {study.spec.name}, N = {study.samples} base samples, {len(study.inputs)} rows "
             f"(seed {study.seed}); every row runs at every pressure and load"]
    for criterion in CRITERIA:
        lines.append(f"\nP(best) by {criterion} ({CRITERIA[criterion].column}), 95 % Wilson interval; * measured best")
        pb = study.p_best[study.p_best["criterion"] == criterion]
        for fz, rows in pb.groupby("fz_n", sort=False):
            cells = []
            for _, r in rows.iterrows():
                name = "none" if math.isnan(r["pressure_kpa"]) else f"{r['pressure_kpa']:g}{'*' if r['measured_best'] else ''}"
                cells.append(f"{name}: {r['p']:.2f} [{r['low']:.2f}, {r['high']:.2f}]")
            lines.append(f"  {fz:g} N ({int(rows['rows'].iloc[0])} rows): " + "; ".join(cells))
    lines.append("\nfall / not recovered (settling) / failed runs per pressure")
    for _, r in study.rates.iterrows():
        lines.append(f"  {r['fz_n']:g} N {r['pressure_kpa']:g} kPa: {int(r['fell'])}/{int(r['not_recovered_settling'])}/"
                     f"{int(r['failed'])} of {int(r['runs'])}")
    lines += ["", *study.notes, "", *study.verdict]
    return "\n".join(lines)
