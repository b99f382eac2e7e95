"""Reading and validating the project's TOML parameter files: one reader, one set of rules.

The shipped files (bicycles, experiments, riders, tyres) are package data of
``whipple_kick.parameter_files``, which is the repository's top-level
``parameters/`` folder: :func:`shipped` finds them with
:mod:`importlib.resources` wherever the package is installed (a wheel or an
editable install). Every value in them carries its unit and source.

This module checks the format only, with the same rules and the same
one-line messages (``<file>: <key>: <problem>``) for every file:
:func:`quantity` for one ``{value, unit, source[, uncertainty]}`` entry,
:func:`quantities` for a table of them. What the entries mean is checked by
the module that owns them (:mod:`whipple_kick.library.tyres`,
:mod:`whipple_kick.library.bicycles`, :mod:`whipple_kick.library.riders`).
"""
from collections.abc import Mapping
from importlib import resources
import math
import pathlib
from typing import NoReturn

try:  # Python >= 3.11
    import tomllib
except ModuleNotFoundError:  # pragma: no cover - Python 3.10
    import tomli as tomllib

from whipple_kick import fileio
from whipple_kick.errors import InputError

#: The package whose data are the shipped parameter files.
DATA_PACKAGE = "whipple_kick.parameter_files"
#: Kinds of shipped parameter files (sub-folders of the data package).
KINDS = ("bicycles", "experiments", "riders", "tyres", "uncertainty", "calibration")


def shipped(kind: str) -> pathlib.Path:
    """Folder of the shipped parameter files of one kind.

    Parameters
    ----------
    kind : {"bicycles", "experiments", "riders", "tyres", "uncertainty", "calibration"}

    Returns
    -------
    pathlib.Path
        Inside the installed package (a wheel installs it as plain files).

    Example
    -------
    >>> sorted(toml_files(shipped("tyres")))
    ['T01', 'T02', 'T03', 'T04', 'T05']
    """
    if kind not in KINDS:
        raise ValueError(f"kind must be one of {', '.join(KINDS)}, got {kind!r}")
    folder = resources.files(DATA_PACKAGE) / kind
    # A wheel or an editable install puts the package on the file system, where
    # files() is a pathlib.Path; the readers below glob and stat it.
    return pathlib.Path(str(folder))


def toml_files(folder) -> dict:
    """The ``*.toml`` files of a folder by name (file name without ``.toml``), sorted.

    Listed once per process while the folder stays as it was (its :func:`~whipple_kick.fileio.settled_key`:
    adding, removing or renaming a file changes it): a sweep's every case looks its tyre, rider and bicycle
    files up here.
    """
    # A copy: a caller cannot change the kept listing.
    return dict(fileio.read_once(_LISTINGS, folder,
                                 lambda f: {p.stem: p for p in sorted(pathlib.Path(f).glob("*.toml"))}))


#: :func:`toml_files`' listings: folder -> (its settled key, the listing).
_LISTINGS = {}


def load_toml(path) -> dict:
    """Read a TOML file and return its contents as a dict.

    Raises
    ------
    InputError
        If the file is missing or is not valid TOML (one line, naming the file).
    """
    return parse_toml(path, file_bytes(path))


def file_bytes(path) -> bytes:
    """The bytes of a parameter file (what a parse cache keys on: an edited file is read afresh).

    Raises
    ------
    InputError
        If the file is missing or cannot be read, e.g. it is a folder (one line, naming the file).
    """
    try:
        with open(path, "rb") as file:   # what Path.read_bytes does, without parsing the path into a Path first
            return file.read()
    except FileNotFoundError:
        raise InputError(f"parameter file {path} does not exist") from None
    except OSError as exc:   # a folder, no permission: the input cannot be read (not an output failure)
        raise InputError(f"parameter file {path} cannot be read: {exc.strerror or exc}") from None


def parse_toml(path, content: bytes) -> dict:
    """The TOML ``content`` of the file ``path`` as a dict (InputError naming the file if it is not valid TOML)."""
    try:
        return tomllib.loads(content.decode())
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"parameter file {path} is not valid TOML: {exc}") from None


def fail(path, key: str, problem: str) -> NoReturn:
    """Raise the one-line :class:`InputError` ``<path>: <key>: <problem>``."""
    raise InputError(f"{path}: {key}: {problem}")


def table(path, key: str, value) -> dict:
    """``value`` if it is a TOML table, else :func:`fail`."""
    if not isinstance(value, dict):
        fail(path, key, f"must be a table, got {value!r}")
    return value


def text(path, key: str, value) -> str:
    """``value`` if it is a non-empty string, else :func:`fail`."""
    if not isinstance(value, str) or not value.strip():
        fail(path, key, f"must be a non-empty string, got {value!r}")
    return value


def number(path, key: str, value) -> float:
    """``float(value)`` if it is a finite number (not a boolean), else :func:`fail`."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        fail(path, key, f"must be a number, got {value!r}")
    if not math.isfinite(value):
        fail(path, key, f"must be finite, got {value!r}")
    return float(value)


def at_least(path, key: str, value: float, unit: str, low: float, *, low_open: bool = False) -> float:
    """``value`` if it is >= ``low`` (> with ``low_open``), else :func:`fail` naming the bound and unit."""
    if value < low or (low_open and value == low):
        fail(path, key, f"value {value!r} {unit} must be {'>' if low_open else '>='} {low:g} {unit}")
    return value


def quantity(path, key: str, entry, unit: str | None, *, sources: Mapping | None = None,
             low: float | None = None, low_open: bool = False,
             uncertainty: bool = False) -> tuple[float, float | None]:
    """Read one ``{value, unit, source[, uncertainty]}`` entry.

    Parameters
    ----------
    path : path-like
        The file (named in every message).
    key : str
        Where the entry is, e.g. ``"pressure.300.vertical_stiffness"``.
    entry : object
        What the file holds there.
    unit : str or None
        The unit the entry must declare (None: any non-empty unit).
    sources : mapping, optional
        The file's ``[sources]`` table: ``source`` must be one of its keys.
        Without it, ``source`` is the citation itself (a non-empty string).
    low, low_open : float, bool
        Smallest allowed value (excluded with ``low_open``); None: unbounded.
    uncertainty : bool
        Allow an ``uncertainty`` field (finite, >= 0, in the entry's unit).

    Returns
    -------
    (value, uncertainty or None)

    Raises
    ------
    InputError
        One line naming the file, the key and the problem.

    Example
    -------
    >>> quantity("f.toml", "mass", {"value": 3.0, "unit": "kg", "source": "scale"}, "kg", low=0.0)
    (3.0, None)
    """
    entry = table(path, key, entry)
    allowed = ("value", "unit", "source", "uncertainty") if uncertainty else ("value", "unit", "source")
    extra = sorted(set(entry) - set(allowed))
    if extra:
        fail(path, key, f"unknown field(s) {extra}; allowed: {', '.join(allowed)}")
    for name in ("value", "unit", "source"):
        if name not in entry:
            fail(path, key, f"missing field '{name}'")
    declared = entry["unit"]
    if not isinstance(declared, str) or not declared or (unit is not None and declared != unit):
        fail(path, key, f"unit must be {unit or 'a unit string'!r}, got {declared!r}")
    if sources is None:
        text(path, f"{key}.source", entry["source"])
    elif entry["source"] not in sources:
        fail(path, key, f"source {entry['source']!r} is not a key of [sources] ({', '.join(sources)})")
    value = number(path, f"{key}.value", entry["value"])
    if low is not None:
        at_least(path, key, value, declared, low, low_open=low_open)
    spread = None
    if "uncertainty" in entry:
        spread = at_least(path, f"{key}.uncertainty", number(path, f"{key}.uncertainty", entry["uncertainty"]),
                          declared, 0.0)
    return value, spread


def quantities(path, table_name: str, entries, units: Mapping | None, *, sources: Mapping | None = None,
               complete: bool = True, uncertainty: bool = False) -> tuple[dict, dict]:
    """Read a table of :func:`quantity` entries.

    Parameters
    ----------
    table_name : str
        The table's name in the file (keys are reported as ``<table_name>.<key>``).
    entries : object
        The table.
    units : mapping or None
        The allowed keys and the unit each must declare (None: any key, any unit).
    complete : bool
        Every key of ``units`` must be present.
    sources, uncertainty
        As for :func:`quantity`.

    Returns
    -------
    values, uncertainties : dict
        By key; ``uncertainties`` holds the entries that give one.
    """
    entries = table(path, table_name, entries)
    if units is not None:
        unknown = sorted(set(entries) - set(units))
        if unknown:
            fail(path, table_name, f"unknown keys {', '.join(unknown)}; allowed: {', '.join(units)}")
        missing = [k for k in units if k not in entries] if complete else []
        if missing:
            fail(path, table_name, f"missing {', '.join(missing)}")
    values, spreads = {}, {}
    for key, entry in entries.items():
        want = None if units is None else units[key]
        values[key], spread = quantity(path, f"{table_name}.{key}", entry, want, sources=sources,
                                       uncertainty=uncertainty)
        if spread is not None:
            spreads[key] = spread
    return values, spreads


def positive(path, values: Mapping, names, units: Mapping) -> None:
    """:func:`fail` unless every ``values[name]`` of ``names`` is > 0."""
    for key in names:
        if not values[key] > 0:
            fail(path, key, f"value {values[key]!r} {units[key]} must be > 0 {units[key]}")
