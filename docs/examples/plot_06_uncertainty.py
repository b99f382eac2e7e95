"""
How sure is the best pressure: the uncertainty study
====================================================

Which inflation pressure lets a rider recover fastest depends on inputs the
experiment cannot pin down: the plate's acceleration and the kick's
direction, the riding speed, the carcass stiffness, the rider model and its
gains (``parameters/uncertainty/kickplate_2025.toml`` gives each with its
distribution and reason; docs/uncertainty.md). The study runs every
pressure on the same sampled inputs (a Saltelli-Sobol' design from SALib)
and answers with the probability that each pressure is best, with its
interval, and the Sobol indices of the paired differences: what the answer
hinges on.

This example is deliberately tiny (N = 2 base samples, one load, two
pressures: 44 runs) so that the site builds quickly: its numbers show the
method, not the answer. The command for a real study is
``recommend-pressure --fz 570 635 701 --uncertain --samples 64 --out study``.
"""
from whipple_kick.figures.uncertainty import p_best_figure, sobol_figure
from whipple_kick.studies import uncertainty

study = uncertainty.run_study(samples=2, seed=0, loads=(635.0,), pressures=(300.0, 500.0))
print(uncertainty.format_study(study))

# %%
# P(best) per pressure, with 95 % Wilson intervals
# ------------------------------------------------
# With 2N = 4 rows the intervals are as wide as they must be.
fig = p_best_figure(study.p_best)

# %%
# What the difference hinges on
# -----------------------------
# First-order and total Sobol indices of the paired recovery-time difference
# (at N = 2 their intervals are wider than the indices: a picture of the
# output, not a finding).
fig = sobol_figure(study.sobol)
