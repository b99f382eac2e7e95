"""
The model against the measurements: ``validate`` on two cases
===============================================================

:func:`whipple_kick.studies.validation.validate` runs the thesis' measured
kick-plate cases (Section 8.5, Tables 8.6-8.9) on the model, reduces each
run's yaw rate exactly as the recordings were reduced, and compares the
metrics. The ``validate`` command runs all nine cases in both kick
directions; here two of them (400 kPa at 570 N and at 701 N), kicks to the
right only, and 2 s after the kick (the recordings' metrics use the first
second), so that the example is quick.
"""
import dataclasses

from whipple_kick.figures.plotting import validation_figure
from whipple_kick.library import experiments
from whipple_kick.studies import validation

measured = experiments.load()
two = {name: case for name, case in measured.cases.items() if name in ("570N_400kPa", "701N_400kPa")}
subset = dataclasses.replace(measured, cases=two)
base = validation.base_scenario(duration=2.0, output_rate=500.0)
result = validation.validate(base=base, experiment=subset, directions=("right",), workers=2)

# %%
# Model beside measurement
# ------------------------
# The printed report of the ``validate`` command: per case the measured and
# the modelled last-peak time, number of peaks, period, logarithmic
# decrements and dominant frequency.
print("\n".join(validation.report_lines(result)))

# %%
# The figure
# ----------
# The metric panels (measured, model), the model's processed yaw rates and
# their spectra with the measured 5-6 Hz band shaded.
fig = validation_figure(result)
