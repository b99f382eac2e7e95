"""Uncertain inputs as data: a TOML file declares each input's distribution and the reason for it.

An uncertainty file (``parameters/uncertainty/<name>.toml``, shipped as package
data like the other parameter files) holds:

* ``format``, ``name`` (the file's name), ``description``;
* ``[fixed.<field>]``: ``{ value, reason }`` scenario fields the study holds
  fixed (e.g. the experiment's kick profile);
* ``[inputs.<name>]``: one uncertain input, with a ``reason`` (its source or
  why the range is what it is) and a ``distribution``:

  - ``uniform``: ``field``, ``unit``, ``low`` < ``high``;
  - ``normal``: ``field``, ``unit``, ``mean``, ``sd`` > 0, optionally
    ``low`` and/or ``high`` (a truncated normal);
  - ``choice``: ``[[inputs.<name>.options]]``, each with a ``label``, a
    ``probability`` (all summing to 1 within 1e-9) and either ``value`` (the
    input then names one ``field``) or ``set``, a table of scenario fields
    the option sets together (a discrete choice of mechanism, e.g. the rider).

This module checks the format and maps unit-interval samples (SALib's) onto
values through each input's inverse CDF (a choice by cumulative probability).
Whether a field exists and whether the run uses it is the study's to check
(:func:`whipple_kick.studies.uncertainty.check_inputs`): this wing does not
know the scenario. Every problem is a one-line :class:`InputError`
``<file>: <key>: <problem>``.

Example
-------
>>> spec = load()
>>> spec.names[:3]
('speed', 'kick_accel', 'kick_direction')
>>> spec.values([0.5] * len(spec.names))["speed"]
1.96
"""
import dataclasses
import math
import pathlib

import numpy as np
from scipy import stats

from whipple_kick.errors import InputError

from . import bicycleparameters, parameters
from .parameters import fail, number, table, text

#: The ``format`` line of an uncertainty file.
FORMAT = "whipple_kick uncertainty, version 1"
#: The shipped file the study uses by default (thesis Chapter 8's kick-plate experiment).
DEFAULT = "kickplate_2025"
#: Distributions and the keys each takes (besides ``distribution`` and ``reason``).
DISTRIBUTIONS = {
    "uniform": {"required": ("field", "unit", "low", "high"), "optional": ()},
    "normal": {"required": ("field", "unit", "mean", "sd"), "optional": ("low", "high")},
    "choice": {"required": ("options",), "optional": ("field",)},
}
#: How far the probabilities of a choice may miss 1.
PROBABILITY_TOLERANCE = 1e-9
# Unit samples are kept this far inside (0, 1): an untruncated normal's inverse CDF is infinite at 0 and 1.
_EDGE = 1e-12


@dataclasses.dataclass(frozen=True)
class Option:
    """One option of a discrete choice: its label, probability and the fields it sets."""

    label: str
    probability: float
    values: dict


@dataclasses.dataclass(frozen=True)
class UncertainInput:
    """One uncertain input.

    Attributes
    ----------
    name : str
    distribution : {"uniform", "normal", "choice"}
    reason : str
        Its source, or why the range is what it is.
    field : str or None
        The scenario field it sets (None: a choice whose options set several fields).
    unit : str
        Unit of a continuous input ("" for a choice).
    low, high : float or None
        Bounds (a normal's truncation; None: unbounded).
    mean, sd : float or None
        A normal's parameters.
    options : tuple of Option
        A choice's options.
    """

    name: str
    distribution: str
    reason: str
    field: str | None = None
    unit: str = ""
    low: float | None = None
    high: float | None = None
    mean: float | None = None
    sd: float | None = None
    options: tuple = ()

    @property
    def fields(self) -> tuple:
        """Every scenario field this input sets."""
        if self.field is not None:
            return (self.field,)
        return tuple(dict.fromkeys(k for o in self.options for k in o.values))

    def possible(self, field) -> set:
        """The values this input can give ``field`` (a choice's; empty for a continuous input)."""
        return {o.values[field] for o in self.options if field in o.values}

    def ppf(self, u):
        """Inverse CDF: unit samples ``u`` (array) to values; a choice gives its option indices."""
        u = np.clip(np.asarray(u, dtype=float), _EDGE, 1.0 - _EDGE)
        if self.distribution == "uniform":
            return self.low + u * (self.high - self.low)
        if self.distribution == "normal":
            lo = -np.inf if self.low is None else (self.low - self.mean) / self.sd
            hi = np.inf if self.high is None else (self.high - self.mean) / self.sd
            return self.mean + self.sd * stats.truncnorm.ppf(u, lo, hi)
        cumulative = np.cumsum([o.probability for o in self.options])
        return np.minimum(np.searchsorted(cumulative, u, side="right"), len(self.options) - 1)

    def describe(self) -> str:
        """One line: the distribution and its parameters."""
        if self.distribution == "uniform":
            return f"uniform {self.low:g}-{self.high:g} {self.unit}"
        if self.distribution == "normal":
            lo = "-inf" if self.low is None else f"{self.low:g}"
            hi = "inf" if self.high is None else f"{self.high:g}"
            cut = "" if self.low is None and self.high is None else f", truncated to [{lo}, {hi}]"
            return f"normal {self.mean:g} +- {self.sd:g} {self.unit}{cut}"
        return "choice: " + ", ".join(f"{o.label} ({o.probability:.3g})" for o in self.options)


@dataclasses.dataclass(frozen=True)
class UncertainSet:
    """The inputs of an uncertainty file, in file order, the fields it holds fixed, and the measured bicycle
    whose parameters its ``bicycle.*`` inputs sample (None: no ``[bicycle]`` table)."""

    name: str
    description: str
    path: str
    inputs: tuple
    fixed: dict
    measured_bicycle: str | None = None

    @property
    def names(self) -> tuple:
        return tuple(i.name for i in self.inputs)

    def problem(self) -> dict:
        """SALib's problem: every input on the unit interval (the inverse CDFs map it)."""
        return {"num_vars": len(self.inputs), "names": list(self.names), "bounds": [[0.0, 1.0]] * len(self.inputs)}

    def values(self, unit_row) -> dict:
        """The scenario field values of one row of unit samples (one per input, in order)."""
        out = {}
        for inp, u in zip(self.inputs, unit_row, strict=True):
            value = inp.ppf([u])[0]
            if inp.distribution == "choice":
                out.update(inp.options[int(value)].values)
            else:
                out[inp.field] = float(value)
        return out

    def labels(self, unit_row) -> dict:
        """Each input's value in one row as a table shows it: a number, or a choice's label."""
        out = {}
        for inp, u in zip(self.inputs, unit_row, strict=True):
            value = inp.ppf([u])[0]
            out[inp.name] = inp.options[int(value)].label if inp.distribution == "choice" else float(value)
        return out


def available() -> dict:
    """The shipped uncertainty files by name."""
    return parameters.toml_files(parameters.shipped("uncertainty"))


def load(name_or_path=DEFAULT) -> UncertainSet:
    """Read and check an uncertainty file (a shipped name, or a path).

    Raises
    ------
    InputError
        One line naming the file, the key and the problem: an unknown key or
        distribution, inverted bounds, a non-positive sd, probabilities not
        summing to 1, a missing reason, two inputs setting one field.
    """
    shipped = available()
    text_name = str(name_or_path)
    if text_name in shipped:
        path = shipped[text_name]
    else:
        path = pathlib.Path(text_name)
        if not path.exists():
            raise InputError(f"uncertainty file {text_name!r} does not exist (shipped: {', '.join(shipped)})")
    data = parameters.load_toml(path)
    allowed = {"format", "name", "description", "fixed", "inputs", "bicycle"}
    unknown = sorted(set(data) - allowed)
    if unknown:
        fail(path, "top level", f"unknown key(s) {', '.join(unknown)}; allowed: {', '.join(sorted(allowed))}")
    if data.get("format") != FORMAT:
        fail(path, "format", f"must be {FORMAT!r}, got {data.get('format')!r}")
    name = text(path, "name", data.get("name"))
    description = text(path, "description", data.get("description"))
    fixed = {}
    for field, entry in table(path, "fixed", data.get("fixed", {})).items():
        entry = table(path, f"fixed.{field}", entry)
        extra = sorted(set(entry) - {"value", "reason"})
        if extra or "value" not in entry:
            fail(path, f"fixed.{field}", "must be { value = ..., reason = \"...\" }")
        text(path, f"fixed.{field}.reason", entry.get("reason"))
        fixed[field] = entry["value"]
    # [inputs] may be left out only where a [bicycle] table declares the inputs.
    entries = table(path, "inputs", data.get("inputs")) if "inputs" in data or "bicycle" not in data else {}
    inputs = tuple(_read_input(path, key, entry) for key, entry in entries.items())
    measured = None
    if "bicycle" in data:
        if "bicycle" in fixed:
            fail(path, "bicycle", "the measured bicycle's parameters are sampled: fixed.bicycle would contradict it")
        bicycle = table(path, "bicycle", data["bicycle"])
        inputs += bicycle_inputs(path, bicycle)
        measured = bicycle["measured"]
    if not inputs:
        fail(path, "inputs", "declares no uncertain input")
    owner = {}
    for inp in inputs:
        for field in inp.fields:
            if field in owner:
                fail(path, f"inputs.{inp.name}", f"sets {field!r}, which inputs.{owner[field]} sets too")
            if field in fixed:
                fail(path, f"inputs.{inp.name}", f"sets {field!r}, which [fixed] holds fixed")
            owner[field] = inp.name
    return UncertainSet(name, description, str(path), inputs, fixed, measured)


#: A field name ``bicycle.<parameter>``: a measured bicycle's parameter (BicycleParameters' names, and
#: ``seating.<length>``), sampled from its standard deviation (:func:`bicycle_inputs`).
BICYCLE_PREFIX = "bicycle."
#: A measured parameter is sampled from its normal distribution truncated to this many standard deviations
#: either side (a mass or an inertia several deviations below its nominal would be unphysical).
BICYCLE_TRUNCATION_SD = 3.0


def bicycle_inputs(path, entry) -> tuple:
    """The inputs of a ``[bicycle]`` table: a measured bicycle's parameters from their ``+/-``.

    ``[bicycle]`` holds ``measured`` (a shipped bicycle, or a BicycleParameters
    folder or Benchmark.txt), ``reason``, and optionally ``parameters`` (the
    names to sample; default every parameter with a standard deviation) and
    ``sd_scale`` (a factor on every deviation, default 1). Each parameter is a
    normal input ``bicycle.<name>`` with the file's value as mean and its
    standard deviation times ``sd_scale`` as sd, truncated to
    :data:`BICYCLE_TRUNCATION_SD` deviations.
    """
    allowed = {"measured", "reason", "parameters", "sd_scale"}
    extra = sorted(set(entry) - allowed)
    if extra or "measured" not in entry or "reason" not in entry:
        fail(path, "bicycle", "must have measured and reason, optionally parameters and sd_scale"
                              + (f" (unknown: {', '.join(extra)})" if extra else ""))
    measured = text(path, "bicycle.measured", entry["measured"])
    reason = text(path, "bicycle.reason", entry["reason"])
    scale = number(path, "bicycle.sd_scale", entry.get("sd_scale", 1.0))
    if not scale > 0:
        fail(path, "bicycle.sd_scale", f"value {scale:g} must be > 0")
    bike = bicycleparameters.load_bicycle(measured)
    # Benchmark names and seating lengths: what a BicycleParameters folder written per sample row can carry.
    known = {k: v for k, v in bicycleparameters.parameter_uncertainties(bike).items()
             if k in bike.benchmark or k.startswith("seating.")}
    names = entry.get("parameters", sorted(known))
    if not isinstance(names, list) or not names:
        fail(path, "bicycle.parameters", "must be a non-empty array of parameter names")
    out = []
    for name in names:
        if name not in known:
            fail(path, "bicycle.parameters", f"{name!r} has no standard deviation in {measured!r}; "
                                             f"those that have: {', '.join(sorted(known))}")
        nominal, std = known[name]
        sd = std * scale
        out.append(UncertainInput(
            f"{BICYCLE_PREFIX}{name}", "normal", f"{reason} ({measured}: {nominal:g} +/- {std:g})",
            f"{BICYCLE_PREFIX}{name}", "SI", nominal - BICYCLE_TRUNCATION_SD * sd,
            nominal + BICYCLE_TRUNCATION_SD * sd, nominal, sd))
    return tuple(out)


def _read_input(path, name, entry) -> UncertainInput:
    key = f"inputs.{name}"
    entry = table(path, key, entry)
    if "reason" not in entry:
        fail(path, key, "missing 'reason' (the source of the distribution, or why it is what it is)")
    reason = text(path, f"{key}.reason", entry["reason"])
    kind = entry.get("distribution")
    if kind not in DISTRIBUTIONS:
        fail(path, f"{key}.distribution", f"{kind!r} is unknown; choose one of {', '.join(DISTRIBUTIONS)}")
    spec = DISTRIBUTIONS[kind]
    allowed = {"distribution", "reason", *spec["required"], *spec["optional"]}
    extra = sorted(set(entry) - allowed)
    if extra:
        fail(path, key, f"unknown key(s) {', '.join(extra)} for a {kind} distribution; "
                        f"allowed: {', '.join(sorted(allowed))}")
    missing = [k for k in spec["required"] if k not in entry]
    if missing:
        fail(path, key, f"missing {', '.join(missing)} for a {kind} distribution")
    field = text(path, f"{key}.field", entry["field"]) if "field" in entry else None
    if kind == "choice":
        return UncertainInput(name, kind, reason, field, options=_read_options(path, key, entry["options"], field))
    unit = text(path, f"{key}.unit", entry["unit"])
    low = number(path, f"{key}.low", entry["low"]) if "low" in entry else None
    high = number(path, f"{key}.high", entry["high"]) if "high" in entry else None
    if low is not None and high is not None and not low < high:
        fail(path, key, f"bounds inverted or empty: low = {low:g} {unit} must be < high = {high:g} {unit}")
    if kind == "uniform":
        return UncertainInput(name, kind, reason, field, unit, low, high)
    mean = number(path, f"{key}.mean", entry["mean"])
    sd = number(path, f"{key}.sd", entry["sd"])
    if not sd > 0:
        fail(path, f"{key}.sd", f"value {sd:g} {unit} must be > 0 {unit}")
    return UncertainInput(name, kind, reason, field, unit, low, high, mean, sd)


def _read_options(path, key, entries, field) -> tuple:
    if not isinstance(entries, list) or not entries:
        fail(path, f"{key}.options", "must be a non-empty array of tables ([[...options]])")
    options = []
    for k, entry in enumerate(entries):
        where = f"{key}.options[{k}]"
        entry = table(path, where, entry)
        want = {"label", "probability", "value" if field is not None else "set"}
        if set(entry) != want:
            fail(path, where, f"must have exactly {', '.join(sorted(want))}"
                 + (" (the input names a field)" if field is not None else " (the input names no field: "
                    "each option sets its fields in 'set')"))
        label = text(path, f"{where}.label", entry["label"])
        p = number(path, f"{where}.probability", entry["probability"])
        if not 0.0 <= p <= 1.0:
            fail(path, f"{where}.probability", f"value {p:g} must lie in [0, 1]")
        values = {field: entry["value"]} if field is not None else dict(table(path, f"{where}.set", entry["set"]))
        if not values:
            fail(path, f"{where}.set", "sets no field")
        options.append(Option(label, p, values))
    labels = [o.label for o in options]
    if len(set(labels)) != len(labels):
        fail(path, f"{key}.options", f"labels repeat: {labels}")
    total = math.fsum(o.probability for o in options)
    if abs(total - 1.0) > PROBABILITY_TOLERANCE:
        fail(path, f"{key}.options", f"probabilities sum to {total:.12g}, not 1 (within {PROBABILITY_TOLERANCE:g})")
    return tuple(options)
