"""The LQR steer-torque "rider" designed on the linearised classic model.

State ``x = [q4, q7, u4, u7]`` (roll, steer, roll rate, steer rate), input
the steer torque ``T7``. The law is ``T7 = -K x`` (python-control's
``lqr`` convention), ``K = [kq4, kq7, ku4, ku7]``. Thesis eq. 8.4 prints the
law without the minus sign; with the signs of its Table 8.4 gains (kq4 < 0,
kq7 > 0) only ``-K x`` stabilises, which ``tests/test_control.py`` proves on
the linear and the nonlinear model.
"""
import control as ct
import numpy as np

from . import classic
from .errors import InputError, check_range

GAIN_ORDER = ("kq4", "kq7", "ku4", "ku7")

#: Thesis Table 8.4: gains used for the Chapter 8 simulations, per rear load
#: [N]; units N m/rad (kq4, kq7) and N m s/rad (ku4, ku7). Applied as
#: T7 = -(kq4 q4 + kq7 q7 + ku4 u4 + ku7 u7).
THESIS_GAINS = {
    570: {"kq4": -18.619, "kq7": 14.721, "ku4": -6.2915, "ku7": 1.5647},
    635: {"kq4": -19.5679, "kq7": 15.4934, "ku4": -6.7665, "ku7": 1.5876},
    701: {"kq4": -20.5164, "kq7": 16.2624, "ku4": -7.3074, "ku7": 1.600},
}


def lqr_gains(moore, speed=3.0, Q=None, R=1.0):
    """LQR gains on the linearised classic model of ``moore`` at ``speed``.

    Parameters
    ----------
    moore : mapping
        Moore parameters (bicycle with rider) by name.
    speed : float
        Design speed [m/s], > 0.
    Q : array_like (4, 4), optional
        State weight (default identity).
    R : float
        Steer-torque weight (default 1).

    Returns
    -------
    K : ndarray, shape (4,)
        ``[kq4, kq7, ku4, ku7]`` for ``T7 = -K x``.
    poles : ndarray, shape (4,), complex
        Closed-loop eigenvalues of ``A - B K``.
    """
    check_range("design speed", speed, 0.0, None, "m/s", low_open=True)
    A, B = classic.linear_state_space(moore, speed)
    Qm = np.eye(4) if Q is None else np.asarray(Q, dtype=float)
    if Qm.shape != (4, 4):
        raise InputError(f"Q must be 4x4, got shape {Qm.shape}")
    K, _, poles = ct.lqr(A, B[:, [1]], Qm, np.atleast_2d(float(R)))
    return np.asarray(K).ravel(), np.asarray(poles)


def gains_dict(K, scale=1.0):
    """Gains by name (``kq4 kq7 ku4 ku7``) from an array, scaled by ``scale``."""
    return {name: float(scale * k) for name, k in zip(GAIN_ORDER, np.ravel(K))}


def thesis_gains(rear_load_n):
    """Table 8.4 gains for one of the thesis' rear loads (570, 635 or 701 N)."""
    load = check_range("rear load", rear_load_n, 0.0, None, "N", low_open=True)
    key = int(round(load))
    if key not in THESIS_GAINS or abs(load - key) > 1e-9:
        raise InputError(f"thesis gains exist for rear loads 570, 635 and 701 N only, got {rear_load_n} N")
    return dict(THESIS_GAINS[key])


def closed_loop_matrix(moore, speed, K):
    """``A - B_T7 K`` of the linearised classic model."""
    A, B = classic.linear_state_space(moore, speed)
    return A - B[:, [1]] @ np.atleast_2d(np.ravel(K))
