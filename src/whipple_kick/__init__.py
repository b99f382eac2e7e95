"""whipple_kick: a nonlinear bicycle-rider simulator for kick-plate studies.

The public API is small (``__all__``)::

    import whipple_kick as wk
    result = wk.run(wk.Scenario(pressure_kpa=400, fz_n=635))   # one kick-plate run
    result.trajectory, result.summary                           # time histories, metrics
    table = wk.sweep({"pressure_kpa": [300, 400, 500]})         # many runs in parallel

The package is five wings, each importing only the ones below it:
``model`` (the equations, the generated code, the tyre formulas) <
``library`` (parameter sets) < ``simulate`` (one scenario to one result;
:func:`whipple_kick.simulate.simulation.run` reads it top-down) <
``figures`` < ``studies`` (sweeps, recommendation, validation, stability)
< ``cli``; ``errors`` and ``fileio`` sit beneath them all.

Imports sit at the top of each module, and the modules' top-level imports
form no circle. A function imports only what keeps a slow or optional
package out of a run that does not use it: SymPy (the model's build on a
cache miss, and the package's symbolic modules), python-control,
matplotlib and Pillow, imageio-ffmpeg, Tornado, Selenium, Dask, SALib,
scikit-learn, emcee, SciPy's signal package; and the command-line module
imports a command's own studies and figures when that command runs.
``tests/test_imports.py`` checks both rules; a warm ``simulate`` loads
none of these packages (``tests/test_cli.py``).

Names and submodules are imported lazily on first attribute access
(``wk.Scenario``, ``wk.tyres``, ``wk.stability`` ...), so importing the
package is cheap and nothing slow to import (the symbolic derivation) is
loaded unless it is used.
"""
import importlib

__version__ = "0.4.0"

#: The public names and the module each lives in.
_EXPORTS = {
    "Scenario": "simulate.scenario",
    "Result": "simulate.results",
    "run": "simulate.simulation",
    "sweep": "studies.sweep_engine",
    "InputError": "errors",
    "SimulationError": "errors",
}
__all__ = ["InputError", "Result", "Scenario", "SimulationError", "__version__", "run", "sweep"]

#: The modules by their short names (``wk.tyres``, ``wk.stability``, ``wk.plotting`` ...) and their
#: homes in the wings: model < library < simulate < figures < studies < cli.
_SUBMODULES = {
    **{name: f"model.{name}" for name in (
        "benchmark", "cache", "carcass", "classic", "energy", "geometry", "kane", "magic_formula", "reflex",
        "rhs_call", "slip", "symbolic", "symbols", "transient")},
    **{name: f"library.{name}" for name in (
        "bicycleparameters", "bicycles", "experiments", "inputs", "parameters", "priors", "riders", "tyres",
        "uncertain")},
    **{name: f"simulate.{name}" for name in (
        "analysis", "assembly", "control", "integration", "lsoda", "oscillation", "provenance", "results",
        "scenario", "simulation", "steady")},
    **{name: f"figures.{name}" for name in ("animation", "plotting")},
    "uncertainty_figures": "figures.uncertainty",
    "calibration_figures": "figures.calibration",
    **{name: f"studies.{name}" for name in (
        "authors_code", "calibration", "posterior_study", "recommend", "stability", "sweep_engine", "sweep_store", "uncertainty",
        "validation")},
    **{name: name for name in ("cli", "errors", "fileio")},
    **{name: name for name in ("model", "library", "simulate", "figures", "studies")},
}


def __getattr__(name):
    if name in _EXPORTS:
        value = getattr(importlib.import_module(f"{__name__}.{_EXPORTS[name]}"), name)
    elif name in _SUBMODULES:
        value = importlib.import_module(f"{__name__}.{_SUBMODULES[name]}")
    else:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    globals()[name] = value
    return value


def __dir__():
    return sorted(set(globals()) | set(_EXPORTS) | set(_SUBMODULES))
