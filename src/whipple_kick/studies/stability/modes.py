"""Modes: where an eigenvector carries its amplitude, the mode names, and tracking across speed."""

import numpy as np
from scipy.optimize import linear_sum_assignment

from whipple_kick.model import parts, reflex, slip
from whipple_kick.model.benchmark import from_moore
from whipple_kick.simulate import results

from ._constants import (
    BODY_GROUPS,
    DOMINANT_SHARE,
    GROUPS,
    MIN_NAME_RUN,
    TYRE_SHARE,
    WOBBLE_MIN_FREQUENCY_HZ,
)

# ------------------------------------------------------------------ mode content

def _wheelbase(moore):
    return float(from_moore(moore)["w"])


def mode_content(model, eigenvalue, vector, wheelbase):
    """Where an eigenvector carries its amplitude, as comparable angles [rad].

    Every state is turned into an angle-like amplitude:

    * roll and steer: their angles;
    * heading: the yaw angle ``u3 tau`` and the lateral displacement
      ``v_lat tau`` over the wheelbase ``w``, with ``tau = 1/max(|lambda|, V/w)``
      (a fast mode's own time scale, or for a slow one the time to roll one
      wheelbase: then ``u3 w/V`` is the steer angle that would make that yaw
      rate and ``v_lat/V`` the drift angle);
    * vertical: the compressions over the wheelbase (the pitch they make);
    * each tyre: how far its contact patch lags the wheel, ``lambda z /
      (-A_zz)`` for a tyre state z (``A_zz = -V/sigma``: the patch lags its
      kinematic slip or camber by ``(sigma/V) dz/dt``), as an angle (the
      force lag's force and moment states divided by their slope in the
      lateral velocity, i.e. by the cornering stiffness and its moment).

    Parameters
    ----------
    model : LinearModel
    eigenvalue : complex or ndarray (k,)
        One eigenvalue, or several.
    vector : ndarray, complex, (n,) or (n, k)
        Right eigenvector(s) of ``model.matrix``, as columns.
    wheelbase : float
        [m].

    Returns
    -------
    shares : ndarray (6,) or (k, 6)
        Fraction of the squared amplitude in each of :data:`GROUPS` (sums to 1).
    scaled : ndarray, complex, (10,) or (10, k)
        The angle-like amplitudes (for the eigenvector similarity of :func:`track`).

    Example
    -------
    >>> from whipple_kick import Scenario
    >>> from whipple_kick.studies.stability import linear_model
    >>> model = linear_model(Scenario(symmetric_tyres=True), 4.0)
    >>> lam, vec = np.linalg.eig(model.matrix)
    >>> shares, scaled = mode_content(model, lam, vec, wheelbase=1.113)
    >>> shares.shape        # one row per eigenvalue, one column per kind of motion
    (14, 6)
    """
    single = np.ndim(eigenvalue) == 0
    lam = np.atleast_1d(np.asarray(eigenvalue, dtype=complex))
    vec = np.asarray(vector, dtype=complex).reshape(len(model.states), -1)
    idx = {n: i for i, n in enumerate(model.states)}
    M = model.matrix
    speed = model.speed
    tau = 1.0 / np.maximum(np.abs(lam), speed / wheelbase)
    lag = []
    body = _body_states()
    bicycle = [n for n in model.states if n not in body]
    for name in bicycle[-4:]:   # tyre slots: rear, front, rear, front
        i = idx[name]
        gain = 1.0
        if name in slip.TYRE_STATES or name in results.CARCASS_STATE_COLUMNS:
            # force-lag forces and moments, carcass deflections: per radian of slip
            gain = abs(M[i, idx["v_lat"]]) * speed / abs(M[i, i])
        lag.append(lam * vec[i] / (-M[i, i]) / gain)
    scaled = np.array([
        vec[idx["q4"]], vec[idx["q7"]],
        vec[idx["u3"]] * tau, vec[idx["v_lat"]] * tau / wheelbase,
        vec[idx["q9"]] / wheelbase, vec[idx["q10"]] / wheelbase,
        *lag,
    ])
    groups = [scaled]
    if len(bicycle) < len(model.states):   # the rider's body: the upper body's lean, the reflex filter
        groups.append(_body_content(model, lam, vec, idx))
    scaled = np.vstack(groups)
    power = np.abs(scaled) ** 2
    shares = [power[0], power[1], power[2] + power[3], power[4] + power[5], power[6] + power[8], power[7] + power[9]]
    if len(groups) > 1:   # the lean: every angle of the body's parts (the rows before the filter's four)
        shares += [power[10:-len(slip.REFLEX_STATES)].sum(axis=0)]
    shares = np.array(shares).T
    total = shares.sum(axis=1, keepdims=True)
    shares = shares / np.where(total > 0, total, 1.0)
    if len(groups) > 1:   # the reflex column: the filter's own share (:func:`filter_share`), not an amplitude
        tau = model.steady.params.get("reflex_delay", 0.0)
        shares = np.column_stack([shares, filter_share(lam, tau) if tau > 0 else np.zeros(lam.size)])
    return (shares[0], scaled[:, 0]) if single else (shares, scaled)


def _body_states():
    """States of the rider's body (after the bicycle's in a :class:`LinearModel`): every declared part's, read
    when called (a part declared after this module was imported counts too), and the reflex filter's."""
    return frozenset(tuple(n for part in parts.REGISTRY.values() for n in part.coordinates + part.speeds)
                     + slip.REFLEX_STATES)


def groups_of(model):
    """The content groups of ``model``'s eigenvectors: :data:`GROUPS`, and :data:`BODY_GROUPS` with a body.

    Example
    -------
    >>> from whipple_kick import Scenario
    >>> from whipple_kick.studies.stability import linear_model
    >>> groups_of(linear_model(Scenario(symmetric_tyres=True), 4.0))
    ('roll', 'steer', 'heading', 'vertical', 'rear_tyre', 'front_tyre')
    """
    return GROUPS + (BODY_GROUPS if any(n in _body_states() for n in model.states) else ())


def _lean_states():
    """Every declared part's coordinates that are angles (their declared column unit rad; the trunk's lean q11),
    read when called (a part declared after this module was imported counts too)."""
    return tuple(n for part in parts.REGISTRY.values() for n in part.coordinates
                 if part.columns.get(n, ("", ""))[1] == "rad")


def _body_content(model, lam, vec, idx):
    """Angle-like amplitudes of the rider body's states: its parts' angles (the lean q11), the reflex filter's.

    The upper body's lean on the hip is an angle [rad] like the roll (each angle a part declares, at least
    one row). The
    reflex filter's states are torques [N m] (controllable canonical form of
    :mod:`whipple_kick.model.reflex`): divided by the reflex's torque per radian
    of motion at this eigenvalue, ``|rq4| + |rq7| + |lambda| (|ru4| + |ru7|)``
    (at least 1 N m/rad), they compare with the angles that drive them.
    Rows: the parts' angles the model has (one row of zeros without any), then the four filter states (zero
    where the model lacks them).
    """
    n = lam.size
    lean = [vec[idx[q]] for q in _lean_states() if q in idx] or [np.zeros(n)]
    p = model.steady.params
    per_rad = np.maximum(abs(p.get("rq4", 0.0)) + abs(p.get("rq7", 0.0))
                         + np.abs(lam) * (abs(p.get("ru4", 0.0)) + abs(p.get("ru7", 0.0))), 1.0)
    reflex = [vec[idx[r]] / per_rad if r in idx else np.zeros(n) for r in slip.REFLEX_STATES]
    return np.array([*lean, *reflex])


def filter_share(lam, tau):
    """How far the reflex's Pade filter departs from the delay at ``lam``: ``1 - |exp(-lam tau)| / |H(lam)|`` (>= 0).

    In any eigenvector the filter's states are its driven response, ``z =
    (lam tau I - A)^-1 B r``: what tells a filter pole from a motion of the
    bicycle the filter delays is the eigenvalue itself. Where the filter
    transfer ``H`` is the delay it approximates (a motion slow against
    ``1/tau``), this is about 0; near the filter's own poles ``|H|`` grows
    without bound and it tends to 1 (0.5 where the filter amplifies twice
    as much as the delay would).

    Example
    -------
    >>> round(float(filter_share(np.array([-0.5 + 3j]), 0.1)[0]), 3)
    0.0
    """
    num, den = reflex.pade_coefficients(reflex.NUMERATOR_DEGREE, reflex.ORDER)
    x = np.atleast_1d(np.asarray(lam, dtype=complex)) * tau
    H = np.abs(np.polyval(num[::-1], x) / np.polyval(den[::-1], x))
    delay = np.abs(np.exp(-x))
    return np.clip(1.0 - delay / np.where(H > 0, H, np.inf), 0.0, 1.0)


def name_mode(shares, real, frequency_hz, arms=False):
    """Name a mode from its content (:func:`mode_content` shares, averaged over a branch).

    Rules, in order (shares of :data:`GROUPS`; dominant = at least
    :data:`DOMINANT_SHARE`):

    1. vertical dominant -> ``vertical``;
    2. non-oscillatory: the two tyres' lag together dominant ->
       ``relaxation_rear`` or ``relaxation_front`` (the larger lag); else
       roll >= steer -> ``capsize``, steer > roll -> ``caster``;
    3. oscillatory, steer the largest mechanical share (roll, steer,
       heading) and the front tyre's lag above the rear's, above roll and
       at least :data:`TYRE_SHARE`:
       ``wobble`` from :data:`WOBBLE_MIN_FREQUENCY_HZ` up, ``caster`` below
       it (at walking speed the caster mode and the front tyre's relaxation
       combine into a slow oscillation);
    4. oscillatory, the tyres' lag together dominant -> ``lateral_rear`` or
       ``lateral_front`` (the larger lag): the frame swaying on the tyres'
       lateral carcass stiffness;
    5. otherwise ``weave``.

    Parameters
    ----------
    shares : array_like
        Shares of :data:`GROUPS`.
    real : bool
        Non-oscillatory (real eigenvalue).
    frequency_hz : float
        Damped frequency [Hz] (0 when real).

    Returns
    -------
    str
        One of :data:`MODES`.

    Example
    -------
    >>> name_mode([0.9, 0.05, 0.05, 0, 0, 0], True, 0.0)
    'capsize'
    """
    roll, steer, heading, vertical, rear, front, lean, reflex = (
        [float(s) for s in shares] + [0.0] * len(BODY_GROUPS))[:len(GROUPS) + len(BODY_GROUPS)]
    if reflex >= DOMINANT_SHARE:
        return "reflex_delay"
    if vertical >= DOMINANT_SHARE:
        return "vertical"
    if lean >= max(roll, steer, heading, rear, front):
        return "lean"
    if real:
        if rear + front >= DOMINANT_SHARE:
            return "relaxation_rear" if rear >= front else "relaxation_front"
        return "capsize" if roll >= steer else "caster"
    if steer >= max(roll, heading) and front > max(rear, roll, TYRE_SHARE):
        return "wobble" if frequency_hz >= WOBBLE_MIN_FREQUENCY_HZ else "caster"
    if arms and steer >= max(roll, heading, lean) and frequency_hz >= WOBBLE_MIN_FREQUENCY_HZ:
        return "arm_steer"
    if rear + front >= DOMINANT_SHARE:
        return "lateral_rear" if rear >= front else "lateral_front"
    return "weave"


# ------------------------------------------------------------------ mode tracking

def _mac(a, b):
    """Modal assurance criterion |a^H b|^2 / (|a|^2 |b|^2) between columns of ``a`` and ``b``."""
    num = np.abs(a.conj().T @ b) ** 2
    den = np.outer(np.sum(np.abs(a) ** 2, axis=0), np.sum(np.abs(b) ** 2, axis=0))
    return num / np.where(den > 0, den, 1.0)


def match_cost(lam_a, vec_a, lam_b, vec_b):
    """Cost of calling eigenpair j of b the continuation of i of a: distance plus (1 - MAC).

    ``|lam_i - lam_j| / (|lam_i| + |lam_j| + 1 1/s)`` (0 for equal
    eigenvalues, about 1 for unrelated ones) plus one minus the modal
    assurance criterion of the angle-like eigenvectors (0 for the same shape,
    1 for orthogonal ones).

    Parameters
    ----------
    lam_a, lam_b : ndarray (n,), (m,)
        Eigenvalues at two neighbouring speeds.
    vec_a, vec_b : ndarray (p, n), (p, m)
        Their angle-like eigenvectors (:func:`mode_content`) as columns.

    Returns
    -------
    ndarray (n, m)

    Example
    -------
    >>> match_cost(np.array([1j]), np.array([[1.0]]), np.array([1j]), np.array([[2.0]]))
    array([[0.]])
    """
    la, lb = np.asarray(lam_a)[:, None], np.asarray(lam_b)[None, :]
    return np.abs(la - lb) / (np.abs(la) + np.abs(lb) + 1.0) + (1.0 - _mac(vec_a, vec_b))


def track(eigenvalues, vectors):
    """Follow each eigenvalue across consecutive speeds.

    Parameters
    ----------
    eigenvalues : list of ndarray (n,)
        Eigenvalues at each speed (``None`` where there is no model: the
        tracks restart after it).
    vectors : list of ndarray (m, n)
        Angle-like eigenvectors (:func:`mode_content`) as columns.

    Returns
    -------
    list of ndarray (n,) of int
        Track number of each eigenvalue at each speed: at each step the
        optimal assignment (Hungarian method) of :func:`match_cost`, so two
        modes crossing in real part keep their identity when their
        eigenvalues or shapes differ.

    Example
    -------
    >>> lams = [np.array([-1.0, -2.0]), np.array([-2.1, -0.9])]
    >>> vecs = [np.eye(2), np.eye(2)[:, ::-1]]
    >>> [ids.tolist() for ids in track(lams, vecs)]
    [[0, 1], [1, 0]]
    """
    ids, next_id, prev = [], 0, None
    for lam, vec in zip(eigenvalues, vectors, strict=True):
        if lam is None:
            ids.append(None)
            prev = None
            continue
        if prev is None:
            cur = np.arange(next_id, next_id + lam.size)
            next_id += lam.size
        else:
            rows, cols = linear_sum_assignment(match_cost(prev[0], prev[1], lam, vec))
            cur = np.empty(lam.size, dtype=int)
            cur[cols] = prev[2][rows]
        ids.append(cur)
        prev = (lam, vec, cur)
    return ids


def _segments(flags):
    """Maximal runs of equal values in ``flags``: list of (start, stop) index pairs (stop exclusive)."""
    out, start = [], 0
    for k in range(1, len(flags) + 1):
        if k == len(flags) or flags[k] != flags[start]:
            out.append((start, k))
            start = k
    return out


def _merge_short_runs(names, min_run):
    """``names`` with every run shorter than ``min_run`` absorbed by its longer neighbour (shortest first)."""
    names = list(names)
    while True:
        runs = _segments(names)
        if len(runs) < 2:
            return names
        lengths = [stop - start for start, stop in runs]
        k = int(np.argmin(lengths))
        if lengths[k] >= min_run:
            return names
        left = lengths[k - 1] if k > 0 else -1
        right = lengths[k + 1] if k + 1 < len(runs) else -1
        donor = runs[k - 1] if left >= right else runs[k + 1]
        start, stop = runs[k]
        names[start:stop] = [names[donor[0]]] * (stop - start)


def name_tracks(points, min_run=MIN_NAME_RUN):
    """Name every point of every track from its own eigenvector content, without flicker.

    Each point gets :func:`name_mode` of its own shares. Along a track, a
    name can change only where the eigenvalue turns real or complex (a pair
    splitting or two merging) or where the eigenvector's content changes
    (two modes exchanging character where their eigenvalues veer); a run of
    fewer than ``min_run`` speeds with another name is absorbed by its
    longer neighbour, so a content hovering near a rule's threshold does not
    flicker. Where two modes merely cross in real part nothing changes,
    since tracking follows each eigenvector (:func:`track`).

    Parameters
    ----------
    points : list of dict
        Each with ``track``, ``speed_index``, ``real`` (bool), ``frequency_hz``
        and ``shares``; ``mode`` is set in place.
    min_run : int
        Fewest consecutive speeds a name must hold within a branch.

    Example
    -------
    >>> pts = [{"track": 0, "speed_index": k, "real": True, "frequency_hz": 0.0,
    ...         "shares": [0.9, 0.1, 0, 0, 0, 0]} for k in range(4)]
    >>> name_tracks(pts); [p["mode"] for p in pts]
    ['capsize', 'capsize', 'capsize', 'capsize']
    """
    by_track = {}
    for p in points:
        by_track.setdefault(p["track"], []).append(p)
    for pts in by_track.values():
        pts.sort(key=lambda p: p["speed_index"])
        # A branch: consecutive speeds of one character (real or complex).
        keys = []
        for k, p in enumerate(pts):
            gap = k and p["speed_index"] != pts[k - 1]["speed_index"] + 1
            keys.append((keys[-1][0] + 1 if gap else (keys[-1][0] if keys else 0), p["real"]))
        for start, stop in _segments(keys):
            branch = pts[start:stop]
            names = [name_mode(p["shares"], p["real"], p["frequency_hz"], p.get("arms", False)) for p in branch]
            for p, name in zip(branch, _merge_short_runs(names, min_run), strict=True):
                p["mode"] = name
