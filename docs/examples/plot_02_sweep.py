"""
A sweep over pressure and its figure
====================================

:func:`whipple_kick.sweep` runs many kick-plate cases in parallel and puts
them in one table, one row per case: here three tyre pressures at one rear
load. ``recommend-pressure`` and the validation run on the same machinery.

The runs are shortened to 3 s after the kick (sampled at 200 Hz) to keep
the example quick; the recovery time needs the longer default run when a
rider recovers slowly, and is then missing from the table (no value, not a
guess).
"""
import whipple_kick as wk
from whipple_kick.figures.plotting import sweep_figure

base = wk.Scenario(fz_n=635, duration=3.0, output_rate=200.0)
table = wk.sweep({"pressure_kpa": [300, 400, 500]}, base=base, workers=2, progress=False)

# %%
# The table
# ---------
# Every Scenario field and the flat results, e.g. the peak yaw rate and the
# recovery time.
print(table[["pressure_kpa", "status", "fell", "recovery.time_s"]].to_string(index=False))

# %%
# The figure
# ----------
# One line per rear load (here one); a case that fell would be an x at the top.
fig = sweep_figure(table, x="pressure_kpa", metric="recovery.time_s", y="fz_n")
