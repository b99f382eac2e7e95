"""
A bicycle in BicycleParameters' format
======================================

Bicycle-dynamics researchers keep their measured bicycles in BicycleParameters'
data folders: ``bicycles/<Name>/Parameters/<Name>Benchmark.txt``, every value
written with its standard deviation (``mB = 22.500+/-0.010``). The ``simulate``
command takes such a folder with ``--bicycle PATH``; from Python,
:func:`whipple_kick.library.bicycleparameters.load` reads it and keeps the
uncertainties.

Here the project's own measured bicycle is written in that format into a
temporary data folder, read back, and run through a short kick; the same
works on any folder of BicycleParameters' data (their Browser, Crescendo,
Stratos, ...).
"""
import pathlib
import tempfile

import whipple_kick as wk
from whipple_kick.figures.plotting import kick_band, response_figure
from whipple_kick.library import bicycleparameters, bicycles

data = pathlib.Path(tempfile.mkdtemp(prefix="bp_data_"))
folder = bicycleparameters.write_folder(bicycles.load("balanceassist_v1"), data, name="Balanceassist")
print(sorted(p.relative_to(data).as_posix() for p in folder.rglob("*.txt")))

# %%
# What the folder holds, with its uncertainties
# ---------------------------------------------
# The nominal value and standard deviation of each measured parameter, by
# BicycleParameters' names (what an uncertainty study can sample).
bike = bicycleparameters.load(folder)
for name, (nominal, std) in list(bicycleparameters.parameter_uncertainties(bike).items())[:8]:
    print(f"{name:>6} = {nominal:.4g} +/- {std:.2g}")
print("from defaults:", bicycleparameters.describe_defaults(bike) or "nothing")

# %%
# A kick on it
# ------------
# A scenario names the folder as its bicycle, as ``simulate --bicycle PATH`` does
# (3 s at 200 Hz to keep the example quick).
result = wk.run(wk.Scenario(bicycle=str(folder), fz_n=635, duration=3.0, output_rate=200.0))
print("fell:", result.summary["fell"], "| recovery time [s]:", result.summary["recovery"]["time_s"])
fig = response_figure([("BicycleParameters folder", result)], kick=kick_band(result))
