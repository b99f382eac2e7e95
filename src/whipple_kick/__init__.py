"""whipple_kick: a nonlinear bicycle-rider simulator for kick-plate studies.

Submodules are imported lazily on first attribute access
(``whipple_kick.benchmark``, ``whipple_kick.classic``, ``whipple_kick.tyres``
...), so importing the package is cheap and a module that is slow to import
(the symbolic derivation) is only loaded when it is used.
"""
import importlib

__version__ = "0.1.0"

_SUBMODULES = (
    "analysis", "animation", "benchmark", "bicycles", "cache", "classic", "cli", "codegen", "energy",
    "errors", "control", "derivation", "geometry", "integrate", "kane", "magic_formula",
    "parameters", "plotting", "riders", "simulation", "slip", "stability", "steady", "sweep", "symbols", "transient",
    "tyres",
)


def __getattr__(name):
    if name in _SUBMODULES:
        module = importlib.import_module(f"{__name__}.{name}")
        globals()[name] = module
        return module
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__():
    return sorted(list(globals()) + list(_SUBMODULES))
