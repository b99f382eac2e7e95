"""
A sweep over pressure and load, and its figure
==============================================

:func:`whipple_kick.sweep` runs many kick-plate cases in parallel and puts
them in one table, one row per case: here three tyre pressures at two rear
loads. ``recommend-pressure`` and the validation run on the same machinery.

The recovery time (yaw, roll and steer rate back within 5 % of their first
peaks, the recommender's rule) needs the full 6 s after the kick, so the
runs keep it; they are sampled at 200 Hz instead of 1000 Hz to keep the
example quick.
"""
import whipple_kick as wk
from whipple_kick.figures.plotting import sweep_figure

base = wk.Scenario(output_rate=200.0)
table = wk.sweep({"pressure_kpa": [300, 400, 500], "fz_n": [570, 701]}, base=base, workers=2, progress=False)

# %%
# The table
# ---------
# Every Scenario field and the flat results of each run: here whether it
# fell, the largest roll angle and the recovery time.
columns = ["fz_n", "pressure_kpa", "status", "fell", "peaks.max_abs_roll_absolute_rad", "recovery.time_s"]
print(table[columns].to_string(index=False))

# %%
# The figure
# ----------
# One line per rear load; a case that fell would be an x at the top.
fig = sweep_figure(table, x="pressure_kpa", metric="recovery.time_s", y="fz_n")
