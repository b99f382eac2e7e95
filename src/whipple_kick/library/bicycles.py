"""Bicycle parameter sets: loading the shipped files and the :class:`Bicycle` mapping.

A bicycle file (``parameters/bicycles/<name>.toml``) holds one parameter set
in either of two parameterisations of the Carvallo-Whipple bicycle, stated in
the file's ``parameterisation`` entry:

* ``"benchmark"``: Meijaard et al. (2007) names (``w, c, lam, ..., IFyy``);
* ``"moore"``: Moore (2012) names (``d1, d2, d3, l1..l4, ..., g``).

Every parameter is an inline table ``{value, unit, source[, uncertainty]}``
whose ``source`` names an entry of the file's ``[sources]`` table. Optional
tables: ``[seating]`` (the geometry needed to seat a rider, see
:mod:`whipple_kick.library.riders`) and ``[tyre_placeholders]`` (the linear-tyre
entries of the authors' sets, kept as metadata only).

Whatever the file's form, :func:`load` returns a :class:`Bicycle`: a mapping
of Moore's parameters (what the equations of motion use) that also carries
the benchmark form and the file's metadata.
"""
from collections.abc import Mapping
import math
import types

from whipple_kick.errors import InputError
from whipple_kick.model import benchmark as _benchmark

from . import parameters

#: Folder of the shipped bicycle files (package data, :func:`whipple_kick.library.parameters.shipped`).
BICYCLE_DIR = parameters.shipped("bicycles")

FORMAT = "whipple_kick bicycle, version 1"

_LENGTH, _ANGLE, _MASS, _INERTIA, _ACCEL = "m", "rad", "kg", "kg m^2", "m/s^2"

#: Unit required for each parameter, per parameterisation.
BENCHMARK_UNITS = {
    name: (_ACCEL if name == "g" else _ANGLE if name == "lam"
           else _MASS if name.startswith("m") else _INERTIA if name.startswith("I")
           else _LENGTH)
    for name in _benchmark.BENCHMARK_NAMES
}
MOORE_UNITS = {
    name: (_ACCEL if name == "g" else _MASS if name.startswith("m")
           else _INERTIA if name.startswith("i") else _LENGTH)
    for name in _benchmark.MOORE_NAMES
}

#: Seating geometry (names of Moore's BicycleParameters measurements) and units.
SEATING_UNITS = {
    "lcs": _LENGTH,    # chain stay: rear wheel centre to bottom bracket
    "hbb": _LENGTH,    # bottom-bracket height above the ground
    "lst": _LENGTH,    # seat-tube length
    "lsp": _LENGTH,    # seat-post length
    "lamst": _ANGLE,   # seat-tube angle above the horizontal
    "whb": _LENGTH,    # handlebar width between the grips
    "LhbR": _LENGTH,   # rear wheel centre to a grip
    "LhbF": _LENGTH,   # front wheel centre to a grip
}

_TOP_KEYS = {"format", "name", "parameterisation", "includes_rider", "description",
             "thesis_rear_load", "sources", "parameters", "seating", "tyre_placeholders"}


class Bicycle(Mapping):
    """One bicycle parameter set: a read-only mapping of Moore's parameters.

    ``bike["d1"]`` etc. are Moore (2012) parameters in SI units. Metadata:

    Attributes
    ----------
    name : str
        Name of the set (the file name without ``.toml`` for shipped files).
    benchmark : Mapping
        The same set in Meijaard et al. (2007) benchmark form.
    moore : Mapping
        Moore's parameters (the mapping itself, as a separate view).
    uncertainties : Mapping
        Measurement uncertainty per parameter name of the file's
        parameterisation, same units (empty when the source gives none).
    geometry : Mapping or None
        Seating geometry (:data:`SEATING_UNITS`) when present, else None.
    source : str
        The file's sources, one per line (``key: citation``).
    includes_rider : bool
        True when a rider is already lumped into the rear frame.
    parameterisation : str
        ``"benchmark"`` or ``"moore"``: the form the values were given in.
    tyre_placeholders : Mapping
        The authors' linear-tyre placeholder entries, if the file has them
        (metadata only; not used by whipple_kick's tyre models).
    description : str
        One-line description.
    rider : Mapping or None
        For a bicycle built by :func:`whipple_kick.library.riders.seat`: the rider's
        name, mass [kg], height [m] and its own benchmark-form inertia.
    thesis_rear_load_n : float or None
        For the authors' presets with rider: the rear-tyre load [N] the set
        is labelled with (thesis Table 8.3), which selects the Table 8.4
        gains; None otherwise.
    defaults : Mapping
        What the set's source lacks and was taken from a default: name ->
        (value or None, source). Empty for the shipped sets; see
        :mod:`whipple_kick.library.bicycleparameters`.
    """

    def __init__(self, *, name, benchmark=None, moore=None, parameterisation,
                 includes_rider, source, description="", uncertainties=None,
                 geometry=None, tyre_placeholders=None, rider=None, thesis_rear_load_n=None, defaults=None):
        if (benchmark is None) == (moore is None):
            raise InputError(f"bicycle {name!r}: give exactly one of benchmark or moore parameters")
        if benchmark is not None:
            bench = {k: float(benchmark[k]) for k in _benchmark.BENCHMARK_NAMES
                     if k in benchmark}
            moore_dict = _benchmark.to_moore(bench)
        else:
            moore_dict = {k: float(moore[k]) for k in _benchmark.MOORE_NAMES if k in moore}
            bench = _benchmark.from_moore(moore_dict)
        self.name = str(name)
        self.parameterisation = str(parameterisation)
        self.includes_rider = bool(includes_rider)
        self.source = str(source)
        self.description = str(description)
        self._moore = moore_dict
        self.moore = types.MappingProxyType(moore_dict)
        self.benchmark = types.MappingProxyType(bench)
        self.uncertainties = types.MappingProxyType(dict(uncertainties or {}))
        self.geometry = None if geometry is None else types.MappingProxyType(dict(geometry))
        self.tyre_placeholders = types.MappingProxyType(dict(tyre_placeholders or {}))
        self.rider = None if rider is None else types.MappingProxyType(dict(rider))
        self.thesis_rear_load_n = None if thesis_rear_load_n is None else float(thesis_rear_load_n)
        self.defaults = types.MappingProxyType(dict(defaults or {}))

    def __getitem__(self, key):
        return self._moore[key]

    def __iter__(self):
        return iter(self._moore)

    def __len__(self):
        return len(self._moore)

    def __repr__(self):
        rider = ", with rider" if self.includes_rider else ""
        return f"<Bicycle {self.name!r} ({self.parameterisation} file{rider})>"


def available():
    """Names of the shipped bicycle parameter sets, sorted.

    Returns
    -------
    list of str
        Names accepted by :func:`load`.
    """
    return list(parameters.toml_files(BICYCLE_DIR))


def load(name):
    """Load a bicycle parameter set by name or from a path.

    Parameters
    ----------
    name : str or os.PathLike
        A shipped set (see :func:`available`), or the path of a ``.toml``
        file in the same format. (A scenario's bicycle may also be a
        BicycleParameters folder: :func:`whipple_kick.library.bicycleparameters.load_bicycle`
        reads either.)

    Returns
    -------
    Bicycle
        Moore-parameter mapping with the benchmark form and metadata.

    Raises
    ------
    InputError
        Unknown name, or a malformed file (naming file, key and problem).
    """
    text = str(name)
    if text.endswith(".toml") or "/" in text or "\\" in text:
        path = text
    else:
        names = available()
        if text not in names:
            raise InputError(f"unknown bicycle {text!r}; available: {', '.join(names)}")
        path = BICYCLE_DIR / f"{text}.toml"
    return _parse(path, parameters.load_toml(path))


#: Plausible range [m] of each geometry length of a bicycle, refused outside (:func:`check_benchmark`). The measured
#: bicycles BicycleParameters ships (its app data: Benchmark, Browser, Browserins, Crescendo, Fisher, Pista,
#: Silver, Yellow, Yellowrev) and the project's sets (parameters/bicycles/) span w 0.985-1.121 m, c 0.042-0.190 m,
#: rR 0.300-0.350 m, rF 0.330-0.352 m (Meijaard et al. 2007's benchmark: w 1.02, c 0.08, rR 0.3, rF 0.35 m).
#: The bounds widen that spread by judgement, not by a survey: to a child's or a folding bicycle's small wheels and
#: short wheelbase and a long cargo bicycle's wheelbase, and to a small negative trail (Kooijman et al. 2011,
#: Science 332:339, built a self-stable bicycle with one), while a length given in the wrong unit (mm or cm read
#: as m) or a trail of metres is refused (tests/library/test_bicycles.py keeps every set above inside).
GEOMETRY_RANGES = {"w": (0.5, 2.5), "c": (-0.2, 0.5), "rR": (0.1, 0.6), "rF": (0.1, 0.6)}
_GEOMETRY_NAMES = {"w": "wheelbase", "c": "trail", "rR": "rear wheel radius", "rF": "front wheel radius"}


def check_benchmark(path, bench):
    """Physical sanity of a benchmark-form set; raise InputError naming the key.

    Masses, radii, wheelbase, g and the principal inertias must be positive;
    wheelbase, trail and wheel radii must lie in their plausible ranges
    (:data:`GEOMETRY_RANGES`); the steer-axis tilt must lie in (-pi/2, pi/2)
    rad; each planar inertia tensor [[Ixx, Ixz], [Ixz, Izz]] must be positive
    definite.
    """
    parameters.positive(path, bench, ("w", "g", "rR", "rF", "mR", "mB", "mH", "mF",
                                      "IRxx", "IRyy", "IFxx", "IFyy", "IBxx", "IByy", "IBzz",
                                      "IHxx", "IHyy", "IHzz"), BENCHMARK_UNITS)
    for key, (low, high) in GEOMETRY_RANGES.items():
        if not low <= bench[key] <= high:
            parameters.fail(path, key, f"{_GEOMETRY_NAMES[key]} {bench[key]!r} m is outside the plausible range "
                                       f"[{low:g}, {high:g}] m of a bicycle (bicycles.GEOMETRY_RANGES)")
    if not abs(bench["lam"]) < math.pi / 2:
        parameters.fail(path, "lam", f"value {bench['lam']!r} rad is outside (-pi/2, pi/2) rad")
    for body in ("B", "H"):
        ixx, izz, ixz = bench[f"I{body}xx"], bench[f"I{body}zz"], bench[f"I{body}xz"]
        if not ixx * izz > ixz * ixz:
            parameters.fail(path, f"I{body}xz", f"value {ixz!r} kg m^2 makes the {body} inertia tensor indefinite "
                            f"(need I{body}xz^2 < I{body}xx*I{body}zz = {ixx * izz:g} kg^2 m^4)")


def _parse(path, data):
    """Build a :class:`Bicycle` from a parsed TOML file, validating everything."""
    unknown = sorted(set(data) - _TOP_KEYS)
    if unknown:
        parameters.fail(path, unknown[0], f"unknown top-level key; allowed: {', '.join(sorted(_TOP_KEYS))}")
    for key in ("format", "name", "parameterisation", "includes_rider", "sources", "parameters"):
        if key not in data:
            parameters.fail(path, key, "missing")
    if data["format"] != FORMAT:
        parameters.fail(path, "format", f"must be {FORMAT!r}, got {data['format']!r}")
    form = data["parameterisation"]
    if form not in ("benchmark", "moore"):
        parameters.fail(path, "parameterisation", f"must be 'benchmark' or 'moore', got {form!r}")
    if not isinstance(data["includes_rider"], bool):
        parameters.fail(path, "includes_rider", f"must be true or false, got {data['includes_rider']!r}")
    sources = data["sources"]
    if not isinstance(sources, dict) or not sources or not all(
            isinstance(v, str) and v for v in sources.values()):
        parameters.fail(path, "sources", "must map keys to non-empty citation strings")

    units = BENCHMARK_UNITS if form == "benchmark" else MOORE_UNITS
    values, unc = parameters.quantities(path, "parameters", data["parameters"], units, sources=sources,
                                        uncertainty=True)
    geometry = None
    if "seating" in data:
        geometry, geo_unc = parameters.quantities(path, "seating", data["seating"], SEATING_UNITS,
                                                  sources=sources, uncertainty=True)
        parameters.positive(path, geometry, SEATING_UNITS, SEATING_UNITS)
        unc.update({f"seating.{k}": v for k, v in geo_unc.items()})
    label = None
    if "thesis_rear_load" in data:
        if not data["includes_rider"]:
            parameters.fail(path, "thesis_rear_load", "labels a set that includes its rider; "
                            "this set has includes_rider = false")
        label = parameters.quantity(path, "thesis_rear_load", data["thesis_rear_load"], "N", sources=sources,
                                    low=0.0, low_open=True)[0]
    tyres = None
    if "tyre_placeholders" in data:
        tyres, _ = parameters.quantities(path, "tyre_placeholders", data["tyre_placeholders"], None,
                                         sources=sources, complete=False, uncertainty=True)

    if form == "benchmark":
        bench = values
    else:
        parameters.positive(path, values, ("g", "rf", "rr", "mc", "md", "me", "mf", "id11", "id22",
                                           "if11", "if22", "ic22", "ie22"), MOORE_UNITS)
        try:
            bench = _benchmark.from_moore(values)
        except ValueError:  # acos outside [-1, 1]: no upright pose with both wheels down
            bench = None
        if bench is None:
            parameters.fail(path, "parameters", "d1, d2, d3, rr, rf admit no upright configuration with "
                                                "both wheels on the ground")
    check_benchmark(path, bench)
    return Bicycle(
        name=data["name"],
        benchmark=values if form == "benchmark" else None,
        moore=values if form == "moore" else None,
        parameterisation=form,
        includes_rider=data["includes_rider"],
        source="\n".join(f"{k}: {v}" for k, v in sources.items()),
        description=data.get("description", ""),
        uncertainties=unc,
        geometry=geometry,
        tyre_placeholders=tyres,
        thesis_rear_load_n=label,
    )
