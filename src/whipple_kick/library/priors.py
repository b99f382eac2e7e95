"""The calibration's inputs as data: uniform priors, measurement errors and model discrepancies, each with its reason.

A calibration file (``parameters/calibration/<name>.toml``, package data) holds:

* ``format``, ``name``, ``description``, ``experiment`` (the measured cases it is for);
* ``[priors.<name>]``: ``field`` (a scenario field), ``unit``, ``low`` < ``high``
  (a uniform prior), ``reason``, ``sourced`` (false: no publication or
  measurement sets the range; the answer rests on a choice);
* ``[errors.<feature>]``: the measurement error of a feature (:data:`FEATURES`
  names its one number: a prior standard deviation), ``unit``, ``reason``, ``sourced``;
* ``[discrepancy.<feature>]``: ``sd`` > 0, the model discrepancy's standard
  deviation, ``unit``, ``reason``, ``sourced``.

Every problem is a one-line :class:`~whipple_kick.errors.InputError`
``<file>: <key>: <problem>``; :func:`prior` and :func:`discrepancy` check
values given from Python the same way.

Example
-------
>>> spec = load()
>>> spec.priors["kick_accel"].low, spec.priors["kick_accel"].sourced
(30.0, True)
"""
import dataclasses
import math
import pathlib

from whipple_kick.errors import InputError

from . import parameters
from .parameters import fail, number, table, text

#: The ``format`` line of a calibration file.
FORMAT = "whipple_kick calibration, version 1"
#: The shipped file (thesis Chapter 8's kick plate).
DEFAULT = "kickplate_2025"
#: The response features and the key of their measurement-error prior in ``[errors.<feature>]``
#: (their definitions: :mod:`whipple_kick.studies.calibration`).
FEATURES = {"frequency_hz": "period_sd", "log_decrement": "floor_sd", "last_peak_time_s": "trial_sd"}


@dataclasses.dataclass(frozen=True)
class Prior:
    """A uniform prior on one scenario field."""

    name: str
    field: str
    unit: str
    low: float
    high: float
    reason: str
    sourced: bool

    @property
    def width(self):
        """``high - low``."""
        return self.high - self.low


@dataclasses.dataclass(frozen=True)
class Stated:
    """A stated standard deviation (an error or a discrepancy) with its reason."""

    feature: str
    sd: float
    unit: str
    reason: str
    sourced: bool


@dataclasses.dataclass(frozen=True)
class CalibrationSpec:
    """A calibration file as read by :func:`load`."""

    name: str
    description: str
    path: str
    experiment: str
    priors: dict
    errors: dict
    discrepancy: dict

    def unsourced(self):
        """``[(kind, name, reason)]`` of every value no publication or measurement sets."""
        out = [("prior", p.name, p.reason) for p in self.priors.values() if not p.sourced]
        out += [("error", s.feature, s.reason) for s in self.errors.values() if not s.sourced]
        out += [("discrepancy", s.feature, s.reason) for s in self.discrepancy.values() if not s.sourced]
        return out


def prior(name, field, low, high, unit="", reason="given", sourced=False):
    """A checked :class:`Prior` (``low < high``, both finite); InputError otherwise."""
    try:
        low, high = float(low), float(high)
    except (TypeError, ValueError):
        raise InputError(f"prior {name!r}: bounds must be numbers, got {low!r} and {high!r}") from None
    if not (math.isfinite(low) and math.isfinite(high)):
        raise InputError(f"prior {name!r}: bounds must be finite, got {low!r} and {high!r} {unit}")
    if not low < high:
        raise InputError(f"prior {name!r}: bounds inverted or empty: low = {low:g} {unit} must be < "
                         f"high = {high:g} {unit}")
    return Prior(name, field, unit, low, high, reason, bool(sourced))


def discrepancy(feature, sd, unit="", reason="given", sourced=False):
    """A checked discrepancy :class:`Stated` (``sd > 0``); InputError otherwise."""
    if feature not in FEATURES:
        raise InputError(f"feature {feature!r} is unknown; the experiments give {', '.join(FEATURES)}")
    try:
        sd = float(sd)
    except (TypeError, ValueError):
        raise InputError(f"discrepancy of {feature}: sd must be a number in {unit}, got {sd!r}") from None
    if not (math.isfinite(sd) and sd > 0):
        raise InputError(f"discrepancy of {feature}: sd = {sd!r} {unit} must be > 0 {unit} (a model that "
                         "matches the measurement exactly is not a calibration's premise)")
    return Stated(feature, sd, unit, reason, bool(sourced))


def available():
    """The shipped calibration files by name."""
    return parameters.toml_files(parameters.shipped("calibration"))


def _flag(path, key, entry):
    value = entry.get("sourced")
    if not isinstance(value, bool):
        fail(path, f"{key}.sourced", f"must be true or false (does a publication or measurement set it?), got {value!r}")
    return value


def _allowed(path, key, entry, keys):
    extra = sorted(set(entry) - set(keys))
    missing = sorted(set(keys) - set(entry))
    if extra or missing:
        fail(path, key, f"must have exactly {', '.join(sorted(keys))}"
                        + (f" (unknown: {', '.join(extra)})" if extra else "")
                        + (f" (missing: {', '.join(missing)})" if missing else ""))


def load(name_or_path=DEFAULT) -> CalibrationSpec:
    """Read and check a calibration file (a shipped name, or a path).

    Raises
    ------
    InputError
        One line naming the file, the key and the problem: inverted bounds, a
        discrepancy or error <= 0, an unknown feature, a missing reason or flag.
    """
    shipped = available()
    if str(name_or_path) in shipped:
        path = shipped[str(name_or_path)]
    else:
        path = pathlib.Path(str(name_or_path))
        if not path.exists():
            raise InputError(f"calibration file {name_or_path!r} does not exist (shipped: {', '.join(shipped)})")
    data = parameters.load_toml(path)
    allowed = {"format", "name", "description", "experiment", "priors", "errors", "discrepancy"}
    unknown = sorted(set(data) - allowed)
    if unknown:
        fail(path, "top level", f"unknown key(s) {', '.join(unknown)}; allowed: {', '.join(sorted(allowed))}")
    if data.get("format") != FORMAT:
        fail(path, "format", f"must be {FORMAT!r}, got {data.get('format')!r}")
    priors = {}
    for name, entry in table(path, "priors", data.get("priors")).items():
        key = f"priors.{name}"
        entry = table(path, key, entry)
        _allowed(path, key, entry, ("field", "unit", "low", "high", "reason", "sourced"))
        low, high = number(path, f"{key}.low", entry["low"]), number(path, f"{key}.high", entry["high"])
        unit = text(path, f"{key}.unit", entry["unit"])
        if not low < high:
            fail(path, key, f"bounds inverted or empty: low = {low:g} {unit} must be < high = {high:g} {unit}")
        priors[name] = Prior(name, text(path, f"{key}.field", entry["field"]), unit, low, high,
                             text(path, f"{key}.reason", entry["reason"]), _flag(path, key, entry))
    errors, disc = {}, {}
    for kind, out in (("errors", errors), ("discrepancy", disc)):
        for feature, entry in table(path, kind, data.get(kind)).items():
            key = f"{kind}.{feature}"
            if feature not in FEATURES:
                fail(path, key, f"feature {feature!r} is unknown; the experiments give {', '.join(FEATURES)}")
            entry = table(path, key, entry)
            sd_key = FEATURES[feature] if kind == "errors" else "sd"
            _allowed(path, key, entry, (sd_key, "unit", "reason", "sourced"))
            sd = number(path, f"{key}.{sd_key}", entry[sd_key])
            unit = text(path, f"{key}.unit", entry["unit"])
            if not sd > 0:
                fail(path, f"{key}.{sd_key}", f"value {sd:g} must be > 0 (unit of {feature}: {unit})")
            out[feature] = Stated(feature, sd, unit, text(path, f"{key}.reason", entry["reason"]),
                                  _flag(path, key, entry))
    missing = [f for f in FEATURES if f not in errors or f not in disc]
    if missing:
        fail(path, "errors/discrepancy", f"every feature needs both; missing for {', '.join(missing)}")
    return CalibrationSpec(text(path, "name", data.get("name")), text(path, "description", data.get("description")),
                           str(path), text(path, "experiment", data.get("experiment")), priors, errors, disc)
