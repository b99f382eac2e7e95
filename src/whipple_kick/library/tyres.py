"""The tyre library: measured bicycle tyres as Magic-Formula tyre objects.

Example
-------
>>> import whipple_kick as wk
>>> tyre = wk.tyres.load("T03", pressure_kpa=400)
>>> round(float(tyre.lateral_force(slip=0.02, camber=0.0, fz=600.0)), 1)   # N, model convention
-117.2

Units and signs everywhere in this module: radians, newtons, metres and the
MODEL convention of :mod:`whipple_kick.model.magic_formula` (y right, z down;
slip > 0 = contact sliding right; camber > 0 = top of the wheel leaning right).

Parameter files live in ``parameters/tyres/<name>.toml`` (one per tyre, every
value with unit and source). A pressure between two measured ones blends the
OUTPUTS of the two bracketing measured coefficient sets linearly; see
:attr:`Tyre.blend` for what a simulation must evaluate. docs/tyres.md has the
data's provenance, the friction modes and the known limits of the fits.
"""
import copy
import functools
import math
import pathlib
import warnings

import numpy as np

from whipple_kick.errors import InputError, WhippleKickWarning, check_range
from whipple_kick.model import magic_formula as mf

from . import parameters
from .parameters import fail as _fail
from .parameters import table as _table
from .parameters import text as _text

__all__ = [
    "DEFAULT_COEFFICIENT_SET",
    "FRICTION_MODES",
    "MISSING_MOMENT_MODES",
    "ZERO_MOMENT_COEFFICIENTS",
    "LinearTyre",
    "Tyre",
    "TyreFile",
    "available",
    "linear_tyre",
    "load",
    "read_tyre_file",
]

#: Folder of the shipped tyre files (package data, :func:`whipple_kick.library.parameters.shipped`).
TYRE_DIR = parameters.shipped("tyres")
#: Coefficient set used unless another is asked for (thesis Table 7.9 F_y).
DEFAULT_COEFFICIENT_SET = "table7_9"
#: ``none``: as measured on the rig; ``plate``: D scaled by mu_plate/mu_rig
#: keeping the cornering stiffness; ``thesis``: whole F_y and M_z curves
#: multiplied by the factor the Chapter 8 code used.
FRICTION_MODES = ("none", "plate", "thesis")
#: What ``aligning_moment`` does for a tyre without published M_z data.
MISSING_MOMENT_MODES = ("error", "zero")
#: M_z coefficients whose moment is exactly zero for every input with
#: F_z > 0: C = 1, D = F_z (never 0 while loaded, so B = BCD/(C*D) is defined),
#: BCD = 0 (so B = 0 and sin(C*atan(0)) = 0), all shifts 0. Used by
#: ``missing_moment="zero"`` so the compiled model needs no special case.
ZERO_MOMENT_COEFFICIENTS = np.array([1.0, 0.0, 1.0] + [0.0] * 15)

# Units each entry of a tyre file must declare, and its allowed range.
_FORMULA_UNITS = {"angle_unit": "deg", "load_unit": "kN", "force_unit": "N", "moment_unit": "N m"}
_PRESSURE_QUANTITIES = {  # name: (unit, low, low_open)
    "vertical_stiffness": ("N/m", 0.0, True),
    "vertical_damping": ("N s/m", 0.0, False),
    "relaxation_length": ("m", 0.0, True),
    "crown_radius": ("m", 0.0, False),
}
_FRICTION_QUANTITIES = {
    "mu_plate": ("-", 0.0, True),
    "mu_rig": ("-", 0.0, True),
    "thesis_curve_scale": ("-", 0.0, True),
}
#: The optional ``[measured]`` table: the ranges the fits were measured over (what lies outside is extrapolation).
_MEASURED_QUANTITIES = {
    "slip_deg": ("deg", 0.0, True),
    "load_min": ("N", 0.0, True),
    "load_max": ("N", 0.0, True),
}
_TOP_KEYS = {"name", "description", "size", "source", "warning", "formula", "friction",
             "pressure", "coefficients", "measured"}
_SET_ENTRY_KEYS = {"fy", "fy_source", "mz", "mz_source", "mz_from"}


# ---------------------------------------------------------------------------
# Reading and validating a tyre file.

class TyreFile:
    """The validated contents of one tyre file (all pressures, all sets).

    Attributes
    ----------
    path : pathlib.Path
    name, description, size, warning : str (warning may be None)
    friction : dict of float
        ``mu_plate``, ``mu_rig``, ``thesis_curve_scale``.
    properties : dict
        pressure (kPa, float) -> dict of the per-pressure quantities (SI).
    sets : dict
        set name -> pressure (kPa) -> ``(fy ndarray (14,), mz ndarray (18,) or None)``.
    measured : dict or None
        The ``[measured]`` ranges of the fits (:data:`_MEASURED_QUANTITIES`), None if the file has none.
    """

    def __init__(self, path, name, description, size, warning, friction, properties, sets, measured=None):
        self.path = path
        self.name = name
        self.description = description
        self.size = size
        self.warning = warning
        self.friction = friction
        self.properties = properties
        self.sets = sets
        self.measured = measured


def _quantity(path, key, entry, unit, low, low_open):
    """Read ``{value, unit, source}`` (the source is the citation), checking unit, finiteness and range."""
    return parameters.quantity(path, key, entry, unit, low=low, low_open=low_open)[0]


def _pressure_key(path, key, text):
    """Pressure table keys are pressures in kPa, e.g. ``[pressure.400]``."""
    try:
        value = float(text)
    except ValueError:
        _fail(path, key, f"'{text}' is not a pressure in kPa (expected e.g. 300, 400)")
    if not math.isfinite(value) or value <= 0:
        _fail(path, key, f"pressure {text} kPa must be a finite number > 0 kPa")
    return value


def _coefficient_list(path, key, values, count):
    if not isinstance(values, list):
        _fail(path, key, f"must be a list of {count} numbers, got {values!r}")
    if len(values) != count:
        _fail(path, key, f"must hold {count} coefficients, got {len(values)}")
    array = np.array([parameters.number(path, f"{key}[{i}]", v) for i, v in enumerate(values)])
    array.setflags(write=False)   # shared by every load of the file (read_tyre_file's cache)
    return array


def read_tyre_file(path):
    """Read and validate one tyre file.

    Parsed once per process and content (a sweep loads the same tyre for
    every case; parsing and checking it took ~1.2 ms a load): the file's bytes
    are the cache key, so an edited file is read afresh. The result is
    shared: its coefficient arrays are read-only.

    Raises
    ------
    InputError
        One line naming the file, the key and the problem.
    """
    path = path if isinstance(path, pathlib.Path) else pathlib.Path(path)   # a listing's paths are Paths already
    return _read_tyre_file(path, parameters.file_bytes(path))


@functools.lru_cache(maxsize=64)
def _read_tyre_file(path, content):
    data = parameters.parse_toml(path, content)
    unknown = set(data) - _TOP_KEYS
    if unknown:
        _fail(path, sorted(unknown)[0], f"unknown key; allowed: {', '.join(sorted(_TOP_KEYS))}")
    for key in ("name", "description", "formula", "friction", "pressure", "coefficients"):
        if key not in data:
            _fail(path, key, "missing")
    name = _text(path, "name", data["name"])
    if name != path.stem:
        _fail(path, "name", f"'{name}' must match the file name '{path.stem}'")
    warning = _text(path, "warning", data["warning"]) if "warning" in data else None

    formula = _table(path, "formula", data["formula"])
    for key, unit in _FORMULA_UNITS.items():
        if formula.get(key) != unit:
            _fail(path, f"formula.{key}", f"must be '{unit}' (Pacejka 1989 units), got {formula.get(key)!r}")

    friction_table = _table(path, "friction", data["friction"])
    friction = {key: _quantity(path, f"friction.{key}", friction_table.get(key), *spec)
                for key, spec in _FRICTION_QUANTITIES.items()}

    properties = {}
    for text, entry in _table(path, "pressure", data["pressure"]).items():
        key = f"pressure.{text}"
        pressure = _pressure_key(path, key, text)
        entry = _table(path, key, entry)
        extra = set(entry) - set(_PRESSURE_QUANTITIES)
        if extra:
            _fail(path, f"{key}.{sorted(extra)[0]}", "unknown key")
        properties[pressure] = {q: _quantity(path, f"{key}.{q}", entry.get(q), *spec)
                                for q, spec in _PRESSURE_QUANTITIES.items()}
    if not properties:
        _fail(path, "pressure", "needs at least one pressure table, e.g. [pressure.400]")

    sets = _read_sets(path, _table(path, "coefficients", data["coefficients"]), properties)
    measured = None
    if "measured" in data:
        table = _table(path, "measured", data["measured"])
        extra = set(table) - set(_MEASURED_QUANTITIES)
        if extra:
            _fail(path, f"measured.{sorted(extra)[0]}", f"unknown key; allowed: {', '.join(_MEASURED_QUANTITIES)}")
        measured = {key: _quantity(path, f"measured.{key}", table.get(key), *spec)
                    for key, spec in _MEASURED_QUANTITIES.items()}
        if measured["load_min"] > measured["load_max"]:
            _fail(path, "measured.load_min", f"{measured['load_min']:g} N exceeds load_max "
                                             f"{measured['load_max']:g} N")
    return TyreFile(path, name, _text(path, "description", data["description"]),
                    data.get("size", ""), warning, friction, properties, sets, measured)


def _read_sets(path, table, properties):
    """Coefficient sets: ``[coefficients.<set>.<pressure>]`` with fy and mz."""
    if DEFAULT_COEFFICIENT_SET not in table:
        _fail(path, f"coefficients.{DEFAULT_COEFFICIENT_SET}", "missing (the default coefficient set)")
    raw = {}
    for set_name, set_table in table.items():
        set_table = _table(path, f"coefficients.{set_name}", set_table)
        _text(path, f"coefficients.{set_name}.description", set_table.get("description"))
        raw[set_name] = {}
        for text, entry in set_table.items():
            if text == "description":
                continue
            key = f"coefficients.{set_name}.{text}"
            pressure = _pressure_key(path, key, text)
            if pressure not in properties:
                _fail(path, key, f"no [pressure.{text}] table holds this pressure's properties")
            entry = _table(path, key, entry)
            extra = set(entry) - _SET_ENTRY_KEYS
            if extra:
                _fail(path, f"{key}.{sorted(extra)[0]}", "unknown key")
            if "fy" not in entry:
                _fail(path, f"{key}.fy", "missing")
            _text(path, f"{key}.fy_source", entry.get("fy_source"))
            fy = _coefficient_list(path, f"{key}.fy", entry["fy"], mf.N_FY_COEFFICIENTS)
            if "mz" in entry and "mz_from" in entry:
                _fail(path, key, "give either mz or mz_from, not both")
            mz = None
            if "mz" in entry:
                _text(path, f"{key}.mz_source", entry.get("mz_source"))
                mz = _coefficient_list(path, f"{key}.mz", entry["mz"], mf.N_MZ_COEFFICIENTS)
            raw[set_name][pressure] = (fy, mz, entry.get("mz_from"), key, text)
        if not raw[set_name]:
            _fail(path, f"coefficients.{set_name}", "holds no pressure, e.g. [coefficients.<set>.400]")

    sets = {}
    for set_name, pressures in raw.items():
        sets[set_name] = {}
        for pressure, (fy, mz, mz_from, key, text) in pressures.items():
            if mz_from is not None:
                # M_z borrowed from another set at the same pressure (T03: Chapter 8).
                other = raw.get(mz_from, {}).get(pressure)
                if other is None or other[1] is None:
                    _fail(path, f"{key}.mz_from",
                          f"set '{mz_from}' has no mz coefficients at {text} kPa")
                mz = other[1]
            sets[set_name][pressure] = (fy, mz)
    return sets


def _tyre_files(directory=None):
    return parameters.toml_files(TYRE_DIR if directory is None else directory)


def available(directory=None):
    """List the shipped tyres.

    Returns
    -------
    list of (name, pressures, coefficient_sets)
        ``pressures`` are the measured pressures (kPa) of the default set.
    """
    out = []
    for name, path in _tyre_files(directory).items():
        data = read_tyre_file(path)
        out.append((name, tuple(sorted(data.sets[DEFAULT_COEFFICIENT_SET])), tuple(data.sets)))
    return out


# ---------------------------------------------------------------------------
# The tyre object.

def load(name, pressure_kpa, coefficient_set=DEFAULT_COEFFICIENT_SET, friction="none",
         missing_moment="error", directory=None):
    """Load a tyre at an inflation pressure.

    Parameters
    ----------
    name : str
        Tyre name, e.g. ``"T03"`` (see :func:`available`).
    pressure_kpa : float
        Inflation pressure in kPa, within the measured range of the set;
        between two measured pressures the outputs are blended linearly.
    coefficient_set : str
        ``"table7_9"`` (default) or another set of the file (T03: ``"chapter8"``).
    friction : {"none", "plate", "thesis"}
        See :data:`FRICTION_MODES` and docs/tyres.md.
    missing_moment : {"error", "zero"}
        For tyres without published M_z coefficients: ``"error"`` makes
        :meth:`Tyre.aligning_moment` (and :attr:`Tyre.blend`) raise,
        ``"zero"`` gives an exactly zero aligning moment.
    directory : path-like, optional
        Folder of tyre files (default: the shipped ``parameters/tyres``).
    """
    files = _tyre_files(directory)
    if name not in files:
        raise InputError(f"tyre = {name!r} is unknown; choose one of {', '.join(files) or '(none)'}")
    if friction not in FRICTION_MODES:
        raise InputError(f"friction = {friction!r} is unknown; choose one of {', '.join(FRICTION_MODES)}")
    if missing_moment not in MISSING_MOMENT_MODES:
        raise InputError(f"missing_moment = {missing_moment!r} is unknown; "
                         f"choose one of {', '.join(MISSING_MOMENT_MODES)}")
    data = read_tyre_file(files[name])
    if coefficient_set not in data.sets:
        raise InputError(f"coefficient_set = {coefficient_set!r} does not exist for tyre {name}; "
                         f"choose one of {', '.join(data.sets)}")
    if data.warning:
        warnings.warn(data.warning, DataQualityWarning, stacklevel=2)
    return Tyre(data, pressure_kpa, coefficient_set, friction, missing_moment)


class DataQualityWarning(WhippleKickWarning):
    """A tyre file's own warning about its data (e.g. T02's fit that misses its published factors).

    Issued by :func:`load`; a run's summary lists it under
    ``tyres.data_warnings`` whatever the warning filters, and the command-line
    tools print it once, in one line, instead of Python's warning.
    """


def _bracket(pressure, measured, name, coefficient_set):
    """Weights of the measured pressures bracketing ``pressure`` (kPa)."""
    measured = sorted(measured)
    p = check_range(f"pressure of tyre {name} ({coefficient_set})", pressure,
                    measured[0], measured[-1], "kPa")
    if p in measured:
        return [(1.0, p)]
    hi = next(m for m in measured if m > p)
    lo = measured[measured.index(hi) - 1]
    w_hi = (p - lo) / (hi - lo)
    return [(1.0 - w_hi, lo), (w_hi, hi)]


class Tyre:
    """One tyre at one inflation pressure, as the simulation uses it.

    Attributes
    ----------
    name, description : str
    pressure_kpa : float
    coefficient_set : str
    friction : str
        The friction mode (``none``, ``plate`` or ``thesis``).
    vertical_stiffness : float
        N/m (linear in pressure between measured pressures).
    vertical_damping : float
        N s/m.
    relaxation_length : float
        m.
    crown_radius : float
        m, radius of the tyre's cross-section (toroidal tyre).
    friction_ratio : float
        mu_plate/mu_rig (thesis Table 8.5), whatever the friction mode.
    friction_scale : float
        ``k`` passed to the ``*_model`` builders: friction_ratio in ``plate``
        mode, else 1.
    curve_scale : float
        Factor on the whole F_y and M_z: the Chapter 8 factor in ``thesis``
        mode, else 1.
    has_aligning_moment : bool
        Whether published M_z coefficients exist for this tyre.
    data_warning : str or None
        The tyre file's warning about its data.
    measured : dict or None
        The ranges the fits were measured over, from the file's ``[measured]``
        table: ``slip_deg`` (``|slip|``, deg), ``load_min``, ``load_max`` (N).
    """

    def __init__(self, data, pressure_kpa, coefficient_set, friction, missing_moment):
        self.name = data.name
        self.description = data.description
        self.coefficient_set = coefficient_set
        self.friction = friction
        self.missing_moment = missing_moment
        self.data_warning = data.warning
        coefficients = data.sets[coefficient_set]
        self._weights = _bracket(pressure_kpa, coefficients, data.name, coefficient_set)
        self.pressure_kpa = float(pressure_kpa)
        self.measured_pressures = tuple(sorted(coefficients))
        for quantity in _PRESSURE_QUANTITIES:
            value = sum(w * data.properties[p][quantity] for w, p in self._weights)
            setattr(self, quantity, value)
        self.mu_plate = data.friction["mu_plate"]
        self.mu_rig = data.friction["mu_rig"]
        self.friction_ratio = self.mu_plate / self.mu_rig
        self.friction_scale = self.friction_ratio if friction == "plate" else 1.0
        self.curve_scale = data.friction["thesis_curve_scale"] if friction == "thesis" else 1.0
        self._sets = [(w, coefficients[p][0], coefficients[p][1]) for w, p in self._weights]
        self.has_aligning_moment = all(mz is not None for _, _, mz in self._sets)
        #: Measured ranges of the fits (``slip_deg``, ``load_min``, ``load_max``; deg, N), or None.
        self.measured = data.measured

    def __repr__(self):
        return (f"Tyre({self.name!r}, pressure_kpa={self.pressure_kpa:g}, "
                f"coefficient_set={self.coefficient_set!r}, friction={self.friction!r})")

    @property
    def blend(self):
        """``[(weight, fy (14,), mz (18,)), ...]``: what the simulation evaluates.

        One entry (weight 1) at a measured pressure, two between measured
        ones. The tyre's outputs are::

            F_y = curve_scale * sum(w * lateral_force_model(slip, camber, F_z, fy, friction_scale))
            M_z = curve_scale * sum(w * aligning_moment_model(slip, camber, F_z, mz, friction_scale))
        """
        return [(w, fy.copy(), self._moment_coefficients(mz).copy()) for w, fy, mz in self._sets]

    def _moment_coefficients(self, mz):
        if mz is not None:
            return mz
        if self.missing_moment == "zero":
            return ZERO_MOMENT_COEFFICIENTS
        raise InputError(f"tyre {self.name} has no measured aligning-moment (M_z) coefficients "
                         f"(the thesis publishes M_z fits for T03 only); load it with "
                         f"missing_moment='zero' to use a zero aligning moment")

    def without_offsets(self):
        """A copy with the zero-slip offsets zeroed (as ``symmetric_tyres`` runs use it).

        Example
        -------
        >>> import whipple_kick as wk
        >>> float(wk.tyres.load("T03", 400).without_offsets().lateral_force(0.0, 0.0, 600.0))
        0.0
        """
        twin = copy.copy(self)
        twin._sets = []
        for w, fy, mz in self._sets:
            fy = fy.copy()
            fy[list(mf.FY_OFFSET_INDICES)] = 0.0
            if mz is not None:
                mz = mz.copy()
                mz[list(mf.MZ_OFFSET_INDICES)] = 0.0
            twin._sets.append((w, fy, mz))
        return twin

    # -- symbolic -------------------------------------------------------------

    def lateral_force_expression(self, slip, camber, fz):
        """SymPy expression of :meth:`lateral_force` (numbers for coefficients)."""
        return self.curve_scale * sum(
            w * mf.lateral_force_model(slip, camber, fz, fy, self.friction_scale)
            for w, fy, _ in self._sets)

    def aligning_moment_expression(self, slip, camber, fz):
        """SymPy expression of :meth:`aligning_moment`."""
        return self.curve_scale * sum(
            w * mf.aligning_moment_model(slip, camber, fz, mz, self.friction_scale)
            for w, _, mz in self.blend)

    # -- numeric --------------------------------------------------------------

    def lateral_force(self, slip, camber, fz):
        """Lateral force F_y in N (model convention, + = right).

        Parameters
        ----------
        slip : array_like
            Slip angle in rad (+ = contact sliding right).
        camber : array_like
            Camber angle in rad (+ = top of the wheel leaning right).
        fz : array_like
            Normal force in N; ``fz <= 0`` gives exactly 0.
        """
        slip, camber, fz = _finite_inputs(slip, camber, fz)
        return self.curve_scale * sum(
            w * mf.lateral_force_numpy(slip, camber, fz, fy, self.friction_scale)
            for w, fy, _ in self._sets)

    def aligning_moment(self, slip, camber, fz):
        """Aligning moment M_z in N m about the downward normal (+ turns the heading right)."""
        slip, camber, fz = _finite_inputs(slip, camber, fz)
        return self.curve_scale * sum(
            w * mf.aligning_moment_numpy(slip, camber, fz, mz, self.friction_scale)
            for w, _, mz in self.blend)

    def cornering_stiffness(self, fz):
        """Cornering stiffness at zero slip and camber, N/rad, positive.

        ``-dF_y/dslip``: in the model convention the force opposes the slip,
        so the slope is negative; the magnitude is returned, as the thesis'
        Tables 7.2-7.7 do (there in N/deg). 0 for ``fz = 0``.
        """
        fz = _load(fz, "normal load fz", 0.0, low_open=False)
        return self.curve_scale * sum(
            w * mf.cornering_stiffness_numpy(fz, fy, self.friction_scale)
            for w, fy, _ in self._sets)

    def secant_ratio(self, slip, fz):
        """Secant ratio of the pure-slip lateral-force curve [-] (blended like the force).

        ``g = F_sym(slip) / (C0 slip)`` with F_sym the curve at zero camber
        without its zero-slip offsets and C0 its slope at zero: 1 at zero
        slip, falling as the force saturates (:func:`magic_formula.lateral_secant_model`).
        The contact-patch transient's relaxation length is the tyre's
        ``relaxation_length`` times this (floored, :data:`whipple_kick.model.transient.G_MIN`).

        Parameters
        ----------
        slip : array_like
            Slip angle [rad].
        fz : array_like
            Normal load [N], > 0 (a shape: independent of the curve scale).
        """
        slip, _, fz = _finite_inputs(slip, 0.0, fz)
        fz = _load(fz, "normal load fz", 0.0, low_open=True)
        num = den = 0.0
        for w, fy, _ in self._sets:
            slope, ratio = mf.lateral_secant_numpy(slip, fz, fy, self.friction_scale)
            num = num + w * slope * ratio
            den = den + w * slope
        return num / den

    def magic_formula_factors(self, fz, camber=0.0):
        """Magic Formula factors of F_y in the formula's units, at a measured pressure.

        Parameters
        ----------
        fz : array_like
            Normal load in N, > 0.
        camber : array_like
            Camber in rad, model convention (mapped to the formula's gamma).

        Returns
        -------
        dict
            ``B`` (1/deg), ``C``, ``D`` (N), ``E``, ``Sh`` (deg), ``Sv`` (N),
            with the friction mode applied (``plate``: D*k, B/k; ``thesis``:
            D and Sv times the curve scale).
        """
        if len(self._sets) != 1:
            raise InputError(f"pressure = {self.pressure_kpa:g} kPa is between measured pressures; "
                             f"Magic Formula factors exist only at {self.measured_pressures} kPa")
        fz = _load(fz, "normal load fz", 0.0, low_open=True)
        camber = np.asarray(_finite("camber", camber, "rad"), dtype=float)
        factors = mf.lateral_force_factors_numpy(camber, fz, self._sets[0][1], self.friction_scale)
        factors["D"] = factors["D"] * self.curve_scale
        factors["Sv"] = factors["Sv"] * self.curve_scale
        return factors


class LinearTyre:
    """A tyre that is linear in slip and has no camber force or moment.

    ``F_y = -cornering_coefficient * F_z * slip`` over any slip a simulation
    reaches, written as a Magic Formula with a huge peak factor so the slip
    model evaluates it unchanged. Made for checks against the no-slip
    (knife-edge) model: as the coefficient and the vertical stiffness grow
    and the relaxation length shrinks, the slip model approaches it. It has
    no friction limit: under large slip (the thesis kick's instant plate
    stop) the contact-patch transient's force follows load spikes at once
    and reaches tens of kN; use small kicks, or ``tyre_transient="force_lag"``,
    for no-slip-limit checks.

    Attributes match those of :class:`Tyre` that the slip model reads.
    """

    def __init__(self, cornering_coefficient, relaxation_length, vertical_stiffness,
                 vertical_damping=None):
        self.cornering_coefficient = check_range("cornering coefficient", cornering_coefficient,
                                                 0.0, None, "1/rad", low_open=True)
        self.relaxation_length = check_range("relaxation length", relaxation_length, 0.0, None, "m",
                                             low_open=True)
        self.vertical_stiffness = check_range("vertical stiffness", vertical_stiffness, 0.0, None, "N/m",
                                              low_open=True)
        if vertical_damping is None:
            # About 0.1 of critical damping for a 50 kg share of the mass (no ringing, little loss).
            vertical_damping = math.sqrt(self.vertical_stiffness * 50.0)
        self.vertical_damping = check_range("vertical damping", vertical_damping, 0.0, None, "N s/m")
        self.name = f"linear({self.cornering_coefficient:g}/rad)"
        self.description = "linear cornering force, no camber force, no aligning moment"
        self.pressure_kpa = None
        self.crown_radius = 0.0
        self.friction_scale = 1.0
        self.curve_scale = 1.0
        self.has_aligning_moment = False
        # Pacejka 1989 F_y in the formula's units (deg, kN, N):
        # BCD = a3 sin(2 atan(Fz/a4)) = 2 a3 Fz/a4 to 1e-8 for Fz << a4, and
        # with C = 1 and D = a2 Fz huge, F = BCD * slip(deg) exactly enough.
        a4 = 1e4
        fy = np.zeros(14)
        fy[0], fy[2], fy[4] = 1.0, 1e8, a4
        fy[3] = self.cornering_coefficient * 1000.0 * math.pi / 180.0 * a4 / 2.0
        self.blend = [(1.0, fy, ZERO_MOMENT_COEFFICIENTS.copy())]

    def __repr__(self):
        return (f"LinearTyre({self.cornering_coefficient:g}/rad, relaxation {self.relaxation_length:g} m, "
                f"kz {self.vertical_stiffness:g} N/m)")


def linear_tyre(cornering_coefficient, relaxation_length, vertical_stiffness, vertical_damping=None):
    """A :class:`LinearTyre` (cornering coefficient [1/rad], relaxation length [m], stiffness [N/m])."""
    return LinearTyre(cornering_coefficient, relaxation_length, vertical_stiffness, vertical_damping)


def _finite(name, values, unit):
    values = np.asarray(values, dtype=float)
    bad = ~np.isfinite(values)
    if bad.any():
        check_range(name, float(values[bad].flat[0]), None, None, unit)
    return values


def _finite_inputs(slip, camber, fz):
    return _finite("slip", slip, "rad"), _finite("camber", camber, "rad"), _finite("fz", fz, "N")


def _load(fz, name, low, low_open):
    fz = _finite(name, fz, "N")
    bad = (fz <= low) if low_open else (fz < low)
    if bad.any():
        check_range(name, float(fz[bad].flat[0]), low, None, "N", low_open=low_open)
    return fz
