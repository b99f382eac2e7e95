"""Reading the project's TOML parameter files.

All parameter files live under ``parameters/`` at the top of the repository
(bicycles, riders, tyres). Every value in them carries its unit and source;
this module only reads and validates the file format, the meaning of the
entries is checked by the module that owns them (``tyres``, ``bicycles``,
``riders``).
"""
import math
import pathlib

try:  # Python >= 3.11
    import tomllib
except ModuleNotFoundError:  # pragma: no cover - Python 3.10
    import tomli as tomllib

from .errors import InputError

#: Folder holding the shipped parameter files.
PARAMETER_DIR = pathlib.Path(__file__).resolve().parents[2] / "parameters"


def load_toml(path):
    """Read a TOML file and return its contents as a dict.

    Raises
    ------
    InputError
        If the file is missing or is not valid TOML (one line, naming the file).
    """
    path = pathlib.Path(path)
    try:
        with open(path, "rb") as fh:
            return tomllib.load(fh)
    except FileNotFoundError:
        raise InputError(f"parameter file {path} does not exist") from None
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"parameter file {path} is not valid TOML: {exc}") from None


def require_finite(path, key, value):
    """Return ``float(value)`` or raise InputError naming file, key and problem."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise InputError(f"{path}: {key} must be a number, got {value!r}")
    if not math.isfinite(value):
        raise InputError(f"{path}: {key} must be finite, got {value!r}")
    return float(value)
