"""Bicycles and riders from Moore's BicycleParameters: its data folders and its Python objects.

BicycleParameters (J. K. Moore, github.com/moorepants/BicycleParameters) keeps
the measured bicycles of the Davis and Delft labs in a data folder::

    <data>/bicycles/<Name>/Parameters/<Name>Benchmark.txt   benchmark parameters, "name = value+/-std"
    <data>/bicycles/<Name>/RawData/<Name>Measured.txt       raw measurements (the rider-seating lengths among them)
    <data>/riders/<Rider>/Parameters/<Rider><Name>Benchmark.txt   the seated rider alone (mB, xB, yB, zB, IB..)
    <data>/riders/<Rider>/RawData/<Rider>YeadonMeas.txt           the rider's 95 Yeadon measurements
    <data>/riders/<Rider>/RawData/<Rider><Name>YeadonCFG.txt      the rider's joint angles on that bicycle

:func:`load` reads a bicycle folder or its ``Benchmark.txt`` into the
project's :class:`~whipple_kick.library.bicycles.Bicycle`, keeping the
standard deviation of every value (``bike.uncertainties``; nominal and
standard deviation together from :func:`parameter_uncertainties`).
:func:`from_bicycleparameters` takes a ``bicycleparameters.Bicycle`` or one
of its parameter-set objects directly; :func:`yeadon_rider` reads a rider's
Yeadon files into a :class:`~whipple_kick.library.riders.YeadonRider` that
:func:`whipple_kick.library.riders.seat` seats.

What the slip model needs and BicycleParameters does not hold is taken from a
default with its source, listed in ``bike.defaults`` (name -> (value, source))
and warned about once (:data:`DEFAULT_SOURCES`):

* the tyres (crown radius, stiffnesses, Magic Formula): BicycleParameters
  models knife-edge wheels; the project's tyre files (``--tyre``) give them, as
  for every bicycle. ``rR`` and ``rF`` (measured there from the distance the
  loaded wheel rolls) are taken as the radii to the tyre's crown, as for the
  shipped ``balanceassist_v1``;
* the seating geometry (``lcs, hbb, lst, lsp, lamst, whb, LhbR, LhbF``) when the
  folder has no ``RawData/<Name>Measured.txt`` holding it: the measured
  seating of ``balanceassist_v1`` (its file's ``bp_measured`` source).

The Benchmark.txt values are SI (lengths m, angle rad, masses kg, inertias
kg m^2, g m/s^2), as BicycleParameters writes them; a name whose unit is not
known here is refused, not guessed.
"""
from collections.abc import Mapping
import math
import pathlib
import re
import warnings

import numpy as np
import yaml

from whipple_kick.errors import DefaultValueWarning, InputError
from whipple_kick.model import benchmark as _benchmark
from whipple_kick.model import parts

from . import bicycles, parameters, riders
from .riders import MAX_RIDER_MASS_KG, MIN_RIDER_MASS_KG, NO_RIDER

#: The benchmark file of a bicycle (and of a rider on a bicycle) ends so.
BENCHMARK_SUFFIX = "Benchmark.txt"
#: Raw-measurement file of a bicycle: only the seating lengths are read from it (the rest were
#: BicycleParameters' inputs to the Benchmark.txt it computed, which is read instead).
MEASURED_SUFFIX = "Measured.txt"
#: Rider-alone benchmark entries of ``riders/<Rider>/Parameters/<Rider><Name>Benchmark.txt`` and their units.
RIDER_UNITS = {"mB": "kg", "xB": "m", "yB": "m", "zB": "m",
               "IBxx": "kg m^2", "IByy": "kg m^2", "IBzz": "kg m^2", "IBxz": "kg m^2"}
#: Entries some Benchmark.txt files add beyond the 26 benchmark names (Silver's), with their unit: each is
#: checked against what the Whipple model assumes (bodies in the mid-plane, axisymmetric wheels), not ignored.
EXTRA_UNITS = {"yB": "m", "yH": "m", "IRzz": "kg m^2", "IFzz": "kg m^2"}
#: First line of a Benchmark.txt whose rear frame holds a rider already (a comment to BicycleParameters).
RIDER_MARK = "# whipple_kick: includes_rider = true"
#: The shipped set whose measured seating geometry is the default for a bicycle without one.
DEFAULT_SEATING_BICYCLE = "balanceassist_v1"
#: Source of each kind of default value a BicycleParameters bicycle takes (see the module docstring).
DEFAULT_SOURCES = {
    "tyres": "BicycleParameters has knife-edge wheels: the tyre (crown radius, stiffnesses, Magic Formula) "
             "comes from the tyre file chosen for the run (--tyre, parameters/tyres/); rR and rF are taken "
             "as the radii to the tyre crown",
    "seating": f"seating geometry of the shipped '{DEFAULT_SEATING_BICYCLE}' (its [seating] table, measured on "
               "the TU Delft balance-assist bicycle, BicycleParameters' Balanceassistv1Measured.txt)",
}

_NUMBER = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?"
_VALUE = re.compile(rf"^(?P<nominal>{_NUMBER})(?:\s*\+/-\s*(?P<std>{_NUMBER}))?$")


def _units_text(unit):
    return unit or "-"


def read_text(path, units, *, keep=None):
    """Read one BicycleParameters text file: ``name = value`` or ``name = value+/-std`` per line.

    Parameters
    ----------
    path : path-like
        The file.
    units : Mapping or None
        Unit of each name the file may hold; a name not in it is refused
        (its unit cannot be known). None: any name (only ``keep`` is checked).
    keep : collection of str, optional
        Names to return (default all); the other lines are checked for form only.

    Returns
    -------
    values, stds, lines : dict, dict, dict
        Nominal value, standard deviation and line number of each kept name (std 0.0 where
        the file gives none); a comma-separated list of readings is averaged,
        as BicycleParameters averages it.

    Raises
    ------
    InputError
        One line ``<file>:<line>: <problem>``: a line without ``=``, a value
        that is not a number or has a malformed ``+/-``, a repeated or
        unknown name.
    """
    path = pathlib.Path(path)
    try:
        text = path.read_text()
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"{path}: cannot be read as a BicycleParameters text file ({exc})") from None
    values, stds, lines = {}, {}, {}
    for number, raw in enumerate(text.splitlines(), start=1):
        line = raw.split("#", 1)[0].strip()
        if not line:
            continue
        where = f"{path}:{number}"
        name, sep, value = (part.strip() for part in line.partition("="))
        if not sep or not name:
            raise InputError(f"{where}: expected 'name = value' or 'name = value+/-std', got {raw.strip()!r}")
        if units is not None and name not in units:
            raise InputError(f"{where}: unknown parameter {name!r}, so its unit cannot be known "
                             f"(expected one of {', '.join(units)})")
        if name in lines:
            raise InputError(f"{where}: {name!r} is given again (first on line {lines[name]})")
        lines[name] = number
        items = [v.strip() for v in value.split(",")]
        unit = _units_text(units.get(name) if units is not None else None)
        parsed = []
        for item in items:
            match = _VALUE.match(item)
            if match is None:
                problem = ("malformed '+/-' (expected value+/-std, both plain numbers)" if "+/-" in item
                           or "+-" in item or "\u00b1" in item else "not a plain number (BicycleParameters "
                           "values are SI numbers without a unit)")
                raise InputError(f"{where}: {name} = {item!r}: {problem}, in {unit}")
            nominal, std = float(match["nominal"]), float(match["std"] or 0.0)
            if not (math.isfinite(nominal) and math.isfinite(std)) or std < 0.0:
                raise InputError(f"{where}: {name} = {item!r}: the value must be finite and the standard "
                                 f"deviation finite and >= 0 {unit}")
            parsed.append((nominal, std))
        if keep is not None and name not in keep:
            continue
        # Repeated readings are averaged, as BicycleParameters does (independent errors: std / sqrt-sum rule).
        values[name] = sum(p[0] for p in parsed) / len(parsed)
        stds[name] = math.sqrt(sum(p[1] ** 2 for p in parsed)) / len(parsed)
    return values, stds, {k: lines[k] for k in values}


def _check_extras(path, values, stds, lines):
    """Refuse :data:`EXTRA_UNITS` entries that contradict the Whipple model, then drop them (they add nothing)."""
    for name in ("yB", "yH"):
        if values.get(name, 0.0) != 0.0:
            raise InputError(f"{path}:{lines[name]}: {name} = {values[name]!r} m: the Whipple model's bodies lie "
                             "in the mid-plane (y = 0 m)")
    for wheel in ("R", "F"):
        zz, xx = f"I{wheel}zz", f"I{wheel}xx"
        if zz in values and abs(values[zz] - values[xx]) > stds[zz] + stds[xx] + 1e-12 * abs(values[xx]):
            raise InputError(f"{path}:{lines[zz]}: {zz} = {values[zz]!r} kg m^2 differs from {xx} = {values[xx]!r} kg m^2 "
                             "beyond their standard deviations: the Whipple model's wheels are axisymmetric")
    for name in EXTRA_UNITS:
        values.pop(name, None)
        stds.pop(name, None)


def _missing(path, values, names):
    missing = [n for n in names if n not in values]
    if missing:
        raise InputError(f"{path}: missing parameter{'s' if len(missing) > 1 else ''} {', '.join(missing)}")


def _bicycle_files(path):
    """(name, Benchmark.txt, Measured.txt or None, data folder or None) of a bicycle folder or file."""
    path = pathlib.Path(path)
    if path.is_file():
        if not path.name.endswith(BENCHMARK_SUFFIX) or path.name == BENCHMARK_SUFFIX:
            raise InputError(f"{path}: a BicycleParameters bicycle file is named <Name>{BENCHMARK_SUFFIX}")
        name = path.name[: -len(BENCHMARK_SUFFIX)]
        folder = path.parent.parent if path.parent.name == "Parameters" else None
        bench = path
    elif path.is_dir():
        if (path / "bicycles").is_dir() and not (path / "Parameters").is_dir():
            names = sorted(p.name for p in (path / "bicycles").iterdir() if p.is_dir())
            raise InputError(f"{path}: is a BicycleParameters data folder; give one bicycle's folder, "
                             f"{path / 'bicycles' / '<Name>'} (here: {', '.join(names) or 'none'})")
        name = path.name
        folder = path
        bench = path / "Parameters" / f"{name}{BENCHMARK_SUFFIX}"
        if not bench.is_file():
            raise InputError(f"{path}: not a BicycleParameters bicycle folder: {bench} does not exist")
    else:
        raise InputError(f"{path}: no such BicycleParameters folder or file")
    measured = None if folder is None else folder / "RawData" / f"{name}{MEASURED_SUFFIX}"
    data = folder.parent.parent if folder is not None and folder.parent.name == "bicycles" else None
    return name, bench, (measured if measured is not None and measured.is_file() else None), data


def is_bicycleparameters_path(text):
    """True if ``text`` names an existing folder or a ``*.txt`` file (how :func:`bicycles.load` dispatches)."""
    path = pathlib.Path(str(text))
    return path.is_dir() or (path.suffix == ".txt" and path.is_file())


def load_bicycle(name, rider=None):
    """The bicycle a scenario names: a shipped set, else a BicycleParameters folder or file (:func:`load`), else a
    ``.toml`` path (:func:`bicycles.load`).

    Parameters
    ----------
    name : str or os.PathLike
        A shipped set's name, a ``.toml`` path, or an existing BicycleParameters
        bicycle folder or ``<Name>Benchmark.txt``.
    rider : str, optional
        The scenario's rider. ``"none"`` (:data:`whipple_kick.library.riders.NO_RIDER`)
        says that the bicycle's parameters include its rider: a
        BicycleParameters bicycle is then read with ``includes_rider=True``
        (BicycleParameters itself cannot say so); a set whose file says it is
        the bicycle alone is refused. Any other value changes nothing here.

    Returns
    -------
    Bicycle

    Example
    -------
    >>> load_bicycle("balanceassist_v1").name
    'balanceassist_v1'
    """
    text = str(name)
    # A shipped name wins over a folder of that name in the working directory (a run's output folder, say).
    if text not in bicycles.available() and not text.endswith(".toml") and is_bicycleparameters_path(text):
        return load(text, includes_rider=True if rider == NO_RIDER else None)
    bike = bicycles.load(text)
    if rider == NO_RIDER and not bike.includes_rider:
        raise InputError(f"rider {NO_RIDER!r} says that bicycle {bike.name!r} includes its rider, but its file says "
                         "includes_rider = false (the bicycle alone): give a Yeadon rider (default 'jason') or a set "
                         "with its rider (balanceassist_635N, balanceassist_701N, browser_with_rider)")
    return bike


def stamp(text):
    """Modification times of the files :func:`load` reads for ``text`` (a cache key: an edited file is re-read)."""
    path = pathlib.Path(str(text))
    files = sorted(path.rglob("*.txt")) if path.is_dir() else [path]
    return tuple(f.stat().st_mtime_ns for f in files if f.is_file())


def _default_seating():
    """Seating geometry and its standard deviations from :data:`DEFAULT_SEATING_BICYCLE`."""
    shipped = bicycles.load(DEFAULT_SEATING_BICYCLE)
    stds = {k[len("seating."):]: v for k, v in shipped.uncertainties.items() if k.startswith("seating.")}
    return dict(shipped.geometry), stds


def _seating(measured):
    """Seating geometry and stds from a Measured.txt, or None if it holds none of the seating lengths."""
    if measured is None:
        return None
    values, stds, _ = read_text(measured, None, keep=bicycles.SEATING_UNITS)
    if not values:
        return None
    _missing(measured, values, bicycles.SEATING_UNITS)
    parameters.positive(measured, values, bicycles.SEATING_UNITS, bicycles.SEATING_UNITS)
    return values, stds


def _rider_benchmark(path):
    """The rider-alone benchmark entries of ``<Rider><Name>Benchmark.txt``: mass, com (3,), inertia (3, 3)."""
    values, _, _ = read_text(path, RIDER_UNITS)
    _missing(path, values, [n for n in RIDER_UNITS if n != "yB"])
    if values.get("yB", 0.0) != 0.0:
        raise InputError(f"{path}: yB = {values['yB']!r} m: the rider must sit in the bicycle's mid-plane (yB = 0)")
    if not MIN_RIDER_MASS_KG <= values["mB"] <= MAX_RIDER_MASS_KG:   # a person's (riders.MIN_RIDER_MASS_KG says how)
        raise InputError(f"{path}: mB = {values['mB']!r} kg is outside a rider's allowed range "
                         f"[{MIN_RIDER_MASS_KG:g}, {MAX_RIDER_MASS_KG:g}] kg")
    inertia = np.array([[values["IBxx"], 0.0, values["IBxz"]], [0.0, values["IByy"], 0.0],
                        [values["IBxz"], 0.0, values["IBzz"]]])
    return values["mB"], np.array([values["xB"], 0.0, values["zB"]]), inertia


def describe_defaults(bike):
    """``bike.defaults`` as text for a run's summary: name -> ``"<value> <unit>: <source>"`` (or the source).

    Example
    -------
    >>> describe_defaults(bicycles.load("balanceassist_v1"))   # a shipped set lacks nothing
    {}
    """
    out = {}
    for key, (value, source) in bike.defaults.items():
        unit = bicycles.SEATING_UNITS.get(key.removeprefix("seating."), "")
        out[key] = source if value is None else f"{value!r} {unit}: {source}"
    return out


def _warn_defaults(name, defaults):
    kinds = sorted({key.split(".", 1)[0] for key in defaults})
    warnings.warn(f"BicycleParameters bicycle {name!r}: {', '.join(kinds)} from defaults: "
                  + "; ".join(f"{k}: {DEFAULT_SOURCES[k]}" for k in kinds), DefaultValueWarning, stacklevel=3)


def _marked_with_rider(path):
    """True if the file's first line is :data:`RIDER_MARK` (written by :func:`write_folder`)."""
    with pathlib.Path(path).open() as handle:
        return handle.readline().strip() == RIDER_MARK


def load(path, rider=None, includes_rider=None):
    """Read a BicycleParameters bicycle (folder or ``<Name>Benchmark.txt``), optionally with a rider.

    Parameters
    ----------
    path : path-like
        ``<data>/bicycles/<Name>`` (its ``Parameters/<Name>Benchmark.txt``,
        and the seating lengths of ``RawData/<Name>Measured.txt`` if there)
        or the ``Benchmark.txt`` file itself.
    rider : str, optional
        A rider folder of the same data folder (``<data>/riders/<rider>``):
        its ``Parameters/<rider><Name>Benchmark.txt`` (the rider BicycleParameters
        seated on this bicycle) is lumped rigidly into the rear frame, as
        BicycleParameters' ``add_rider`` does. The rear frame's values then
        have no standard deviation (the rider file gives none).
    includes_rider : bool, optional
        Whether the benchmark file's rear frame already holds a rider.
        Default: BicycleParameters' own assumption that a bicycle is loaded
        without rider, unless the file's first line is :data:`RIDER_MARK`
        (a comment to BicycleParameters; :func:`write_folder` writes it for a
        set with rider).

    Returns
    -------
    Bicycle
        With ``uncertainties`` (standard deviation per benchmark name, and
        ``seating.<name>``), ``defaults`` (name -> (value, source) of what
        came from defaults) and the file names in ``source``.

    Raises
    ------
    InputError
        One line naming the file, the line and the problem.

    Example
    -------
    >>> folder = write_folder(bicycles.load("benchmark"), "bp_data", name="Bench")   # (in a temporary folder)
    >>> bike = load(folder)
    >>> bike.benchmark["w"], bike.includes_rider, sorted(bike.defaults)   # the benchmark's rider is lumped in
    (1.02, True, ['tyres'])
    """
    name, bench_path, measured, data = _bicycle_files(path)
    values, stds, lines = read_text(bench_path, {**bicycles.BENCHMARK_UNITS, **EXTRA_UNITS})
    _missing(bench_path, values, _benchmark.BENCHMARK_NAMES)
    _check_extras(bench_path, values, stds, lines)
    try:
        bicycles.check_benchmark(bench_path, values)
    except InputError as exc:   # "<file>: <name>: <problem>": add the name's line, as the format errors have it
        key, _, problem = str(exc)[len(str(bench_path)) + 2:].partition(": ")
        raise InputError(f"{bench_path}:{lines.get(key, '?')}: {key}: {problem}") from None
    uncertainties = {k: v for k, v in stds.items() if v > 0.0}
    sources = [f"bicycleparameters: {bench_path}"]
    defaults = {"tyres": (None, DEFAULT_SOURCES["tyres"])}
    geometry = None
    if includes_rider is None:
        includes_rider = _marked_with_rider(bench_path)
    if includes_rider and rider is not None:
        raise InputError(f"{bench_path}: the set includes its rider already; do not add rider {rider!r}")
    includes_rider = bool(includes_rider) or rider is not None
    description = f"BicycleParameters bicycle {name} ({bench_path})"
    if rider is not None:
        if data is None:
            raise InputError(f"{path}: a rider needs the bicycle's folder inside a BicycleParameters data folder "
                             "(<data>/bicycles/<Name>), to find <data>/riders/")
        rider_path = data / "riders" / str(rider) / "Parameters" / f"{rider}{name}{BENCHMARK_SUFFIX}"
        if not rider_path.is_file():
            raise InputError(f"{rider_path}: no such file: BicycleParameters has not seated rider {rider!r} "
                             f"on {name!r}")
        values = riders.lump_into_rear_frame(values, *_rider_benchmark(rider_path))
        # The rear frame is now bicycle + rider; the rider file gives no standard deviations.
        uncertainties = {k: v for k, v in uncertainties.items() if k not in RIDER_UNITS}
        sources.append(f"rider {rider}: {rider_path}")
        description += f" with rider {rider} lumped into the rear frame ({rider_path.name})"
    elif not includes_rider:
        seating = _seating(measured)
        if seating is None:
            geometry, seat_stds = _default_seating()
            defaults.update({f"seating.{k}": (v, DEFAULT_SOURCES["seating"]) for k, v in geometry.items()})
        else:
            geometry, seat_stds = seating
            sources.append(f"seating: {measured}")
        uncertainties.update({f"seating.{k}": v for k, v in seat_stds.items() if v > 0.0})
    bike = bicycles.Bicycle(
        name=name, benchmark=values, parameterisation="benchmark", includes_rider=includes_rider,
        source="\n".join(sources), description=description, uncertainties=uncertainties,
        geometry=geometry, defaults=defaults)
    _warn_defaults(name, defaults)
    return bike


def _nominal(value):
    """(nominal, std) of a float or an ``uncertainties`` number (what BicycleParameters' values are)."""
    if hasattr(value, "nominal_value"):
        return float(value.nominal_value), float(value.std_dev)
    return float(value), 0.0


def from_bicycleparameters(obj, name=None):
    """The project's :class:`Bicycle` of a BicycleParameters object.

    Parameters
    ----------
    obj : bicycleparameters.Bicycle or a parameter set
        A ``bicycleparameters.Bicycle`` (its ``parameters['Benchmark']``, with
        the rider if one was added; seating lengths from its
        ``parameters['Measured']`` when there), or a parameter set with the
        benchmark names (``Meijaard2007ParameterSet``; a set of another
        parameterisation is converted with its ``to_parameterization
        ('Meijaard2007')`` where it has one).
    name : str, optional
        Name of the set (default the object's bicycle name or class name).

    Returns
    -------
    Bicycle
        As :func:`load` returns; parameter sets carry no standard deviations.
    """
    kind = type(obj).__name__
    if hasattr(obj, "parameters") and isinstance(obj.parameters, Mapping) and "Benchmark" in obj.parameters:
        pairs = {k: _nominal(v) for k, v in obj.parameters["Benchmark"].items()}
        name = name or getattr(obj, "bicycleName", kind)
        includes_rider = bool(getattr(obj, "hasRider", False))
        measured = {k: _nominal(v) for k, v in obj.parameters.get("Measured", {}).items()
                    if k in bicycles.SEATING_UNITS}
        what = f"bicycleparameters.Bicycle {name!r}" + (f" with rider {obj.riderName!r}" if includes_rider else "")
    elif hasattr(obj, "parameters") and isinstance(obj.parameters, Mapping):
        params = obj.parameters
        includes_rider = bool(getattr(obj, "includes_rider", False))
        if set(LEAN_NAMES) <= set(params):                 # MooreRiderLean2012: the upper body held rigid
            bike_only, body = leaning_rider(obj)
            params = riders.lump_into_rear_frame(bike_only.benchmark, *_body_in_benchmark(bike_only, body))
            includes_rider = True
        elif set(_benchmark.MOORE_NAMES) <= set(params) and not set(_benchmark.BENCHMARK_NAMES) <= set(params):
            params = _benchmark.from_moore({k: _nominal(params[k])[0] for k in _benchmark.MOORE_NAMES})
        elif not set(_benchmark.BENCHMARK_NAMES) <= set(params) and hasattr(obj, "to_parameterization"):
            converted = obj.to_parameterization("Meijaard2007")
            params = converted.parameters
            includes_rider = bool(getattr(converted, "includes_rider", includes_rider))
        pairs = {k: _nominal(v) for k, v in params.items()}
        name = name or kind
        measured = {}
        what = f"bicycleparameters {kind}"
    else:
        raise InputError(f"expected a bicycleparameters.Bicycle or parameter set, got {kind}")
    missing = [n for n in _benchmark.BENCHMARK_NAMES if n not in pairs]
    if missing:
        raise InputError(f"{what}: missing benchmark parameters {', '.join(missing)}")
    values = {n: pairs[n][0] for n in _benchmark.BENCHMARK_NAMES}
    bicycles.check_benchmark(what, values)
    uncertainties = {n: pairs[n][1] for n in _benchmark.BENCHMARK_NAMES if pairs[n][1] > 0.0}
    defaults = {"tyres": (None, DEFAULT_SOURCES["tyres"])}
    geometry = None
    if not includes_rider:
        if set(measured) == set(bicycles.SEATING_UNITS):
            geometry = {k: v[0] for k, v in measured.items()}
            uncertainties.update({f"seating.{k}": v[1] for k, v in measured.items() if v[1] > 0.0})
        else:
            geometry, seat_stds = _default_seating()
            uncertainties.update({f"seating.{k}": v for k, v in seat_stds.items() if v > 0.0})
            defaults.update({f"seating.{k}": (v, DEFAULT_SOURCES["seating"]) for k, v in geometry.items()})
    bike = bicycles.Bicycle(
        name=name, benchmark=values, parameterisation="benchmark", includes_rider=includes_rider,
        source=f"{what} (BicycleParameters, github.com/moorepants/BicycleParameters)",
        description=f"From {what}", uncertainties=uncertainties, geometry=geometry, defaults=defaults)
    _warn_defaults(name, defaults)
    return bike


#: The leaning rider's entries of BicycleParameters' MooreRiderLean2012ParameterSet (Moore 2012, "Leaning rider
#: extension"): hip spring k9 [N m/rad] and damper c9 [N m s/rad]; the horizontal hinge d4 [m] below the rear
#: wheel centre; the upper body G's mass mg [kg], its mass centre l5 [m] ahead of the rear wheel centre and l6
#: [m] below the hinge, its inertia ig.. [kg m^2] about it in axes level with the ground (x forward, z down).
LEAN_NAMES = ("k9", "c9", "d4", "l5", "l6", "mg", "ig11", "ig22", "ig33", "ig31")


def leaning_rider(obj):
    """A ``MooreRiderLean2012ParameterSet`` as the project's bicycle and leaning body.

    Parameters
    ----------
    obj : bicycleparameters.parameter_sets.MooreRiderLean2012ParameterSet
        Or any object whose ``parameters`` hold Moore's names and :data:`LEAN_NAMES`.

    Returns
    -------
    bike : Bicycle
        The bicycle with the rider's legs (Moore's C, D, E, F).
    body : dict
        :func:`whipple_kick.library.riders.split_rider`'s body (hinge horizontal, ``hip_tilt = -lam``; the
        hinge point taken above the rear wheel centre, any point of the line will do), with ``kh = k9``,
        ``ch = c9``: pass it to ``slip.model_parameters(..., model=slip.Model(("trunk",)), body=body)``.
    """
    params = {k: _nominal(v)[0] for k, v in obj.parameters.items()}
    missing = [n for n in (*_benchmark.MOORE_NAMES, *LEAN_NAMES) if n not in params]
    if missing:
        raise InputError(f"bicycleparameters {type(obj).__name__}: missing {', '.join(missing)}")
    bike = bicycles.Bicycle(name=type(obj).__name__, moore={k: params[k] for k in _benchmark.MOORE_NAMES},
                            parameterisation="moore", includes_rider=True,
                            source=f"bicycleparameters {type(obj).__name__} (Moore 2012)",
                            description="Moore's leaning-rider set: the bicycle with the rider's legs")
    hinge = np.array([0.0, params["d4"]])              # (x, z) from the rear wheel centre, benchmark axes
    inertia = [[params["ig11"], 0.0, params["ig31"]], [0.0, params["ig22"], 0.0], [params["ig31"], 0.0, params["ig33"]]]
    body = parts.trunk_body(bike.benchmark["lam"], hinge, (params["l5"], params["l6"]), params["mg"], inertia)
    return bike, {**body, "kh": params["k9"], "ch": params["c9"]}


def _body_in_benchmark(bike, body):
    """The leaning body's mass [kg], mass centre (3,) [m] and inertia (3, 3) [kg m^2] in the benchmark frame."""
    c_x, c_z = _benchmark._pitch_matrix(bike.benchmark["lam"])
    hinge = body["lh1"] * c_x + body["lh3"] * c_z       # from the rear wheel centre (0, -rR)
    com = np.array([hinge[0] + body["lt1"], 0.0, -bike.benchmark["rR"] + hinge[1] + body["lt3"]])
    inertia = np.array([[body["it11"], 0.0, body["it31"]], [0.0, body["it22"], 0.0],
                        [body["it31"], 0.0, body["it33"]]])
    return body["mt"], com, inertia


def write_folder(bike, data, name=None):
    """Write a bicycle as a BicycleParameters bicycle folder, so a run (a :class:`Scenario`, the CLI) can name it.

    A scenario holds its bicycle as a name or path (it is saved as a file), so
    a set built in Python (:func:`from_bicycleparameters` of a parameter-set
    object) reaches ``simulate`` and ``stability`` through this folder.

    Parameters
    ----------
    bike : Bicycle or bicycleparameters object
        What to write (an object is converted by :func:`from_bicycleparameters`).
    data : path-like
        The data folder; the bicycle goes to ``<data>/bicycles/<Name>``.
    name : str, optional
        Folder name (default the bicycle's, which must then be a plain word).

    Returns
    -------
    pathlib.Path
        The bicycle folder (``Parameters/<Name>Benchmark.txt`` with each value's
        ``+/-`` standard deviation where known; ``RawData/<Name>Measured.txt``
        with the seating lengths unless they were defaults).
    """
    if not isinstance(bike, bicycles.Bicycle):
        bike = from_bicycleparameters(bike)
    name = str(name or bike.name)
    if not re.fullmatch(r"[A-Za-z0-9_-]+", name):
        raise InputError(f"BicycleParameters bicycle name {name!r} must be letters, digits, '_' or '-'")
    folder = pathlib.Path(data) / "bicycles" / name

    def line(key, value, std):
        return f"{key} = {value!r}" + (f"+/-{std!r}" if std else "") + "\n"

    (folder / "Parameters").mkdir(parents=True, exist_ok=True)
    (folder / "Parameters" / f"{name}{BENCHMARK_SUFFIX}").write_text((RIDER_MARK + "\n" if bike.includes_rider else "")
                                                                     + "".join(line(k, float(bike.benchmark[k]), bike.uncertainties.get(k)) for k in _benchmark.BENCHMARK_NAMES))
    if bike.geometry is not None and not any(k.startswith("seating.") for k in bike.defaults):
        (folder / "RawData").mkdir(exist_ok=True)
        (folder / "RawData" / f"{name}{MEASURED_SUFFIX}").write_text("".join(
            line(k, float(v), bike.uncertainties.get(f"seating.{k}")) for k, v in bike.geometry.items()))
    return folder


def parameter_uncertainties(bike):
    """Nominal value and standard deviation of each parameter that has one: ``{name: (nominal, std)}``.

    Parameters
    ----------
    bike : Bicycle
        Any bicycle (a shipped TOML one with uncertainties, or one read here).

    Returns
    -------
    dict
        Benchmark names (``"w"``, ``"IBxx"``, ...) and ``"seating.<name>"``
        for the seating lengths, in SI units; only the parameters whose
        source gives a standard deviation (g, for one, has none).

    Example
    -------
    >>> from whipple_kick.library import bicycles
    >>> parameter_uncertainties(bicycles.load("balanceassist_v1"))["c"]
    (0.042, 0.01)
    """
    out = {}
    for key, std in bike.uncertainties.items():
        if key.startswith("seating."):
            nominal = bike.geometry[key[len("seating."):]]
        elif key in bike.benchmark:
            nominal = bike.benchmark[key]
        elif key in bike.moore:
            nominal = bike.moore[key]
        else:
            continue
        out[key] = (float(nominal), float(std))
    return out


def yeadon_rider(path, bicycle=None, mass_kg=None):
    """A rider from BicycleParameters' Yeadon files, ready for :func:`whipple_kick.library.riders.seat`.

    Parameters
    ----------
    path : path-like
        ``<data>/riders/<Rider>`` (reads ``RawData/<Rider>YeadonMeas.txt``) or
        that measurement file itself.
    bicycle : str, optional
        Name of the bicycle whose ``RawData/<Rider><bicycle>YeadonCFG.txt``
        gives the trunk's configuration; default all joint angles 0. The
        limbs' angles are solved when seating.
    mass_kg : float, optional
        Mass to scale to [kg]; default the file's ``totalmass``.

    Returns
    -------
    whipple_kick.library.riders.YeadonRider
    """
    import yeadon


    path = pathlib.Path(path)
    if path.is_dir():
        rider_name = path.name
        meas_path = path / "RawData" / f"{rider_name}YeadonMeas.txt"
    else:
        meas_path = path
        rider_name = path.name.removesuffix("YeadonMeas.txt") or path.stem
    data = _yaml_file(meas_path, yaml)
    factor = data.pop("measurementconversionfactor", None)
    total = data.pop("totalmass", None)
    for key, value, unit in (("measurementconversionfactor", factor, "m per file unit"),
                             ("totalmass", total, "kg")):
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not value > 0:
            raise InputError(f"{meas_path}: {key} = {value!r} must be a number > 0 {unit}")
    unknown = sorted(set(data) - set(yeadon.Human.measnames))
    missing = [k for k in yeadon.Human.measnames if k not in data]
    if unknown or missing:
        raise InputError(f"{meas_path}: unknown measurements {unknown}, missing measurements {missing}")
    meas = {}
    for key in yeadon.Human.measnames:
        value = data[key]
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not value > 0:
            raise InputError(f"{meas_path}: {key} = {value!r} must be a number > 0 (file units)")
        meas[key] = float(value) * float(factor)
    cfg = dict.fromkeys(yeadon.Human.CFGnames, 0.0)
    sources = [f"bicycleparameters: {meas_path}"]
    if bicycle is not None:
        cfg_path = meas_path.parent / f"{rider_name}{bicycle}YeadonCFG.txt"
        cfg_data = _yaml_file(cfg_path, yaml)
        unknown = sorted(set(cfg_data) - set(yeadon.Human.CFGnames))
        if unknown:
            raise InputError(f"{cfg_path}: unknown joint angles {unknown}")
        for key, value in cfg_data.items():
            if isinstance(value, bool) or not isinstance(value, (int, float)):
                raise InputError(f"{cfg_path}: {key} = {value!r} must be a number in rad")
            cfg[key] = float(value)
        sources.append(f"configuration: {cfg_path}")
    mass = float(total) if mass_kg is None else float(mass_kg)
    return riders.rider_from_measurements(rider_name, meas, cfg, "\n".join(sources), mass_kg=mass)


def _yaml_file(path, yaml):
    try:
        data = yaml.safe_load(pathlib.Path(path).read_text())
    except FileNotFoundError:
        raise InputError(f"{path}: no such file") from None
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        line = f":{mark.line + 1}" if mark is not None else ""
        raise InputError(f"{path}{line}: not a Yeadon file ({getattr(exc, 'problem', exc)})") from None
    if not isinstance(data, dict):
        raise InputError(f"{path}: not a Yeadon file (expected 'name: value' lines)")
    return data
