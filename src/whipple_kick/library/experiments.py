"""The thesis' measured kick-plate responses as data (thesis Chapter 8, Sections 8.3-8.6, Tables 8.3, 8.6-8.9).

:func:`load` reads ``parameters/experiments/kickplate_2025.toml`` (package
data, through the project's one parameter reader :mod:`whipple_kick.library.parameters`):
the nine measured cases (three rear loads x three pressures) with the yaw
rate's last-peak time, log decrements, damping ratios and period; the
printed % variations; Table 8.9's best pressures; the conditions of the
runs and how the recordings were processed. The numbers are kept as
printed; :func:`inconsistencies` lists where the printed tables contradict
themselves (a damping ratio that does not follow from its log decrement by
eq. 8.3, a % variation that does not follow from the printed values), and
the file's ``[[notes]]`` lists what the text contradicts.

:func:`implied_first_peak_times` tests the time origin of the printed
last-peak times (see docs/experiments.md): with the kick at t = 0 peak #1
could not come before the rider's first response (0.04-0.05 s after the
kick), yet the printed last-peak times and periods put it at -0.12 to
+0.09 s; measured from peak #1 they fit.

Example
-------
>>> from whipple_kick import experiments
>>> exp = experiments.load()
>>> exp.cases["635N_400kPa"].values["last_peak_time"], exp.best[701.0]["best_pressure"]
(0.36, 500.0)
"""
from dataclasses import dataclass
import math
import pathlib

from whipple_kick.errors import InputError

from . import parameters

#: The shipped experiment.
DEFAULT_EXPERIMENT = "kickplate_2025"
#: Format string every experiment file declares.
FORMAT = "whipple_kick experiment, version 1"
#: Metrics of a measured case (thesis Tables 8.6-8.8 rows) and their units.
METRICS = {"last_peak_time": "s", "log_dec_13": "-", "zeta_13": "-", "log_dec_24": "-", "zeta_24": "-",
           "log_dec_35": "-", "zeta_35": "-", "period": "s"}
#: Log decrement -> damping ratio pairs (eq. 8.3).
ZETA_OF = {"zeta_13": "log_dec_13", "zeta_24": "log_dec_24", "zeta_35": "log_dec_35"}
#: The tables print two decimals and whole per cents: a printed value stands for any value within half
#: its last digit. A derived value is inconsistent only if no pair of such values gives it.
PRINT_HALF_STEP = 0.005
PERCENT_HALF_STEP = 0.5
#: Earliest plausible time of yaw-rate peak #1 after the kick [s]: the first response seen in the
#: recordings (thesis Section 8.5.1: the steer rate reacts ~0.04 s after the force application;
#: Section 8.5.2: the first significant variation 0.05 s after it).
FIRST_RESPONSE_S = 0.04

_CONDITION_UNITS = {
    "speed_min": "m/s", "speed_max": "m/s", "plate_displacement": "m", "plate_length": "m",
    "plate_acceleration_min": "m/s^2", "plate_acceleration_max": "m/s^2", "plate_acceleration_peak_max": "m/s^2",
    "cylinder_force": "N", "cylinder_force_max": "N", "kick_duration": "s", "wheel_on_plate_min": "s",
    "wheel_on_plate_max": "s", "rider_reaction_delay": "s", "tests_per_pressure": "-"}
_PROCESSING_UNITS = {
    "imu_rate": "Hz", "lowpass_cutoff": "Hz", "trials_averaged": "-", "peak_threshold": "-", "spectrum_max": "Hz",
    "record_length": "s", "peak_window": "s", "yaw_band_low": "Hz", "yaw_band_high": "Hz"}
_RIDER_UNITS = {"mass": "kg", "fz_front": "N", "fz_rear": "N", "rear_share": "-"}
_BEST_UNITS = {"printed_load": "N", "fz_n": "N", "best_pressure": "kPa", "recovery_time_reduction": "%"}
_CASE_UNITS = {"fz_n": "N", "pressure_kpa": "kPa", "last_peak_number": "-", **METRICS}


@dataclass(frozen=True)
class MeasuredCase:
    """One measured case: a rear load and a pressure, three trials averaged.

    Attributes
    ----------
    case : str
        ``"<load>N_<pressure>kPa"``, e.g. ``"635N_400kPa"``.
    fz_n, pressure_kpa : float
        Static rear-tyre load [N] and inflation pressure of both tyres [kPa].
    last_peak_number : int
        Number of the last yaw-rate peak above 8 % (4 or 6).
    values : dict
        :data:`METRICS` that the thesis prints for this case (701 N has no
        peaks #3-#5 row), units as there.
    sources : dict
        Citation of every value.
    """

    case: str
    fz_n: float
    pressure_kpa: float
    last_peak_number: int
    values: dict
    sources: dict


@dataclass(frozen=True)
class Experiment:
    """The kick-plate experiment as read by :func:`load`.

    Attributes
    ----------
    path : pathlib.Path
    name, tyre : str
    conditions, processing : dict
        Values in the units of ``_CONDITION_UNITS`` / ``_PROCESSING_UNITS``
        (``cylinder_force_uncertainty`` [N] as well).
    riders : dict
        ``{"A": {"mass": kg, "fz_front": N, "fz_rear": N, "rear_share": -}, ...}``.
    cases : dict
        ``{case: MeasuredCase}``, nine of them.
    variations : dict
        ``{load [N]: {"reference_kpa": p, "<metric>_vs_<p>kPa": % as printed}}``.
    spectrum_peak_hz : dict
        ``{load [N]: yaw-rate spectrum local maximum [Hz]}`` (per load, from the text).
    best : dict
        ``{load [N]: {"printed_load", "fz_n", "best_pressure", "recovery_time_reduction"}}`` (Table 8.9).
    notes : list of dict
        ``{"where", "printed", "text"}``: the contradictions the file records.
    """

    path: object
    name: str
    tyre: str
    conditions: dict
    processing: dict
    riders: dict
    cases: dict
    variations: dict
    spectrum_peak_hz: dict
    best: dict
    notes: list

    @property
    def loads(self):
        """The rear loads [N], ascending."""
        return sorted({c.fz_n for c in self.cases.values()})

    @property
    def pressures(self):
        """The pressures [kPa], ascending."""
        return sorted({c.pressure_kpa for c in self.cases.values()})

    def case(self, fz_n, pressure_kpa):
        """The :class:`MeasuredCase` of a load [N] and pressure [kPa]."""
        for c in self.cases.values():
            if c.fz_n == fz_n and c.pressure_kpa == pressure_kpa:
                return c
        raise InputError(f"no measured case at {fz_n:g} N and {pressure_kpa:g} kPa; measured loads "
                         f"{', '.join(f'{f:g}' for f in self.loads)} N, pressures "
                         f"{', '.join(f'{p:g}' for p in self.pressures)} kPa")


def damping_ratio(delta):
    """Damping ratio from the logarithmic decrement, thesis eq. 8.3.

    ``zeta = delta / sqrt(4 pi^2 + delta^2)``; always in (-1, 1), exact for a
    linear viscously damped free oscillation.
    """
    delta = float(delta)
    return delta / math.sqrt(4 * math.pi ** 2 + delta ** 2)


def case_name(fz_n, pressure_kpa):
    """``"635N_400kPa"``: the name of a case."""
    return f"{fz_n:g}N_{pressure_kpa:g}kPa"


def available():
    """Names of the shipped experiment files."""
    return list(parameters.toml_files(parameters.shipped("experiments")))


def _load_key(path, key):
    """``570.0`` from a table key ``"570N"``."""
    if not key.endswith("N"):
        parameters.fail(path, key, "must be a rear load such as '570N'")
    try:
        return float(key[:-1])
    except ValueError:
        parameters.fail(path, key, "must be a rear load such as '570N'")


def _read(path, table_name, entries, units, complete=True):
    values, spreads = parameters.quantities(path, table_name, entries, units, complete=complete, uncertainty=True)
    values.update({f"{k}_uncertainty": v for k, v in spreads.items()})
    return values


def load(name=DEFAULT_EXPERIMENT):
    """Read and check an experiment file (default: the thesis' kick-plate campaign).

    Parameters
    ----------
    name : str
        A shipped experiment (:func:`available`) or a path to a ``.toml`` file.

    Returns
    -------
    Experiment

    Raises
    ------
    InputError
        Unknown name, or a malformed file (one line naming the file and key).
    """
    files = parameters.toml_files(parameters.shipped("experiments"))
    if name in files:
        path = files[name]
    elif str(name).endswith(".toml"):
        path = pathlib.Path(name)
    else:
        raise InputError(f"experiment {name!r} is unknown; choose one of {', '.join(files)} or a .toml path")
    data = parameters.load_toml(path)
    if data.get("format") != FORMAT:
        parameters.fail(path, "format", f"must be {FORMAT!r}, got {data.get('format')!r}")
    conditions = _read(path, "conditions", data.get("conditions"), _CONDITION_UNITS)
    processing = _read(path, "processing", data.get("processing"), _PROCESSING_UNITS)
    riders = {key: _read(path, f"riders.{key}", entry, _RIDER_UNITS)
              for key, entry in parameters.table(path, "riders", data.get("riders")).items()}
    cases = {}
    for key, entry in parameters.table(path, "measured", data.get("measured")).items():
        entry = parameters.table(path, f"measured.{key}", entry)
        missing = [k for k in ("fz_n", "pressure_kpa", "last_peak_number", "last_peak_time", "period")
                   if k not in entry]
        if missing:
            parameters.fail(path, f"measured.{key}", f"missing {', '.join(missing)}")
        values = parameters.quantities(path, f"measured.{key}", entry, _CASE_UNITS, complete=False)[0]
        if key != case_name(values["fz_n"], values["pressure_kpa"]):
            parameters.fail(path, f"measured.{key}",
                            f"name must be {case_name(values['fz_n'], values['pressure_kpa'])!r} (its load and pressure)")
        metrics = {k: v for k, v in values.items() if k in METRICS}
        cases[key] = MeasuredCase(key, values["fz_n"], values["pressure_kpa"], int(values["last_peak_number"]),
                                  metrics, {k: entry[k]["source"] for k in entry})
    variations = {}
    for key, entry in parameters.table(path, "variation", data.get("variation")).items():
        variations[_load_key(path, key)] = parameters.quantities(path, f"variation.{key}", entry, None)[0]
    spectrum = {_load_key(path, key): parameters.quantity(path, f"spectrum.{key}.yaw_rate_local_max",
                                                          parameters.table(path, f"spectrum.{key}", entry).get(
                                                              "yaw_rate_local_max"), "Hz")[0]
                for key, entry in parameters.table(path, "spectrum", data.get("spectrum")).items()}
    best = {_load_key(path, key): _read(path, f"best.{key}", entry, _BEST_UNITS)
            for key, entry in parameters.table(path, "best", data.get("best")).items()}
    notes = data.get("notes", [])
    if not isinstance(notes, list):
        parameters.fail(path, "notes", "must be an array of tables [[notes]]")
    for k, note in enumerate(notes):
        note = parameters.table(path, f"notes[{k}]", note)
        for field in ("where", "printed", "text"):
            parameters.text(path, f"notes[{k}].{field}", note.get(field))
    return Experiment(path, parameters.text(path, "name", data.get("name")),
                      parameters.text(path, "tyre", data.get("tyre")), conditions, processing, riders, cases,
                      variations, spectrum, best, notes)


# ------------------------------------------------------------------ checks of the printed tables

def _ratio_range(a, b, half):
    """Range of 100 (a/b - 1) over a, b within +-half of the printed values."""
    lo_a, hi_a, lo_b, hi_b = a - half, a + half, b - half, b + half
    corners = [100.0 * (x / y - 1.0) for x in (lo_a, hi_a) for y in (lo_b, hi_b) if y > 0]
    return min(corners), max(corners)


def inconsistencies(experiment=None):
    """Where the printed tables contradict themselves.

    Two checks, each allowing for the printing's rounding (a two-decimal value
    stands for anything within +-0.005, a whole per cent within +-0.5 %):

    * every damping ratio against eq. 8.3 applied to its log decrement;
    * every % variation against ``100 (a / b - 1)`` of the two printed values
      it compares (``a`` the table's reference pressure: 300, 400 and
      500 kPa in Tables 8.6, 8.7 and 8.8).

    Returns
    -------
    list of dict
        ``{"kind", "case" or "load", "metric", "printed", "expected_min", "expected_max", "text"}``,
        in table order.
    """
    exp = load() if experiment is None else experiment
    found = []
    for case in exp.cases.values():
        for zeta_key, delta_key in ZETA_OF.items():
            if zeta_key not in case.values:
                continue
            delta, zeta = case.values[delta_key], case.values[zeta_key]
            lo = damping_ratio(delta - PRINT_HALF_STEP)
            hi = damping_ratio(delta + PRINT_HALF_STEP)
            if not lo - PRINT_HALF_STEP <= zeta <= hi + PRINT_HALF_STEP:
                found.append({"kind": "damping_ratio", "case": case.case, "metric": zeta_key, "printed": zeta,
                              "expected_min": lo, "expected_max": hi,
                              "text": f"{case.case}: {zeta_key} printed {zeta:.2f}, but eq. 8.3 of the printed "
                                      f"{delta_key} {delta:.2f} gives {damping_ratio(delta):.3f}"})
    for fz, table in exp.variations.items():
        ref = table["reference_kpa"]
        for key, printed in table.items():
            if key == "reference_kpa":
                continue
            metric, other = key.rsplit("_vs_", 1)
            other = float(other.removesuffix("kPa"))
            a = exp.case(fz, ref).values[metric]
            b = exp.case(fz, other).values[metric]
            lo, hi = _ratio_range(a, b, PRINT_HALF_STEP)
            if not lo - PERCENT_HALF_STEP <= printed <= hi + PERCENT_HALF_STEP:
                found.append({"kind": "variation", "load": fz, "metric": key, "printed": printed,
                              "expected_min": lo, "expected_max": hi,
                              "text": f"{fz:g} N: {metric} {ref:g} vs {other:g} kPa printed {printed:+g} %, but the "
                                      f"printed {a:g} and {b:g} give {100 * (a / b - 1):+.0f} % "
                                      f"({lo:+.0f} to {hi:+.0f} % within their rounding)"})
    return found


def implied_first_peak_times(experiment=None):
    """Time of peak #1 that each case's last-peak time implies if the peaks were evenly spaced [s].

    Peaks alternate in sign, half a period apart, so peak #N comes
    ``(N - 1) T / 2`` after peak #1: ``t1 = last_peak_time - (N - 1) period / 2``
    on the clock of the printed last-peak times. With the kick at t = 0,
    t1 could not be below :data:`FIRST_RESPONSE_S`; near 0 it says the
    printed times run from peak #1.

    Returns
    -------
    dict
        ``{case: t1 [s]}``.
    """
    exp = load() if experiment is None else experiment
    return {c.case: c.values["last_peak_time"] - (c.last_peak_number - 1) * c.values["period"] / 2
            for c in exp.cases.values()}


def best_pressures(experiment=None):
    """Best pressure per load by the measured last-peak time (the rule of Table 8.9) [kPa].

    Returns
    -------
    dict
        ``{load [N]: pressure [kPa]}``.
    """
    exp = load() if experiment is None else experiment
    out = {}
    for fz in exp.loads:
        rows = [c for c in exp.cases.values() if c.fz_n == fz]
        out[fz] = min(rows, key=lambda c: c.values["last_peak_time"]).pressure_kpa
    return out


def mean_reduction(experiment, fz_n):
    """Table 8.9's "% recovery time reduction" recomputed: mean of ``100 (t_best / t_other - 1)`` [%]."""
    exp = experiment
    best = best_pressures(exp)[fz_n]
    t_best = exp.case(fz_n, best).values["last_peak_time"]
    others = [exp.case(fz_n, p).values["last_peak_time"] for p in exp.pressures if p != best]
    return sum(100.0 * (t_best / t - 1.0) for t in others) / len(others)

