"""The Meijaard et al. (2007) benchmark bicycle and its conversion to Moore's parameters.

Two parameterisations of the same Carvallo-Whipple bicycle:

* **Benchmark** (Meijaard, Papadopoulos, Ruina & Schwab 2007, Proc. R. Soc. A
  463:1955-1982, Table 1): origin at the rear contact point, axes x forward,
  z down, in the upright reference configuration. Mass centres ``(xB, zB)``,
  ``(xH, zH)``; inertia tensors about each body's mass centre in those axes,
  ``I = [[Ixx, 0, Ixz], [0, Iyy, 0], [Ixz, 0, Izz]]``; wheelbase ``w``, trail
  ``c``, steer-axis tilt ``lam`` (from vertical), wheel radii ``rR``, ``rF``.
* **Moore** (Moore 2012, PhD thesis, UC Davis): ``d1`` perpendicular distance
  of the rear wheel centre from the steer axis, ``d2`` distance along the steer
  axis between the feet of the perpendiculars from the two wheel centres,
  ``d3`` perpendicular distance of the front wheel centre from the steer axis;
  ``l1, l2`` rear-frame mass centre from the rear wheel centre along C.x, C.z;
  ``l3, l4`` front-frame mass centre from the front wheel centre along E.x,
  E.z; inertias in the rear frame C and front frame E, which are pitched by
  the steer-axis tilt so that C.z/E.z lie along the steer axis.

Both directions are written here from the geometry (not copied from any
package) and tested to round-trip to machine precision.
"""
import math

import numpy as np

from whipple_kick.errors import InputError

#: Names of the benchmark parameters, in the order of Meijaard et al. Table 1.
BENCHMARK_NAMES = (
    "w", "c", "lam", "g",
    "rR", "mR", "IRxx", "IRyy",
    "xB", "zB", "mB", "IBxx", "IByy", "IBzz", "IBxz",
    "xH", "zH", "mH", "IHxx", "IHyy", "IHzz", "IHxz",
    "rF", "mF", "IFxx", "IFyy",
)

#: Names of Moore's parameters of the classic model.
MOORE_NAMES = (
    "d1", "d2", "d3", "l1", "l2", "l3", "l4", "rf", "rr",
    "mc", "md", "me", "mf",
    "ic11", "ic22", "ic33", "ic31", "id11", "id22",
    "ie11", "ie22", "ie33", "ie31", "if11", "if22", "g",
)


def meijaard2007_parameters():
    """Return the benchmark bicycle's parameters (exact values, SI units).

    Source: Meijaard, Papadopoulos, Ruina & Schwab (2007), Proc. R. Soc. A
    463:1955-1982, Table 1. ``lam`` is exactly pi/10 rad.

    Returns
    -------
    dict
        Benchmark-named parameters (see :data:`BENCHMARK_NAMES`).
    """
    return {
        "w": 1.02, "c": 0.08, "lam": math.pi / 10.0, "g": 9.81,
        "rR": 0.3, "mR": 2.0, "IRxx": 0.0603, "IRyy": 0.12,
        "xB": 0.3, "zB": -0.9, "mB": 85.0,
        "IBxx": 9.2, "IByy": 11.0, "IBzz": 2.8, "IBxz": 2.4,
        "xH": 0.9, "zH": -0.7, "mH": 4.0,
        "IHxx": 0.05892, "IHyy": 0.06, "IHzz": 0.00708, "IHxz": -0.00756,
        "rF": 0.35, "mF": 3.0, "IFxx": 0.1405, "IFyy": 0.28,
    }


def _check_names(params, names, what):
    missing = [n for n in names if n not in params]
    if missing:
        raise InputError(f"{what} parameters are missing: {', '.join(missing)}")


def _pitch_matrix(lam):
    """Rows: the pitched frame's x and z axes in benchmark (x fwd, z down) axes, xz-plane only."""
    s, c = math.sin(lam), math.cos(lam)
    # C.x = cos(lam) X - sin(lam) Z (forward and up); C.z = sin(lam) X + cos(lam) Z
    # (along the steer axis, pointing down and forward).
    return np.array([[c, -s], [s, c]])


def _rotate_inertia(ixx, izz, ixz, rot):
    """Planar (xz) part of an inertia tensor expressed in rotated axes: R I R^T."""
    tensor = np.array([[ixx, ixz], [ixz, izz]])
    out = rot @ tensor @ rot.T
    return out[0, 0], out[1, 1], out[1, 0]


def to_moore(bench):
    """Convert benchmark parameters to Moore's parameters.

    Parameters
    ----------
    bench : mapping
        Benchmark-named parameters (:data:`BENCHMARK_NAMES`).

    Returns
    -------
    dict
        Moore-named parameters (:data:`MOORE_NAMES`).
    """
    _check_names(bench, BENCHMARK_NAMES, "benchmark")
    b = {k: float(bench[k]) for k in BENCHMARK_NAMES}
    lam, w, c, rR, rF = b["lam"], b["w"], b["c"], b["rR"], b["rF"]
    rot = _pitch_matrix(lam)
    cx, cz = rot[0], rot[1]  # C.x and C.z in benchmark (x, z) components

    # Points in benchmark (x, z) coordinates: rear wheel centre R, front wheel
    # centre F, and the steer axis' ground intercept P (trail c ahead of F).
    R = np.array([0.0, -rR])
    F = np.array([w, -rF])
    P = np.array([w + c, 0.0])
    d1 = (P - R) @ cx            # perpendicular distance R -> steer axis
    d3 = (F - P) @ cx            # perpendicular distance F -> steer axis
    d2 = (F - R) @ cz            # along the axis between the two feet

    l1, l2 = (np.array([b["xB"], b["zB"]]) - R) @ rot.T
    l3, l4 = (np.array([b["xH"], b["zH"]]) - F) @ rot.T
    ic11, ic33, ic31 = _rotate_inertia(b["IBxx"], b["IBzz"], b["IBxz"], rot)
    ie11, ie33, ie31 = _rotate_inertia(b["IHxx"], b["IHzz"], b["IHxz"], rot)
    return {
        "d1": float(d1), "d2": float(d2), "d3": float(d3),
        "l1": float(l1), "l2": float(l2), "l3": float(l3), "l4": float(l4),
        "rf": rF, "rr": rR,
        "mc": b["mB"], "md": b["mR"], "me": b["mH"], "mf": b["mF"],
        "ic11": float(ic11), "ic22": b["IByy"], "ic33": float(ic33), "ic31": float(ic31),
        "id11": b["IRxx"], "id22": b["IRyy"],
        "ie11": float(ie11), "ie22": b["IHyy"], "ie33": float(ie33), "ie31": float(ie31),
        "if11": b["IFxx"], "if22": b["IFyy"],
        "g": b["g"],
    }


def steer_axis_tilt(moore):
    """Steer-axis tilt ``lam`` [rad] implied by Moore's geometry.

    Upright with both wheels on flat ground, the front wheel centre is
    ``rr - rf`` below the rear one (z down), which fixes the pitch of the
    rear frame: ``d2 cos(lam) - (d1 + d3) sin(lam) = rr - rf``.
    """
    d13 = moore["d1"] + moore["d3"]
    radius = math.hypot(moore["d2"], d13)
    phase = math.atan2(d13, moore["d2"])
    return math.acos((moore["rr"] - moore["rf"]) / radius) - phase


def from_moore(moore):
    """Convert Moore's parameters to benchmark parameters (inverse of :func:`to_moore`).

    Parameters
    ----------
    moore : mapping
        Moore-named parameters (:data:`MOORE_NAMES`).

    Returns
    -------
    dict
        Benchmark-named parameters (:data:`BENCHMARK_NAMES`).
    """
    _check_names(moore, MOORE_NAMES, "Moore")
    m = {k: float(moore[k]) for k in MOORE_NAMES}
    lam = steer_axis_tilt(m)
    rot = _pitch_matrix(lam)
    rR, rF = m["rr"], m["rf"]
    R = np.array([0.0, -rR])
    F = R + rot.T @ np.array([m["d1"] + m["d3"], m["d2"]])
    w = F[0]
    # Steer axis passes through the foot point ce = R + d1 C.x with direction
    # C.z; its ground intercept (z = 0) is x = w + c.
    ce = R + m["d1"] * rot[0]
    t = -ce[1] / rot[1][1]
    c = ce[0] + t * rot[1][0] - w
    xB, zB = R + rot.T @ np.array([m["l1"], m["l2"]])
    xH, zH = F + rot.T @ np.array([m["l3"], m["l4"]])
    IBxx, IBzz, IBxz = _rotate_inertia(m["ic11"], m["ic33"], m["ic31"], rot.T)
    IHxx, IHzz, IHxz = _rotate_inertia(m["ie11"], m["ie33"], m["ie31"], rot.T)
    return {
        "w": float(w), "c": float(c), "lam": float(lam), "g": m["g"],
        "rR": rR, "mR": m["md"], "IRxx": m["id11"], "IRyy": m["id22"],
        "xB": float(xB), "zB": float(zB), "mB": m["mc"],
        "IBxx": float(IBxx), "IByy": m["ic22"], "IBzz": float(IBzz), "IBxz": float(IBxz),
        "xH": float(xH), "zH": float(zH), "mH": m["me"],
        "IHxx": float(IHxx), "IHyy": m["ie22"], "IHzz": float(IHzz), "IHxz": float(IHxz),
        "rF": rF, "mF": m["mf"], "IFxx": m["if11"], "IFyy": m["if22"],
    }


def canonical_matrices():
    """Published canonical matrices of the benchmark bicycle.

    Source: Meijaard et al. (2007), Proc. R. Soc. A 463:1955-1982, eqs.
    (A 21)-(A 24); ``M qdd + v C1 qd + (g K0 + v^2 K2) q = f``
    with ``q = [roll, steer]``.

    Returns
    -------
    dict
        ``M``, ``C1``, ``K0``, ``K2`` as 2x2 arrays.
    """
    return {
        "M": np.array([[80.81722, 2.31941332208709], [2.31941332208709, 0.29784188199686]]),
        "C1": np.array([[0.0, 33.86641391492494], [-0.85035641456978, 1.68540397397560]]),
        "K0": np.array([[-80.95, -2.59951685249872], [-2.59951685249872, -0.80329488458618]]),
        "K2": np.array([[0.0, 76.59734589573222], [0.0, 2.65431523794604]]),
    }


#: Published eigenvalues (Meijaard et al. 2007 Table 2) at v = 0..10 m/s.
#: Each row: (v, weave/real pair, capsize, castor) as listed in that table;
#: at v = 0 both pairs are real (+-).
PUBLISHED_EIGENVALUES = {
    0: (3.13164324790656, -3.13164324790656, 5.53094371765393, -5.53094371765393),
    1: (3.52696170990070 + 0.80774027519930j, 3.52696170990070 - 0.80774027519930j, -3.13423125066578, -7.11008014637442),
    2: (2.68234517512745 + 1.68066296590675j, 2.68234517512745 - 1.68066296590675j, -3.07158645641514, -8.67387984831735),
    3: (1.70675605663975 + 2.31582447384325j, 1.70675605663975 - 2.31582447384325j, -2.63366137253667, -10.35101467245920),
    4: (0.41325331521125 + 3.07910818603206j, 0.41325331521125 - 3.07910818603206j, -1.42944427361326, -12.15861426576450),
    5: (-0.77534188219585 + 4.46486771378823j, -0.77534188219585 - 4.46486771378823j, -0.32286642900409, -14.07838969279820),
    6: (-1.52644486584142 + 5.87673060598709j, -1.52644486584142 - 5.87673060598709j, -0.00406690076970, -16.08537123098030),
    7: (-2.13875644258362 + 7.19525913329805j, -2.13875644258362 - 7.19525913329805j, 0.10268170574766, -18.15788466125262),
    8: (-2.69348683581097 + 8.46037971396931j, -2.69348683581097 - 8.46037971396931j, 0.14327879765713, -20.27940894394569),
    9: (-3.21675402252485 + 9.69377351531791j, -3.21675402252485 - 9.69377351531791j, 0.15790184030917, -22.43788559040858),
    10: (-3.72016840437287 + 10.90681139476287j, -3.72016840437287 - 10.90681139476287j, 0.16105338653172, -24.62459635017404),
}

#: Published critical speeds [m/s] (Meijaard et al. 2007, Section 5).
WEAVE_SPEED = 4.29238253634111
CAPSIZE_SPEED = 6.02426201538837
