"""The LQR steer-torque "rider" designed on the linearised classic model.

State ``x = [q4, q7, u4, u7]`` (roll, steer, roll rate, steer rate), input
the steer torque ``T7``. The law is ``T7 = -K x`` (python-control's
``lqr`` convention), ``K = [kq4, kq7, ku4, ku7]``. Thesis eq. 8.4 prints the
law without the minus sign; with the signs of its Table 8.4 gains (kq4 < 0,
kq7 > 0) only ``-K x`` stabilises, which ``tests/test_control.py`` proves on
the linear and the nonlinear model.

python-control is the solver, but importing it costs more than a second
(it pulls in scipy.signal), so it is imported only when a design is really
solved. :func:`cached_lqr_gains` keeps each design in the per-user cache
(:mod:`.cache`), keyed by everything the result depends on, so a repeated
design (every ``simulate`` run after the first) never imports it.
"""
import functools
import hashlib
import json
import pathlib

import numpy as np

from . import cache, classic
from .errors import InputError, check_range
from .symbols import CLASSIC_CONSTANTS

GAIN_ORDER = ("kq4", "kq7", "ku4", "ku7")
#: Gains of :func:`heading_lqr_gains`, whose state adds the yaw angle q3.
HEADING_GAIN_ORDER = ("kq3",) + GAIN_ORDER

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
    return _solve_lqr(A, B[:, [1]], _weight(Q), R)


def _solve_lqr(A, b, Qm, R):
    """python-control's LQR for one input: (K as a flat array, closed-loop poles)."""
    import control as ct   # slow import: only here, where a design is solved

    K, _, poles = ct.lqr(A, b, Qm, np.atleast_2d(float(R)))
    return np.asarray(K).ravel(), np.asarray(poles)


def heading_state_space(moore, speed):
    """Classic model with the yaw angle as a fifth state, for a heading-holding rider.

    Returns
    -------
    A : ndarray, shape (5, 5)
        For x = [q3, q4, q7, u4, u7]; the q3 row is
        :func:`classic.yaw_rate_map` (q3 itself enters nothing: yaw is cyclic).
    b : ndarray, shape (5, 1)
        Steer-torque column.
    """
    A4, B4 = classic.linear_state_space(moore, speed)
    A = np.zeros((5, 5))
    A[1:, 1:] = A4
    A[0, 1:] = classic.yaw_rate_map(moore, speed)
    b = np.zeros((5, 1))
    b[1:, 0] = B4[:, 1]
    return A, b


def heading_lqr_gains(moore, speed=3.0, Q=None, R=1.0):
    """LQR rider who also steers back to the heading held before a disturbance.

    Same design as :func:`lqr_gains` on the state x = [q3, q4, q7, u4, u7]
    of :func:`heading_state_space`: ``T7 = -K x``. Not the thesis' rider
    (its law has no yaw term); made to measure what holding a heading
    changes. Use the gains with ``simulation.run(..., gains=...)`` on a
    scenario whose steady motion is straight (e.g. symmetric tyres).
    Parameters as for :func:`lqr_gains`, with ``Q`` 5x5.

    Returns
    -------
    K : ndarray, shape (5,)
        ``[kq3, kq4, kq7, ku4, ku7]`` (:data:`HEADING_GAIN_ORDER`).
    poles : ndarray, shape (5,), complex
        Closed-loop eigenvalues.
    """
    check_range("design speed", speed, 0.0, None, "m/s", low_open=True)
    A, b = heading_state_space(moore, speed)
    return _solve_lqr(A, b, _weight(Q, size=5), R)


def _weight(Q, size=4):
    Qm = np.eye(size) if Q is None else np.asarray(Q, dtype=float)
    if Qm.shape != (size, size):
        raise InputError(f"Q must be {size}x{size}, got shape {Qm.shape}")
    return Qm


# ------------------------------------------------------------ cached designs

#: Package modules the design depends on: this one, the linearisation and
#: the generated classic model it evaluates (classic.generated's sources).
_LQR_SOURCES = ("control", "classic", "kane", "benchmark", *classic._SOURCES)
_LQR_LAYOUT = "lqr-v1"   # bump when the entry's contents change


def _solver_versions():
    """Versions of the numerical libraries the solution comes from (without importing python-control)."""
    import importlib.metadata
    import importlib.util
    import scipy

    try:
        control_version = importlib.metadata.version("control")
    except importlib.metadata.PackageNotFoundError:
        control_version = "unknown"
    slycot = importlib.util.find_spec("slycot") is not None   # python-control's lqr prefers it
    return f"control {control_version}; slycot {slycot}; numpy {np.__version__}; scipy {scipy.__version__}"


def _sources_key():
    """Hash of the package sources and solver versions a design depends on.

    Computed once per package folder and version reader (about 1.2 ms; a
    sweep over 200 design speeds reads 200 entries), so pointing the cache
    at another source tree or another reader still changes the key.
    """
    return _sources_key_for(cache._PACKAGE_DIR, _solver_versions)


@functools.lru_cache(maxsize=8)
def _sources_key_for(package_dir, versions):
    # package_dir is the memo's key only: source_hash reads that same folder (cache._PACKAGE_DIR).
    return cache.source_hash(_LQR_SOURCES, extra=versions())


def lqr_cache_key(moore, speed=3.0, Q=None, R=1.0):
    """(entry name, key material) of the cached design of :func:`cached_lqr_gains`.

    The material lists exactly what :func:`lqr_gains` reads: the classic
    model's parameters by name (``repr``, full float precision), the speed,
    ``Q`` and ``R``, plus a hash of the package sources and the solver
    library versions, so that a code or library change misses the cache.
    """
    material = {
        "layout": _LQR_LAYOUT,
        "sources": _sources_key(),
        "parameters": {name: repr(float(moore[name])) for name in CLASSIC_CONSTANTS},
        "speed": repr(float(speed)),
        "Q": [[repr(float(v)) for v in row] for row in _weight(Q)],
        "R": repr(float(R)),
    }
    text = json.dumps(material, sort_keys=True)
    return f"lqr_{hashlib.sha256(text.encode()).hexdigest()[:24]}.json", material


def _read_entry(path, material):
    """(K, poles) from a cache entry, or None if it is unreadable, corrupt or for other inputs."""
    try:
        cache.check_private_file(path)
        data = json.loads(pathlib.Path(path).read_text())
        if data["key"] != material:
            return None
        K = np.array([float(v) for v in data["gains"]])
        poles = np.array([complex(float(re), float(im)) for re, im in data["poles"]])
    except (OSError, ValueError, KeyError, TypeError):
        return None
    if K.shape != (4,) or poles.shape != (4,) or not (np.isfinite(K).all() and np.isfinite(poles).all()):
        return None
    return K, poles


def _entry_text(material, K, poles):
    # json writes floats with repr, which reads back bit for bit.
    return json.dumps({"key": material, "gains": [float(k) for k in K],
                       "poles": [[float(p.real), float(p.imag)] for p in np.asarray(poles, dtype=complex)]},
                      indent=1, allow_nan=False) + "\n"


def cached_lqr_gains(moore, speed=3.0, Q=None, R=1.0):
    """:func:`lqr_gains`, kept in the per-user cache between processes.

    The first call for a design solves it with python-control and stores
    the gains and closed-loop poles (JSON, exact float round trip) under a
    hash of :func:`lqr_cache_key`; later calls, in any process, read them
    back without importing python-control. An entry that cannot be read,
    is corrupt or is not private to this user is solved again and replaced.
    """
    check_range("design speed", speed, 0.0, None, "m/s", low_open=True)
    missing = [n for n in CLASSIC_CONSTANTS if n not in moore]
    if missing:
        return lqr_gains(moore, speed, Q, R)   # raises the InputError naming them
    name, material = lqr_cache_key(moore, speed, Q, R)
    solved = []

    def build(tmp):
        solved.append(lqr_gains(moore, speed, Q, R))
        tmp.write_text(_entry_text(material, *solved[0]))

    path = cache.cache_dir() / name   # a folder another user can write to is refused, as for generated code
    try:
        cache.build_once(name, build)
    except OSError:
        pass   # e.g. an entry another user could have written (PermissionError): replaced below
    if solved:
        return solved[0]
    entry = _read_entry(path, material)
    if entry is None:
        entry = lqr_gains(moore, speed, Q, R)
        try:
            with cache.locked(path):
                cache.write_atomic(path, _entry_text(material, *entry))
        except OSError:
            pass   # the design is right; the next process solves it again
    return entry


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


def closed_loop_poles(moore, speed, gains):
    """Closed-loop poles [1/s] of the linearised classic (no-slip) model with gains by name.

    The rider's law is ``T7 = -(kq3 q3 + kq4 q4 + kq7 q7 + ku3 u3 + ku4 u4 + ku7 u7)``
    (missing gains 0). The yaw rate is a fixed combination of the four states
    (:func:`classic.yaw_rate_map`), so ``ku3`` folds into the other gains; a
    yaw-angle gain ``kq3`` adds the yaw angle as a fifth state
    (:func:`heading_state_space`), otherwise the yaw angle is left out
    (its pole is 0 whatever the rider does).

    Parameters
    ----------
    moore : mapping
        Moore parameters of the bicycle with rider (the plant of the run).
    speed : float
        Forward speed [m/s], > 0.
    gains : mapping
        Gains by name (N m/rad, N m s/rad).

    Returns
    -------
    ndarray, complex
        Sorted by decreasing real part.

    Example
    -------
    >>> from whipple_kick import benchmark, control
    >>> moore = benchmark.to_moore(benchmark.meijaard2007_parameters())
    >>> poles = control.closed_loop_poles(moore, 5.0, {})     # no rider: the benchmark at 5 m/s
    >>> bool(poles[0].real < 0)                                 # self-stable there
    True
    """
    check_range("speed", speed, 0.0, None, "m/s", low_open=True)
    g = {name: float(gains.get(name, 0.0)) for name in ("kq3", "kq4", "kq7", "ku3", "ku4", "ku7")}
    yaw = classic.yaw_rate_map(moore, speed)
    K4 = np.array([g["kq4"], g["kq7"], g["ku4"], g["ku7"]]) + g["ku3"] * yaw
    if g["kq3"]:
        A, b = heading_state_space(moore, speed)
        poles = np.linalg.eigvals(A - b @ np.r_[g["kq3"], K4][None, :])
    else:
        poles = np.linalg.eigvals(closed_loop_matrix(moore, speed, K4))
    return poles[np.argsort(-poles.real, kind="stable")]
