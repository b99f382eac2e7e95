"""The thesis authors' published code side by side with this model.

The thesis (Dell'Orto 2025, Chapter 8) names its simulation code,
mechmotum/bicycle-kickplate-model. Its standard run (``base_simulation.py``:
T03 at 500 kPa, Table 8.4 rider, 3 m/s, the thesis kick) falls 3.83 s after
the kick, while the thesis' figures show recovery. ``tests/data/authors_model``
holds that run and two more of the same code, at 400 kPa and with the kick
to the left (its README says how they were made; :data:`STORED_RUNS`);
:meth:`whipple_kick.simulate.simulation.Scenario.authors_code` reproduces the code's
assumptions where they differ from this model's (camber sign, start and its
pitch, slip speed, plate stop). This module reads the stored runs and
measures how far a run of this model is from one; docs/validation.md ("The authors' published code") and
``scripts/authors_code_study.py`` use it.

Example
-------
>>> from whipple_kick import authors_code
>>> ref = authors_code.load_run("tests/data/authors_model")                  # doctest: +SKIP
>>> result = run(Scenario.authors_code())                                     # doctest: +SKIP
>>> authors_code.deviations(result.trajectory, ref.samples)["yaw_rate"]       # doctest: +SKIP
0.0179...
"""
from dataclasses import dataclass
import json
import pathlib

import numpy as np
import pandas as pd

from whipple_kick.errors import InputError
from whipple_kick.simulate import analysis

#: This model's trajectory column for each signal of the stored run (their
#: names: Moore's speeds u3 u4 u7, coordinates q4 q7 and the relaxed tyre forces).
SIGNALS = {"yaw_rate": "u3", "roll_rate": "u4", "steer_rate": "u7", "roll": "q4", "steer": "q7",
           "fy_rear": "Fry", "fy_front": "Ffy"}
#: The stored files: the first second after the kick at 1 kHz, and the whole run at 100 Hz.
SAMPLES_FILE = "run_0-1s_1kHz.csv.gz"
WHOLE_RUN_FILE = "run_100Hz.csv.gz"
RUN_FILE = "run.json"
#: The authors' parameter names and the names this model gives the same values
#: (bicycle by Moore's names; tyres per wheel; their c_a*, c_p*, c_m* are
#: placeholders of a linear tyre their standard run does not use).
PARAMETER_NAMES = {"d1": "d1", "d2": "d2", "d3": "d3", "l1": "l1", "l2": "l2", "l3": "l3", "l4": "l4",
                   "rf": "rf", "rr": "rr", "mc": "mc", "md": "md", "me": "me", "mf": "mf",
                   "ic11": "ic11", "ic22": "ic22", "ic33": "ic33", "ic31": "ic31", "id11": "id11",
                   "id22": "id22", "ie11": "ie11", "ie22": "ie22", "ie33": "ie33", "ie31": "ie31",
                   "if11": "if11", "if22": "if22", "g": "g",
                   "k_r": "kzr", "k_f": "kzf", "c_r": "czr", "c_f": "czf", "s_yr": "sigr", "s_yf": "sigf",
                   "r_tr": "rtr", "r_tf": "rtf"}


@dataclass(frozen=True)
class StoredRun:
    """The authors' stored run.

    Attributes
    ----------
    samples : pandas.DataFrame
        ``time`` [s, from the kick start] and :data:`SIGNALS` under this
        model's column names, 0-1 s at 1 kHz.
    whole : pandas.DataFrame
        The same signals and their u1, u2, u6, q3, Frz, Ffz (their names and
        signs: normal forces negative in compression) to the fall, at 100 Hz.
    fall_time_s : float
        When their roll reached 45 deg [s after the kick start].
    initial_state : dict
        Their initial state by their state names.
    parameters : dict
        Their parameter array by their names.
    tyre : dict
        Their tyre: Magic-Formula coefficients ``Fy_coef`` (14), ``Mz_coef``
        (18) and the factor ``Friction_coeff`` on the whole curves.
    """

    samples: "object"
    whole: "object"
    fall_time_s: float
    initial_state: dict
    parameters: dict
    tyre: dict


#: The runs of the authors' code stored in ``tests/data/authors_model``: name -> (folder in it, the
#: changes to :meth:`~whipple_kick.simulate.simulation.Scenario.authors_code` that make the same case). The
#: standard run (the folder itself) is the one the mode was tuned on; the other two were held out.
STORED_RUNS = {"T03_500kPa_635N": (".", {}),
               "T03_400kPa_635N": ("T03_400kPa_635N", {"pressure_kpa": 400.0}),
               "T03_500kPa_635N_kickleft": ("T03_500kPa_635N_kickleft", {"kick_direction": "left"})}


def load_run(folder):
    """Read a stored run from ``folder`` (``tests/data/authors_model`` or one of its :data:`STORED_RUNS`).

    ``run.json`` is either the standard run's record (``initial_state``,
    ``parameters`` and ``tyre`` by name) or the authors' code's own record of
    a held-out run (``x0`` and ``p_arr`` in the orders ``x0_order`` and
    ``p_order``, ``tyre_Fy_coef``, ``tyre_Mz_coef``,
    ``friction_coeff_in_their_tyre_function``), kept as it was written.

    Parameters
    ----------
    folder : str or path-like

    Returns
    -------
    StoredRun

    Raises
    ------
    InputError
        A file is missing.
    """
    folder = pathlib.Path(folder)
    for name in (SAMPLES_FILE, WHOLE_RUN_FILE, RUN_FILE):
        if not (folder / name).is_file():
            raise InputError(f"the authors' stored run needs {folder / name}, which does not exist")
    rename = {theirs: ours for ours, theirs in SIGNALS.items()}
    samples = pd.read_csv(folder / SAMPLES_FILE).rename(columns=rename)
    whole = pd.read_csv(folder / WHOLE_RUN_FILE).rename(columns=rename)
    info = json.loads((folder / RUN_FILE).read_text())
    if "x0" in info:   # the authors' code's own record
        return StoredRun(samples, whole, float(info["fall_time_s"]), dict(zip(info["x0_order"], info["x0"], strict=True)),
                         dict(zip(info["p_order"], info["p_arr"], strict=True)),
                         {"Fy_coef": info["tyre_Fy_coef"], "Mz_coef": info["tyre_Mz_coef"],
                          "Friction_coeff": info["friction_coeff_in_their_tyre_function"]})
    return StoredRun(samples, whole, float(info["fall_time_s"]), info["initial_state"], info["parameters"],
                     info["tyre"])


def deviations(ours, theirs, window=(0.0, 1.0)):
    """Largest difference of each signal over ``window``, as a fraction of the stored run's peak there.

    Parameters
    ----------
    ours : pandas.DataFrame
        A trajectory of this model (time from the kick start).
    theirs : pandas.DataFrame
        The stored run's samples (:attr:`StoredRun.samples` or ``whole``).
    window : (float, float)
        Time span [s after the kick start]; ``ours`` is interpolated to the
        stored samples in it, so it must cover the span.

    Returns
    -------
    dict
        Signal name (:data:`SIGNALS`) -> max ``|ours - theirs|`` / max ``|theirs|`` [-].
    """
    t_ref = theirs["time"].to_numpy()
    keep = (t_ref >= window[0] - 1e-12) & (t_ref <= window[1] + 1e-12)
    t_ours = ours["time"].to_numpy()
    if t_ours[0] > t_ref[keep][0] + 1e-12 or t_ours[-1] < t_ref[keep][-1] - 1e-12:
        raise InputError(f"the run covers [{t_ours[0]:g}, {t_ours[-1]:g}] s, not the window "
                         f"[{window[0]:g}, {window[1]:g}] s")
    out = {}
    for name in SIGNALS:
        ref = theirs[name].to_numpy()[keep]
        mine = np.interp(t_ref[keep], t_ours, ours[name].to_numpy())
        out[name] = float(np.max(np.abs(mine - ref)) / np.max(np.abs(ref)))
    return out


def first_yaw_peak(frame, window=(0.0, 1.0)):
    """(time [s], value [rad/s]) of the first yaw-rate peak after the kick (start) within ``window``.

    :func:`whipple_kick.simulate.analysis.yaw_rate_peaks` (parabola-refined) on the
    window, baseline 0: both the stored run and the compatibility mode start
    from straight running.
    """
    t = frame["time"].to_numpy()
    keep = (t >= window[0] - 1e-12) & (t <= window[1] + 1e-12)
    peaks = analysis.yaw_rate_peaks(t[keep], frame["yaw_rate"].to_numpy()[keep], t_kick=window[0])
    return float(peaks.times[0]), float(peaks.values[0])
