"""whipple_kick: a nonlinear bicycle-rider simulator for kick-plate studies.

The public API is small (``__all__``)::

    import whipple_kick as wk
    result = wk.run(wk.Scenario(pressure_kpa=400, fz_n=635))   # one kick-plate run
    result.trajectory, result.summary                           # time histories, metrics
    table = wk.sweep({"pressure_kpa": [300, 400, 500]})         # many runs in parallel

A run follows the data flow scenario -> inputs -> assembly -> integration
-> results (the modules of those names, :func:`whipple_kick.simulation.run`
reads it top-down); analysis, plots, animation, the linear stability
(``wk.stability``), sweeps and the command-line tools sit on top.

Names and submodules are imported lazily on first attribute access
(``wk.Scenario``, ``wk.tyres``, ``wk.stability`` ...), so importing the
package is cheap and nothing slow to import (the symbolic derivation) is
loaded unless it is used.
"""
import importlib

__version__ = "0.1.0"

#: The public names and the module each lives in.
_EXPORTS = {
    "Scenario": "scenario",
    "Result": "results",
    "run": "simulation",
    "sweep": "sweep_engine",
    "InputError": "errors",
    "SimulationError": "errors",
}
__all__ = ["InputError", "Result", "Scenario", "SimulationError", "__version__", "run", "sweep"]

_SUBMODULES = (
    "analysis", "animation", "assembly", "authors_code", "benchmark", "bicycles", "cache", "classic", "cli",
    "carcass", "control", "energy", "errors", "experiments", "fileio", "geometry", "inputs",
    "integration", "kane", "lsoda", "magic_formula", "parameters", "plotting", "provenance", "recommend", "reflex",
    "results",
    "riders", "scenario", "simulation",
    "slip", "stability", "steady", "symbolic", "sweep_engine", "sweep_store", "symbols", "transient", "tyres",
    "validation",
)


def __getattr__(name):
    if name in _EXPORTS:
        value = getattr(importlib.import_module(f"{__name__}.{_EXPORTS[name]}"), name)
    elif name in _SUBMODULES:
        value = importlib.import_module(f"{__name__}.{name}")
    else:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    globals()[name] = value
    return value


def __dir__():
    return sorted(set(globals()) | set(_EXPORTS) | set(_SUBMODULES))
