"""
Stability against speed: weave, capsize and the tyre modes
==========================================================

:func:`whipple_kick.studies.stability.analyse` linearises the slip model
(the measured Magic-Formula tyres) about its steady motion at each speed,
follows the eigenvalues across speed and names the modes; the no-slip
(knife-edge) Carvallo-Whipple model of the same bicycle and rider is
computed beside it. The ``stability`` command does the same from 0.5 to
10 m/s; here a few speeds around the weave speed, open loop (no rider
control), on tyres without their zero-slip offsets so that the steady
motion is straight running (the command's default).
"""
import matplotlib.pyplot as plt
import numpy as np

import whipple_kick as wk
from whipple_kick.studies import stability

speeds = np.arange(2.0, 6.01, 0.5)
result = stability.analyse(wk.Scenario(symmetric_tyres=True), speeds, loops=("open",))

# %%
# The weave and capsize speeds
# ----------------------------
# The summary holds, per model and loop, the speeds where the weave and the
# capsize mode change stability, and the self-stable speed range.
open_loop = result.summary["slip"]["open"]
print(f"weave speed:   {open_loop['weave_speed_m_s']:.2f} m/s")
print(f"capsize speed: {open_loop['capsize_speed_m_s']:.2f} m/s")

# %%
# The eigenvalues
# ---------------
# One row per eigenvalue, loop and speed, each named by where its eigenvector
# carries its amplitude. The real parts of the slow modes against speed, the
# slip model beside the no-slip model (as Meijaard et al. 2007, Fig. 3):
table = result.eigenvalues
fig, ax = plt.subplots(figsize=(7, 4))
for mode, colour in (("weave", "tab:blue"), ("capsize", "tab:orange")):
    for model, style in (("slip", "-"), ("no-slip", ":")):
        rows = table[(table["model"] == model) & (table["mode"] == mode)]
        rows = rows.groupby("speed_m_s")["real_1_s"].max()
        ax.plot(rows.index, rows.values, style, color=colour, marker="o", ms=3, label=f"{mode}, {model}")
ax.axhline(0.0, color="k", lw=0.6)
ax.set_xlabel("speed [m/s]")
ax.set_ylabel("real part [1/s]")
ax.set_ylim(-5, 3)
ax.set_title("Open loop: stable where the real parts are below zero")
ax.legend()

# %%
# The linear model at one speed as a ``control.StateSpace``, with named states,
# for control users:
sys = result.state_space(4.0, loop="open")
print(sys.nstates, "states:", ", ".join(sys.state_labels[:6]), "...")
