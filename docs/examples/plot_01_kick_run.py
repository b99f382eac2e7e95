"""
One kick-plate run
==================

The thesis' kick-plate test (Dell'Orto 2025, Sections 8.3-8.4): a bicycle
with a Yeadon rider loading the rear tyre with 635 N rides steadily at
3 m/s on T03 tyres at 400 kPa; the plate under the rear wheel moves
150 mm to the right in 0.150 s and the LQR steer-torque rider recovers.
The ``simulate`` command does the same with ``--pressure 400 --fz 635``.

This run is shortened to 3 s after the kick and sampled at 200 Hz to keep
the example quick (the command's defaults are 6 s and 1000 Hz).
"""
import whipple_kick as wk
from whipple_kick.figures.plotting import kick_band, response_figure

scenario = wk.Scenario(pressure_kpa=400, fz_n=635, duration=3.0, output_rate=200.0)
result = wk.run(scenario)

# %%
# The result
# ----------
# ``result.trajectory`` holds the time histories (SI units, time from the kick
# start) and ``result.summary`` the outcome and the metrics, as summary.json
# has them.
summary = result.summary
print("fell:", summary["fell"], "| recovered:", summary["recovered"])
print("recovery time [s]:", summary["recovery"]["time_s"])
print(result.trajectory[["time", "roll", "steer", "yaw_rate"]].describe().loc[["min", "max"]])

# %%
# The response
# ------------
# Yaw, roll and steer rate and the rear lateral force, as thesis Figure 8.6,
# with the kick shaded (``simulate`` writes the same figure as response.png).
fig = response_figure([("T03, 400 kPa, 635 N", result)], kick=kick_band(result))
