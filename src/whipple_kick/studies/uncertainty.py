"""How sure is the answer: which pressure recovers fastest, with its probability, and what it hinges on.

The uncertainty study runs the kick at every pressure for every
rear load on inputs sampled from an uncertainty file
(:mod:`whipple_kick.library.uncertain`), and reports:

* **P(best)** per pressure per load, for both criteria (the recovery time
  ``recovery.time_s`` and the thesis' last-peak time ``last_peak_time_s``),
  with a 95 % Wilson score interval (:func:`p_best_interval` says why), pooled
  and **per option** (``p_best_by_option``): within the rows of each option of
  a choice (the rider, the kick direction, the friction) and of each half of a
  continuous input (:func:`input_groups`: ``gain_scale`` below and above 1.0).
  The design samples the choices, so this is analysis of the same rows, no new
  runs; a result that hinges on a choice is reported per option;
* the recovery-time distribution per pressure, the **paired differences**
  between pressures (:func:`paired_difference`), and the fall, not-recovered
  and failure rates;
* **Sobol indices** (first order and total, with SALib's 95 % intervals) of
  **which of two pressures recovers first** (:func:`first_sign`: +1, -1, or 0
  for a tie or neither within the run), per pair, load and criterion, with the
  rows where one or neither run recovered counted beside them, and a caution
  where N cannot resolve them (:func:`sobol_caution`);
* the measured ranking (thesis Table 8.9) against the model, with the
  measurement's own error (:func:`against_measurement`).

Why this Sobol output. The paired difference ``T(b) - T(a)`` is undefined
where a run did not recover within the run (fell, not settled, failed):
giving it the run's duration (6 s) made the indices depend on that number
(and a row where neither recovered a difference of 0): the earlier study found, at
N = 48, 4-7 % of the rows carrying 20-43 % of the variance, total indices
summing to 2.1 and 63 of 180 first-order indices negative. Which pressure recovers
first is defined for every row without a number for the runs that did not
recover (one that did not is later than any that did; two that did not tie),
is bounded, and is the paired, ordinal question the study asks (P(best) is its
three-way form). Its mean is P(a first) - P(b first). The alternatives: the
indicator "p recovers within t" is not paired (one pressure's, not the
comparison's), and a rank of the times still needs an order among the runs
that did not recover. What the order cannot avoid: a longer run lets some of
the runs that did not recover do so, which changes their rows (a tie becomes a
win); ``scripts/sobol_censoring.py`` measures how much, at 6 against 8 s.

Against the measurement. The thesis' last-peak times are means of three
trials, without a printed spread (the project was told of differences of 0.04-0.07 s
between the trials of a cell, not re-checked: the calibration file's reason). The error of a cell is the calibration file's trial prior with the printing's
rounding (:func:`measurement_error`). Where a measured difference to the
measured best is within its 95 % error, the measured ranking at that load is
**not resolved by the measurement** (the model can neither confirm nor
contradict it). Where every difference is beyond it, each is placed in the
model's predictive distribution of the paired difference plus the measurement
error (:func:`predictive_check`): consistent, inconsistent, or not resolved at
this N. Unlike the former rule ("admitted when the upper end of P(best)'s
interval reaches 0.05"), fewer rows never make a check pass.

Sampling and pairing. SALib's Saltelli-Sobol' design (``SALib.sample.sobol``,
first order and total, so ``N (D + 2)`` rows for ``N`` base samples and
``D`` inputs) on the unit cube, mapped through each input's inverse CDF.
**Each row is one set of inputs run at every pressure and every load**
(common random numbers): a difference between pressures is never a
difference of inputs. P(best), the distributions and the differences use the
``2N`` rows of the design's two base matrices (A and B: each a sample of the
inputs); the Sobol analysis uses every row, as it must. An N that is not a
power of 2 is valid and said in a note.

Falls and failures (never dropped silently):

* a run that **fell**, or that **did not recover** by the run's end
  (criterion value missing), ranks after every run that recovered; in a row
  where no pressure recovered nothing is best (the ``none`` share of P(best));
  ties split the credit;
* a run that **failed** numerically is counted; a row with a failure at a
  load is left out of that load's P(best) and differences, and the count is
  printed;
* the differences count the pairs with one and with both runs not recovered;
  the mean difference is over the pairs where both recovered, and the
  probabilities (a first, b first, tie, neither) over every pair;
* for the Sobol analysis (which needs every row) a failed run counts as not
  recovered within the run (a note says how many rows); the rows with one or
  neither run recovered are counted in ``sobol.csv``.

Example
-------
Skipped as a doctest: hundreds of kick runs (``tests/studies/test_uncertainty.py``
runs a small one; ``scripts/uncertainty_study.py`` the measured one).

>>> from whipple_kick import uncertainty
>>> study = uncertainty.run_study(samples=16, seed=0)     # doctest: +SKIP
>>> print("\\n".join(study.verdict))                      # doctest: +SKIP
"""
import dataclasses
import difflib
import hashlib
import itertools
import json
import math
import os
import pathlib
import shutil
import warnings

import numpy as np
import pandas as pd
from scipy import stats

from whipple_kick import fileio
from whipple_kick.errors import InputError, check_range
from whipple_kick.library import bicycleparameters, bicycles, experiments, priors, thesis, tyres, uncertain
from whipple_kick.model import cache
from whipple_kick.simulate import assembly
from whipple_kick.simulate.criteria import CRITERIA  # the one table: every declared criterion
from whipple_kick.simulate.scenario import DEFAULTS, MECHANISM_FIELDS, UNITS, Scenario

from .recommend import _num, pressure_grid
from .sweep_engine import check_some_ok, make_cases, sweep
from .sweep_store import read_log, read_manifest
from .sweep_store import table as stored_table

#: Thesis Chapter 8's pressures [kPa] and rear loads [N] (:mod:`whipple_kick.library.thesis`).
PRESSURES = thesis.PRESSURES_KPA
LOADS = thesis.LOADS_N
#: Bootstrap resamples of the paired differences' intervals.
BOOTSTRAP = 2000
#: Confidence level of every interval.
CONFIDENCE = 0.95
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
    distributions, differences, rates : pandas.DataFrame
        Per pressure: quantiles of the recovered runs; per pair: :func:`paired_difference`'s columns; per
        pressure: fell, not recovered, failed.
    sobol : pandas.DataFrame
        :data:`SOBOL_COLUMNS`: per load, criterion, pair and input, the indices of :func:`first_sign` and the
        rows with one or neither run recovered.
    measured : pandas.DataFrame
        :data:`MEASURED_COLUMNS` (:func:`against_measurement`).
    verdict : list of str
        Per load: both criteria's answer (a tie said as one), what it hinges on, P(best) by option; then the
        measured ranking.
    notes : list of str
        Counts of what was left out, constant outputs, an N not a power of 2.
    p_best_by_option : pandas.DataFrame
        :data:`BY_OPTION_COLUMNS` (:func:`p_best_by_option`).
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
    p_best_by_option: object = None

    def write(self, folder):
        """Write every table as CSV into ``folder``; returns the paths."""
        folder = pathlib.Path(folder)
        folder.mkdir(parents=True, exist_ok=True)
        paths = []
        for name in ("inputs", "outcomes", "p_best", "p_best_by_option", "distributions", "differences", "rates",
                     "sobol", "measured"):
            if getattr(self, name) is None:
                continue
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
    close = difflib.get_close_matches(field, DEFAULTS, n=1)
    return f" (did you mean {close[0]!r}?)" if close else ""


def _check_changes(where, base, changes):
    """``base`` with ``changes`` passes the run's checks (the fields the changed mechanisms do not read left at
    ``base``'s, as a sample row leaves them); else InputError ``<where>: <the check's message>``."""
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


def _design(spec, samples, seed, loads, pressures, base):
    """The study's checked design: ``(spec, base, unit, blocks, cases, keys, ids)`` (nothing is run)."""
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
    return spec, base, unit, blocks, cases, keys, ids


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
    spec, base, unit, blocks, cases, keys, ids = _design(spec, samples, seed, loads, pressures, base)
    sweep_options.setdefault("progress", False)
    sweep_options.setdefault("trajectory_columns", None)   # thousands of runs: the table, not the time histories
    table = sweep(cases=cases, base=base, **sweep_options)
    check_some_ok(table)
    return analyse(spec, samples, seed, unit, blocks, keys, ids, table, base.duration)


def analyse_folder(folder, spec=uncertain.DEFAULT, samples=64, seed=0, loads=LOADS, pressures=PRESSURES,
                   base=None):
    """Analyse a study's stored runs again, with this code's analysis, running nothing.

    ``folder`` is the sweep folder :func:`run_study` was given (``folder=``); the
    other arguments must be the ones it ran with (the same design: each case is
    found by its id). A subset of its loads may be asked for (a study cut short
    after its first loads). The runs stay what the code that made them computed
    (its commit is in the folder's manifest); only the statistics are this code's.

    Raises
    ------
    InputError
        The folder holds no sweep, or lacks some of the design's runs (how many, and for which loads).
    """
    spec, base, unit, blocks, cases, keys, ids = _design(spec, samples, seed, loads, pressures, base)
    if read_manifest(folder) is None:
        raise InputError(f"{str(folder)!r} holds no sweep (no manifest): give the folder run_study ran in")
    records = read_log(folder)
    missing = [key for key, cid in zip(keys, ids, strict=True) if cid not in records]
    if missing:
        at = sorted({fz for _, fz, _ in missing})
        raise InputError(f"{str(folder)!r} lacks {len(missing)} of the design's {len(ids)} runs (at "
                         f"{', '.join(f'{fz:g}' for fz in at)} N): the same file, samples = {samples} and "
                         f"seed = {seed}? Finish the study, or analyse only the loads it completed")
    case_list = make_cases(cases=cases, base=base)
    table = stored_table(case_list, records)
    check_some_ok(table)
    return analyse(spec, samples, seed, unit, blocks, keys, ids, table, base.duration)


def _kpa(pressures):
    """Pressures as a message lists them: "300, 400 kPa"."""
    return ", ".join(f"{p:g}" for p in sorted(pressures)) + " kPa"


def analyse(spec, samples, seed, unit, blocks, keys, ids, table, duration):
    """The study's tables from its sweep ``table`` (rows found by case id: a repeated case runs once)."""
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
    p_best, dists, diffs, rates, sobol, by_option = [], [], [], [], [], []
    notes = [f"Sobol output: which of two pressures recovers first within the run's {duration:g} s (+1, -1, or 0 "
             "for a tie or neither): no time is given to a run that did not recover (see the module's docstring)"]
    if samples & (samples - 1):
        notes.append(f"N = {samples} is not a power of 2: the Sobol' sequence's points are not balanced (SALib "
                     "warns so); the design and its indices are valid, their error somewhat larger than at a power of 2")
    a_rows = np.array([b == "A" for b in blocks])
    b_rows = np.array([b == "B" for b in blocks])
    for k, inp in enumerate(spec.inputs):
        # A choice whose option is the same in A and B of every base point is never varied by the design
        # (at a small N the Sobol' sequence can do that: the shipped file's friction column at N = 8).
        if np.array_equal(inp.ppf(unit[a_rows, k]), inp.ppf(unit[b_rows, k])):
            notes.append(f"{inp.name}: the design never varies it at N = {samples} (the same value in A and B of "
                         "every base point): its Sobol indices are 0 by construction, not a finding; use a larger N")
    for inp in spec.inputs:
        if inp.distribution == "choice":
            missing = [o.label for o in inp.options if not (inputs.loc[base_rows, inp.name] == o.label).any()]
            if missing:
                notes.append(f"{inp.name}: no row of the base matrices has {', '.join(missing)} at N = {samples}: "
                             "no P(best) for it (p_best_by_option.csv leaves it out); use a larger N")
    winners, times_of = {}, {}
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
        use = base_rows & ~row_failed
        for criterion, col in ((key, c.column) for key, c in CRITERIA.items()):
            values = at[col].map(_num).to_numpy(dtype=float).reshape(shape)
            # inf: not recovered within the run (fell, not settled, or failed): later than any recovery, never a number
            times = np.where(np.isfinite(values) & ~fell_m & ~failed_m, values, np.inf)
            times_of[fz, criterion] = (times, use)
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
            by_option += [{"fz_n": fz, "criterion": criterion, **r}
                          for r in p_best_by_option(spec, inputs[use], times[use], pressures)]
            for k, p in enumerate(pressures):
                ok = times[use][:, k]
                ok = ok[np.isfinite(ok)]
                q = np.quantile(ok, [0.05, 0.25, 0.5, 0.75, 0.95]) if ok.size else [math.nan] * 5
                dists.append({"fz_n": fz, "criterion": criterion, "pressure_kpa": p, "recovered": int(ok.size),
                              "rows": int(use.sum()), "mean_s": float(ok.mean()) if ok.size else math.nan,
                              **{f"q{int(100 * level):02d}_s": float(v)
                                 for level, v in zip((0.05, 0.25, 0.5, 0.75, 0.95), q, strict=True)}})
            for (i, pi), (j, pj) in itertools.combinations(enumerate(pressures), 2):
                diffs.append({"fz_n": fz, "criterion": criterion, "pressure_a_kpa": pi, "pressure_b_kpa": pj,
                              **paired_difference(times[use][:, i], times[use][:, j], rng)})
            n_failed = int(failed_m.any(axis=1).sum())
            if n_failed:
                notes.append(f"{fz:g} N, {criterion}: {n_failed} of {n_rows} rows have a failed run: for the Sobol "
                             "analysis (which needs every row) it counts as not recovered within the run")
            for (i, pi), (j, pj) in itertools.combinations(enumerate(pressures), 2):
                y = first_sign(times[:, i], times[:, j])
                one = int((np.isfinite(times[:, i]) != np.isfinite(times[:, j])).sum())
                both = int((~np.isfinite(times[:, i]) & ~np.isfinite(times[:, j])).sum())
                if np.ptp(y) == 0.0:
                    notes.append(f"{fz:g} N, {criterion}: which of {pi:g} and {pj:g} kPa recovers first is the same "
                                 "in every row: no Sobol indices")
                    continue
                for name, s1, s1c, st, stc in _sobol(spec, y, rng_seed):
                    sobol.append({"fz_n": fz, "criterion": criterion, "pressure_a_kpa": pi, "pressure_b_kpa": pj,
                                  "input": name, "S1": s1, "S1_conf": s1c, "ST": st, "ST_conf": stc, "rows": n_rows,
                                  "rows_one_not_recovered": one, "rows_neither_recovered": both})
    p_best = pd.DataFrame(p_best)
    sobol = pd.DataFrame(sobol, columns=SOBOL_COLUMNS)
    meas = against_measurement(times_of, winners, loads, pressures, p_best)
    study = UncertaintyStudy(spec, samples, seed, inputs, outcomes, p_best, pd.DataFrame(dists), pd.DataFrame(diffs),
                             pd.DataFrame(rates), sobol, meas, [], notes,
                             pd.DataFrame(by_option, columns=BY_OPTION_COLUMNS))
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


def first_sign(t_a, t_b):
    """Which of two paired runs recovers first: per row +1 (``a``), -1 (``b``) or 0 (a tie, or neither).

    ``inf`` is a run that did not recover within the run (fell, not settled, failed): later than any
    run that recovered, and tied with another that did not. The value depends on the order of the two
    times only, never on a number given to a run that did not recover.
    """
    t_a, t_b = np.asarray(t_a, dtype=float), np.asarray(t_b, dtype=float)
    return (t_a < t_b).astype(float) - (t_b < t_a).astype(float)


def paired_difference(t_a, t_b, rng):
    """``differences.csv``'s columns for one pair of pressures over paired rows (``inf``: not recovered).

    Counts the pairs with one and with both runs not recovered (they are never dropped silently); the
    mean and median of ``T(b) - T(a)`` over the pairs where both recovered (the only ones where it is a
    number); and the censoring-proof statistics over every pair: P(a first), P(b first), P(tie: both
    recovered at the same time), P(neither recovered), the mean of :func:`first_sign` (P(a first) -
    P(b first)) and ``p_a_faster`` (P(a first) + half the ties and neithers), each with its bootstrap
    interval (:data:`CONFIDENCE`).
    """
    t_a, t_b = np.asarray(t_a, dtype=float), np.asarray(t_b, dtype=float)
    rec_a, rec_b = np.isfinite(t_a), np.isfinite(t_b)
    both = rec_a & rec_b
    d = t_b[both] - t_a[both]
    sign = first_sign(t_a, t_b)
    faster = (sign == 1.0) + 0.5 * (sign == 0.0)
    n = len(sign)
    nan2 = ([math.nan], [math.nan])
    lo, hi = _bootstrap_means(d[:, None], rng) if d.size else nan2
    flo, fhi = _bootstrap_means(faster[:, None], rng) if n else nan2
    slo, shi = _bootstrap_means(sign[:, None], rng) if n else nan2

    def share(mask):
        return float(mask.mean()) if n else math.nan
    return {"pairs": n, "pairs_both_recovered": int(both.sum()), "pairs_one_not_recovered": int((rec_a != rec_b).sum()),
            "pairs_neither_recovered": int((~rec_a & ~rec_b).sum()),
            "mean_b_minus_a_s": float(d.mean()) if d.size else math.nan, "low_s": lo[0], "high_s": hi[0],
            "median_b_minus_a_s": float(np.median(d)) if d.size else math.nan,
            "p_a_first": share(sign == 1.0), "p_b_first": share(sign == -1.0),
            "p_tie": share((sign == 0.0) & both), "p_neither": share(~rec_a & ~rec_b),
            "first_sign_mean": float(sign.mean()) if n else math.nan, "first_sign_low": slo[0],
            "first_sign_high": shi[0], "p_a_faster": float(faster.mean()) if n else math.nan,
            "p_a_faster_low": flo[0], "p_a_faster_high": fhi[0]}


#: Columns of ``sobol.csv``.
SOBOL_COLUMNS = ["fz_n", "criterion", "pressure_a_kpa", "pressure_b_kpa", "input", "S1", "S1_conf", "ST", "ST_conf",
                 "rows", "rows_one_not_recovered", "rows_neither_recovered"]
#: Columns of ``p_best_by_option.csv``.
BY_OPTION_COLUMNS = ["fz_n", "criterion", "input", "option", "rows", "pressure_kpa", "p", "low", "high", "pooled_p"]


def input_groups(spec, inputs):
    """The rows of each option of a choice and each half of a continuous input: ``[(input, option, mask)]``.

    ``inputs`` is the study's ``inputs`` table (one row per sample row). A continuous input is split at
    its scenario field's default, the value the plain recommender runs at, where that lies well inside the
    distribution (between its 10 % and 90 % quantiles: ``gain_scale`` at 1.0, the project's LQR gains;
    thesis Table 8.4's gains are 1.3-1.6 times them, its sensitivity case halves them), and otherwise at
    the distribution's median (``speed``, whose default 3 m/s is outside the thesis' 1.92-2 m/s).
    """
    out = []
    for inp in spec.inputs:
        column = inputs[inp.name]
        if inp.distribution == "choice":
            out += [(inp.name, o.label, (column == o.label).to_numpy()) for o in inp.options]
        else:
            mid = float(inp.ppf([0.5])[0])
            default = DEFAULTS.get(inp.field) if inp.field else None
            if isinstance(default, (int, float)) and float(inp.ppf([0.1])[0]) < default < float(inp.ppf([0.9])[0]):
                mid = float(default)
            v = column.to_numpy(dtype=float)
            out += [(inp.name, f"< {mid:g}", v < mid), (inp.name, f">= {mid:g}", v >= mid)]
    return out


def p_best_by_option(spec, inputs, times, pressures):
    """P(best) within the rows of each option (:func:`input_groups`), beside the pooled one.

    Analysis of the study's rows, no new runs: the design samples every choice, so the rows of one option
    are a sample of the other inputs with that option; an option no row has is left out. Returns rows of ``p_best_by_option.csv`` (less the
    load and criterion): ``input, option, rows, pressure_kpa`` (NaN: the ``none`` share), ``p, low, high``
    (:func:`p_best_interval`) and ``pooled_p``.
    """
    pooled = _best_share(times).mean(axis=0) if len(times) else np.full(len(pressures) + 1, math.nan)
    out = []
    for name, option, mask in input_groups(spec, inputs):
        if not mask.any():
            continue   # an option no row samples (a small N): no P(best), the table says nothing of it
        p, low, high = p_best_interval(_best_share(times[mask]))
        for k, pressure in enumerate([*pressures, math.nan]):
            out.append({"input": name, "option": option, "rows": int(mask.sum()), "pressure_kpa": pressure,
                        "p": float(p[k]), "low": float(low[k]), "high": float(high[k]), "pooled_p": float(pooled[k])})
    return out


def measurement_error(calibration=None):
    """Standard deviation [s] of one measured last-peak time (a cell's mean of three trials), with its reason.

    The calibration file's trial prior (``errors.last_peak_time_s.trial_sd``, 0.04 s in the shipped one, an
    unsourced prior: differences of 0.04-0.07 s between a cell's trials, as the project was told;
    :mod:`whipple_kick.library.priors`) and the printing's
    rounding (two decimals: ``0.005 / sqrt(3)``), as the calibration takes them
    (:func:`whipple_kick.studies.calibration.measured_features`, less the 8 % crossing's quantisation, which
    the last-peak time itself does not have). Taken as the error of the cell's mean, not divided by the
    square root of the three trials: the thesis prints no spread.
    """
    spec = priors.load() if calibration is None else calibration
    trial = spec.errors["last_peak_time_s"].sd
    rounding = experiments.PRINT_HALF_STEP / math.sqrt(3.0)
    return math.hypot(trial, rounding), (f"trial prior {trial:g} s ({spec.path}: errors.last_peak_time_s) and "
                                         f"the printing's rounding {rounding:.4f} s")


#: The measured criterion: the thesis prints last-peak times (Tables 8.6-8.8) and ranks by them (Table 8.9).
MEASURED_CRITERION = "last_peak"
#: Columns of ``measured.csv``.
MEASURED_COLUMNS = ["criterion", "fz_n", "measured_best_kpa", "pressure_kpa", "measured_diff_s", "measured_sd_s",
                    "measured_resolved", "rows", "q", "q_low", "q_high", "p_best", "p_best_low", "p_best_high",
                    "verdict"]


def predictive_check(t_best, t_other, measured_diff, sd):
    """Whether a measured difference ``T(other) - T(best)`` [s], with its error ``sd``, is one the model gives.

    Per paired row the probability that the model's difference plus a measurement error (normal, ``sd``)
    is at most the measured one, ``Phi((measured - d) / sd)``; a row where only ``other`` did not recover
    (``inf``) gives 0, only ``best`` 1, neither: unknown, 0 for the lower and 1 for the upper end. Their
    mean ``q`` is the measured difference's place in the model's predictive distribution. Its interval is
    :func:`p_best_interval`'s (Wilson) of the lower and upper ends.

    Returns
    -------
    (q, low, high, verdict)
        ``verdict``: ``"consistent"`` when the whole interval lies within ``[a/2, 1 - a/2]`` (``a = 1 -``
        :data:`CONFIDENCE`), ``"inconsistent"`` when it lies wholly outside, else ``"not resolved at this
        N"``. The Wilson interval holds its point estimate and widens as the rows get fewer: fewer rows never
        turn an inconsistent (or undecided) check into a consistent one.
    """
    t_best, t_other = np.asarray(t_best, dtype=float), np.asarray(t_other, dtype=float)
    if not len(t_best):
        return math.nan, math.nan, math.nan, "no rows"
    neither = ~np.isfinite(t_best) & ~np.isfinite(t_other)
    with np.errstate(invalid="ignore"):
        d = np.where(neither, 0.0, t_other - t_best)   # +-inf where one did not recover: cdf 0 or 1
        prob = stats.norm.cdf((measured_diff - d) / sd)
    lower, upper = np.where(neither, 0.0, prob), np.where(neither, 1.0, prob)
    low = float(p_best_interval(lower[:, None])[1][0])
    high = float(p_best_interval(upper[:, None])[2][0])
    tail = (1.0 - CONFIDENCE) / 2.0
    if low >= tail and high <= 1.0 - tail:
        verdict = "consistent"
    elif high < tail or low > 1.0 - tail:
        verdict = "inconsistent"
    else:
        verdict = "not resolved at this N"
    return float((lower.mean() + upper.mean()) / 2.0), low, high, verdict


def _combine(verdicts):
    """One verdict of several checks: inconsistent if any is, consistent if all are, else not resolved."""
    if not verdicts:
        return "not resolved by the measurement"
    if "inconsistent" in verdicts:
        return "inconsistent"
    return "consistent" if all(v == "consistent" for v in verdicts) else "not resolved at this N"


def against_measurement(times_of, winners, loads, pressures, p_best, calibration=None):
    """``measured.csv``: the model against thesis Table 8.9's measured ranking, with the measurement's own error.

    Per load, for each pressure beside the measured best ``b``: the measured difference ``L(p) - L(b)`` of
    the last-peak times (Tables 8.6-8.8) and its standard deviation (``sqrt(2)`` times
    :func:`measurement_error`). The measurement **resolves** the ranking at a load when every such
    difference exceeds its 95 % half-width (``1.96 sd``); where it does not, the measured best is no
    finding the model could contradict or confirm ("not resolved by the measurement"). Where it does, the
    model's paired rows are checked against each measured difference (:func:`predictive_check`), for the
    last-peak criterion only (the thesis measures no settling time); P(best) of the measured best is
    given beside, for both criteria. One row per criterion with ``fz_n`` NaN: the probability that one row
    gives the measured best at every load (the rows are shared by the loads) and the combined verdict of
    the resolved loads.
    """
    exp = experiments.load()
    z = float(stats.norm.ppf(0.5 + CONFIDENCE / 2.0))
    sd_cell, _ = measurement_error(calibration)
    sd = math.sqrt(2.0) * sd_cell
    out = []
    for criterion in CRITERIA:
        joint, verdicts = None, []
        for fz in loads:
            best = exp.best.get(fz, {}).get("best_pressure")
            if best is None or best not in pressures:
                continue
            rows, share = winners[fz, criterion]
            series = dict(zip(rows, share[:, pressures.index(best)], strict=True))
            joint = series if joint is None else {r: joint[r] * v for r, v in series.items() if r in joint}
            pb = p_best[(p_best["fz_n"] == fz) & (p_best["criterion"] == criterion) & (p_best["pressure_kpa"] == best)]
            times, use = times_of[fz, criterion]
            checks = []
            for other in pressures:
                if other == best or (fz, other) not in {(c.fz_n, c.pressure_kpa) for c in exp.cases.values()}:
                    continue
                diff = exp.case(fz, other).values["last_peak_time"] - exp.case(fz, best).values["last_peak_time"]
                resolved = bool(diff > z * sd)
                row = {"criterion": criterion, "fz_n": fz, "measured_best_kpa": best, "pressure_kpa": other,
                       "measured_diff_s": diff, "measured_sd_s": sd, "measured_resolved": resolved,
                       "rows": int(use.sum()), "q": math.nan, "q_low": math.nan, "q_high": math.nan,
                       "p_best": float(pb["p"].iloc[0]), "p_best_low": float(pb["low"].iloc[0]),
                       "p_best_high": float(pb["high"].iloc[0])}
                if criterion != MEASURED_CRITERION:
                    row["verdict"] = "not measured (the thesis gives last-peak times)"
                else:
                    q, lo, hi, verdict = predictive_check(times[use][:, pressures.index(best)],
                                                          times[use][:, pressures.index(other)], diff, sd)
                    row.update(q=q, q_low=lo, q_high=hi, verdict=verdict)
                checks.append(row)
            if criterion == MEASURED_CRITERION and checks:
                if all(c["measured_resolved"] for c in checks):
                    verdicts += [c["verdict"] for c in checks]
                else:
                    for c in checks:
                        c["verdict"] = "not resolved by the measurement"
            out += checks
        if joint:
            p, lo, hi = p_best_interval(np.array(list(joint.values()))[:, None])
            out.append({"criterion": criterion, "fz_n": math.nan, "measured_best_kpa": math.nan,
                        "pressure_kpa": math.nan, "measured_diff_s": math.nan, "measured_sd_s": sd,
                        "measured_resolved": bool(verdicts), "rows": len(joint), "q": math.nan, "q_low": math.nan,
                        "q_high": math.nan, "p_best": float(p[0]), "p_best_low": float(lo[0]),
                        "p_best_high": float(hi[0]),
                        "verdict": _combine(verdicts) if criterion == MEASURED_CRITERION
                        else "not measured (the thesis gives last-peak times)"})
    return pd.DataFrame(out, columns=MEASURED_COLUMNS)


def sobol_caution(rows):
    """Why one output's Sobol indices (rows of ``sobol.csv``) are not resolved at this N: a list of reasons.

    Empty when they are. A reason: the first-order indices sum above 1 or below 0, or the total ones below
    1, beyond their combined intervals (true indices cannot); an index negative beyond its interval; the
    largest total index not resolved from 0 (its interval reaches 0); more than half the inputs whose total (or
    first-order) index is >= 0.05 with that index's interval wider than the index.
    """
    reasons = []
    s1, s1c = float(rows["S1"].sum()), math.sqrt(float((rows["S1_conf"] ** 2).sum()))
    st, stc = float(rows["ST"].sum()), math.sqrt(float((rows["ST_conf"] ** 2).sum()))
    if s1 - s1c > 1.0 or s1 + s1c < 0.0:
        reasons.append(f"first-order indices sum to {s1:.2f} +- {s1c:.2f} (between 0 and 1)")
    if st + stc < 1.0:
        reasons.append(f"total indices sum to {st:.2f} +- {stc:.2f} (at least 1)")
    negative = int(((rows["S1"] + rows["S1_conf"] < 0) | (rows["ST"] + rows["ST_conf"] < 0)).sum())
    if negative:
        reasons.append(f"{negative} of {len(rows)} inputs with an index negative beyond its interval")
    top = rows.loc[rows["ST"].idxmax()]
    if top["ST_conf"] >= top["ST"]:
        reasons.append(f"the largest total index ({top['input']} {top['ST']:.2f} +- {top['ST_conf']:.2f}) is not "
                       "resolved from 0")
    # Each kind of index over the inputs that matter by it: an input acting only through interactions has a
    # first-order index near 0, whose interval is wider than it at any N (N = 512 cautioned on that alone).
    for name, idx in (("total", "ST"), ("first-order", "S1")):
        matter = rows[rows[idx] >= 0.05]
        wide = int((matter[f"{idx}_conf"] > matter[idx].abs()).sum())
        if len(matter) and 2 * wide > len(matter):
            reasons.append(f"{wide} of the {len(matter)} inputs with a {name} index >= 0.05 have intervals "
                           "wider than their indices")
    return reasons


def hinge(rows):
    """The input one output hinges most on, when its total index's interval separates from the next one's.

    Returns ``(top row, next row, separated)`` of ``sobol.csv`` rows (next None with one input).
    """
    ranked = rows.sort_values("ST", ascending=False)
    top = ranked.iloc[0]
    if len(ranked) < 2:
        return top, None, bool(top["ST"] - top["ST_conf"] > 0)
    second = ranked.iloc[1]
    return top, second, bool(top["ST"] - top["ST_conf"] > second["ST"] + second["ST_conf"])


def _criterion_line(pb, criterion):
    """"<criterion>: 300 kPa P = .. [..], next ..." with "tie" where the two intervals overlap."""
    top = pb[pb["pressure_kpa"].notna()].sort_values("p", ascending=False)
    none = pb[pb["pressure_kpa"].isna()]
    name = CRITERIA[criterion].short
    first = top.iloc[0]
    cell = f"{first['pressure_kpa']:g} kPa P = {first['p']:.2f} [{first['low']:.2f}, {first['high']:.2f}]"
    if len(top) > 1:
        second = top.iloc[1]
        other = f"{second['pressure_kpa']:g} kPa P = {second['p']:.2f} [{second['low']:.2f}, {second['high']:.2f}]"
        if second["high"] >= first["low"]:
            text = f"{name}: a tie, {cell} and {other} (their intervals overlap)"
        else:
            text = f"{name}: {cell} is most probable best, next {other}"
    else:
        text = f"{name}: {cell}"
    if len(none) and none["p"].iloc[0] > 0:
        text += f"; none recovered in {none['p'].iloc[0]:.2f} of the rows"
    return text, (first["pressure_kpa"], top.iloc[1]["pressure_kpa"]) if len(top) > 1 else None


def _option_line(study, fz, criterion):
    """"by option: rider: A 300 kPa (0.55), ...": the most probable best within each option, for the choices
    and the continuous input with the largest total index (its two halves)."""
    bo = study.p_best_by_option
    if bo is None or not len(bo):
        return None
    at = bo[(bo["fz_n"] == fz) & (bo["criterion"] == criterion) & bo["pressure_kpa"].notna()]
    choices = _shown_inputs(study, fz, criterion)
    parts = []
    for name in choices:
        cells = []
        for option, rows in at[at["input"] == name].groupby("option", sort=False):
            if not rows["rows"].iloc[0]:
                continue
            top = rows.sort_values("p", ascending=False)
            first, second = top.iloc[0], top.iloc[1] if len(top) > 1 else None
            tie = second is not None and second["high"] >= first["low"]
            cells.append(f"{option} {'tie ' if tie else ''}{first['pressure_kpa']:g}"
                         + (f"/{second['pressure_kpa']:g}" if tie else "") + f" kPa ({first['p']:.2f}, "
                         f"{int(first['rows'])} rows)")
        if cells:
            parts.append(f"{name}: " + ", ".join(cells))
    return "by option (most probable best): " + "; ".join(parts) if parts else None


def verdict_lines(study, criterion="settling"):
    """Per load: both criteria's most probable best (a tie said as a tie), what the comparison hinges on (only
    where the Sobol intervals separate, with a caution where N cannot resolve them) and P(best) by option;
    then the measured ranking against the model. ``criterion`` comes first and decides the Sobol pair."""
    lines = []
    order = [criterion, *(c for c in CRITERIA if c != criterion)]
    for fz in dict.fromkeys(study.p_best["fz_n"]):
        texts, pair = [], None
        for crit in order:
            pb = study.p_best[(study.p_best["criterion"] == crit) & (study.p_best["fz_n"] == fz)]
            if not len(pb):
                continue
            text, top_pair = _criterion_line(pb, crit)
            texts.append(text)
            pair = pair or top_pair
        line = f"{fz:g} N: " + "; ".join(texts)
        if pair is not None:
            a, b = sorted(pair)
            s = study.sobol[(study.sobol["fz_n"] == fz) & (study.sobol["criterion"] == criterion)
                            & (study.sobol["pressure_a_kpa"] == a) & (study.sobol["pressure_b_kpa"] == b)]
            if len(s):
                top, second, separated = hinge(s)
                if separated:
                    line += (f"; which of {a:g}/{b:g} kPa recovers first ({criterion}) hinges most on {top['input']} "
                             f"(total Sobol {top['ST']:.2f} +- {top['ST_conf']:.2f}"
                             + (f", next {second['input']} {second['ST']:.2f} +- {second['ST_conf']:.2f})"
                                if second is not None else ")"))
                else:
                    line += (f"; no single input decides which of {a:g}/{b:g} kPa recovers first ({criterion}): the "
                             f"largest total Sobol indices' intervals overlap ({top['input']} {top['ST']:.2f} +- "
                             f"{top['ST_conf']:.2f}"
                             + (f", {second['input']} {second['ST']:.2f} +- {second['ST_conf']:.2f})"
                                if second is not None else ")"))
                reasons = sobol_caution(s)
                if reasons:
                    line += (f" [caution: N = {study.samples} does not resolve these indices: "
                             + "; ".join(reasons) + "]")
        lines.append(line)
        option = _option_line(study, fz, criterion)
        if option:
            lines.append(f"{fz:g} N {option}")
    lines += _measured_lines(study)
    return lines


def _measured_lines(study):
    """The measured ranking (Table 8.9, last peak) against the model, per load and as a whole."""
    m = study.measured
    if m is None or not len(m) or "verdict" not in m:
        return []
    m = m[m["criterion"] == MEASURED_CRITERION]
    lines = []
    for fz, rows in m[m["fz_n"].notna()].groupby("fz_n", sort=False):
        best = rows["measured_best_kpa"].iloc[0]
        diffs = ", ".join(f"{r['pressure_kpa']:g} kPa +{r['measured_diff_s']:.2f} s" for _, r in rows.iterrows())
        half = 1.959964 * rows["measured_sd_s"].iloc[0]
        head = (f"measured at {fz:g} N (Table 8.9, last peak): {best:g} kPa best ({diffs}; 95 % error of a "
                f"difference +-{half:.2f} s)")
        if not rows["measured_resolved"].all():
            lines.append(f"{head}: not resolved by the measurement (a difference within its error): the model can "
                         f"neither confirm nor contradict it; model P(best) of {best:g} kPa "
                         f"{rows['p_best'].iloc[0]:.2f}")
        else:
            checks = ", ".join(f"{r['pressure_kpa']:g} kPa {r['verdict']} (q = {r['q']:.2f} [{r['q_low']:.2f}, "
                               f"{r['q_high']:.2f}])" for _, r in rows.iterrows())
            lines.append(f"{head}: the model's paired differences: {checks}; model P(best) of {best:g} kPa "
                         f"{rows['p_best'].iloc[0]:.2f} [{rows['p_best_low'].iloc[0]:.2f}, "
                         f"{rows['p_best_high'].iloc[0]:.2f}]")
    joint = m[m["fz_n"].isna()]
    if len(joint):
        j = joint.iloc[0]
        resolved = [f"{fz:g} N" for fz, rows in m[m["fz_n"].notna()].groupby("fz_n", sort=False)
                    if rows["measured_resolved"].all()]
        head = (f"{j['verdict']} over the loads the measurement resolves ({', '.join(resolved)})" if resolved else
                "not resolved by the measurement at any load")
        lines.append(f"measured ranking as a whole (last peak): {head}; P = {j['p_best']:.2f} [{j['p_best_low']:.2f}, "
                     f"{j['p_best_high']:.2f}] that one row gives the measured best at every load (N = "
                     f"{study.samples}, {len(study.inputs)} rows)")
    return lines


def format_study(study):
    """Plain-text tables: P(best) beside the measured best, by option, rates, Sobol indices, and the verdict."""
    lines = [f"uncertainty study: {study.spec.name}, N = {study.samples} base samples, {len(study.inputs)} rows "
             f"(seed {study.seed}); every row runs at every pressure and load"]
    for criterion in CRITERIA:
        lines.append(f"\nP(best) by {criterion} ({CRITERIA[criterion].column}), 95 % Wilson interval; * measured best")
        pb = study.p_best[study.p_best["criterion"] == criterion]
        for fz, rows in pb.groupby("fz_n", sort=False):
            lines.append(f"  {fz:g} N ({int(rows['rows'].iloc[0])} rows): " + _cells(rows))
            bo = study.p_best_by_option
            if bo is None or not len(bo):
                continue
            at = bo[(bo["fz_n"] == fz) & (bo["criterion"] == criterion)]
            shown = _shown_inputs(study, fz, criterion)
            for (name, option), orows in at.groupby(["input", "option"], sort=False):
                if name in shown:
                    lines.append(f"    {name} = {option} ({int(orows['rows'].iloc[0])} rows): " + _cells(orows))
    lines.append("\nfall / not recovered (settling) / failed runs per pressure")
    for _, r in study.rates.iterrows():
        lines.append(f"  {r['fz_n']:g} N {r['pressure_kpa']:g} kPa: {int(r['fell'])}/{int(r['not_recovered_settling'])}/"
                     f"{int(r['failed'])} of {int(r['runs'])}")
    if len(study.sobol):
        lines.append("\nSobol indices of which pressure recovers first (total, 95 % interval; the 3 largest), with "
                     "the rows where one / neither run recovered")
        for (fz, crit, a, b), rows in study.sobol.groupby(["fz_n", "criterion", "pressure_a_kpa", "pressure_b_kpa"],
                                                          sort=False):
            r0 = rows.iloc[0]
            top = rows.sort_values("ST", ascending=False).head(3)
            cells = ", ".join(f"{r['input']} {r['ST']:.2f} +- {r['ST_conf']:.2f}" for _, r in top.iterrows())
            caution = sobol_caution(rows)
            lines.append(f"  {fz:g} N {crit} {a:g}/{b:g} kPa: {cells}; rows {int(r0['rows'])}, one not recovered "
                         f"{100 * r0['rows_one_not_recovered'] / r0['rows']:.0f} %, neither "
                         f"{100 * r0['rows_neither_recovered'] / r0['rows']:.0f} %"
                         + (" (not resolved at this N)" if caution else ""))
    lines += ["", *study.notes, "", *study.verdict]
    return "\n".join(lines)


def _cells(rows):
    """"300*: 0.51 [0.41, 0.61]; ...; none: 0.07 [..]" of P(best) rows."""
    cells = []
    for _, r in rows.iterrows():
        name = "none" if math.isnan(r["pressure_kpa"]) else \
            f"{r['pressure_kpa']:g}{'*' if r.get('measured_best', False) else ''}"
        cells.append(f"{name}: {r['p']:.2f} [{r['low']:.2f}, {r['high']:.2f}]")
    return "; ".join(cells)


def _shown_inputs(study, fz, criterion):
    """The inputs whose options the text shows at a load: the choices and the continuous input with the largest
    mean total Sobol index there (every input is in ``p_best_by_option.csv``)."""
    names = [i.name for i in study.spec.inputs if i.distribution == "choice"]
    continuous = [i.name for i in study.spec.inputs if i.distribution != "choice"]
    s = study.sobol[(study.sobol["fz_n"] == fz) & (study.sobol["criterion"] == criterion)
                    & study.sobol["input"].isin(continuous)]
    if len(s):
        names.append(s.groupby("input", sort=False)["ST"].mean().idxmax())
    return names
