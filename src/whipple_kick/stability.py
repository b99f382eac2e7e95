"""Linear stability of the slip model against speed: weave, capsize, wobble and the tyre modes.

For a bicycle, rider, tyre, pressure and load (a
:class:`whipple_kick.scenario.Scenario`), at each speed of a sweep:

1. the steady motion is found (:func:`whipple_kick.slip.steady_state`,
   continued from the previous speed's solution; the robust
   :func:`whipple_kick.steady.find_steady_state` where that fails);
2. the slip model is linearised about it in the heading frame
   (:func:`whipple_kick.slip.heading_linearisation`) at constant speed (the
   forward-speed row and column removed, as the classic model treats speed
   as a parameter), open loop (no steer torque; about the uncontrolled
   steady motion) and closed loop (the scenario's rider, designed at each
   speed unless ``design_speed`` fixes it);
3. its eigenvalues and eigenvectors are followed across speed
   (:func:`track`: eigenvalue distance plus eigenvector dissimilarity,
   optimal assignment) and each mode is named from where its eigenvector
   carries its amplitude (:func:`mode_content`, :func:`name_mode`).

The classic no-slip model of the same bicycle (and rider) is computed beside
it. :func:`analyse` returns the tables and a summary (weave and capsize
speeds, self-stable speed range, wobble); :func:`linear_model` gives the
linear model at one speed as a :class:`LinearModel`, whose
:meth:`LinearModel.state_space` is a ``control.StateSpace`` with named states,
the steer torque as input and the states as outputs. The ``stability``
command writes ``eigenvalues.csv``, ``stability.png`` and ``summary.json``
(docs/stability.md).

Example
-------
>>> import numpy as np
>>> from whipple_kick import stability
>>> from whipple_kick import Scenario
>>> result = stability.analyse(Scenario(symmetric_tyres=True), np.arange(2.0, 6.01, 0.5),
...                            loops=("open",))
>>> round(result.summary["slip"]["open"]["weave_speed_m_s"], 2)
3.82
"""
from dataclasses import dataclass, field
import math

import numpy as np

from . import assembly, fileio, results, slip
from .errors import InputError, check_range
from .scenario import Scenario

#: Loops analysed: without rider control, and with the scenario's rider.
LOOPS = ("open", "closed")
#: Content groups of an eigenvector (:func:`mode_content`).
GROUPS = ("roll", "steer", "heading", "vertical", "rear_tyre", "front_tyre")
#: Mode names (:func:`name_mode`), in the order the figure's legend lists them.
MODES = ("weave", "capsize", "caster", "wobble", "lateral_rear", "lateral_front", "relaxation_rear",
         "relaxation_front", "vertical")
#: What each mode name means (summary.json, docs/stability.md).
MODE_DESCRIPTIONS = {
    "weave": "oscillation of roll, steer and heading together (the knife-edge bicycle's weave)",
    "capsize": "non-oscillatory, roll-dominated: the bicycle falls over slowly (or recovers)",
    "caster": "steer-dominated, non-oscillatory or slow: the front frame aligns with its motion",
    "wobble": "steer-dominated oscillation with the front tyre lagging, faster than WOBBLE_MIN_FREQUENCY_HZ",
    "lateral_rear": "fast oscillation of heading and lateral position on the rear tyre's lateral "
                    "carcass stiffness (cornering stiffness / relaxation length), little roll or steer",
    "lateral_front": "the same on the front tyre",
    "relaxation_rear": "non-oscillatory, the rear tyre's contact patch relaxing toward its kinematic slip",
    "relaxation_front": "the same for the front tyre",
    "vertical": "tyre compressions (bounce and pitch on the vertical tyre stiffness)",
}
#: A steer-dominated oscillation slower than this [Hz] is the caster mode coupled with the
#: front tyre's relaxation (at walking speed), not wobble: bicycle wobble is reported at
#: 4-10 Hz (thesis Section 2.2.1; Meijaard et al. 2007 call the fast steer mode caster).
WOBBLE_MIN_FREQUENCY_HZ = 2.0
#: |steer torque| [N m] below which a steady motion of one loop is also the other loop's.
ZERO_TORQUE_N_M = 1e-12
#: Fewest consecutive sweep speeds a mode name must hold along a track (shorter runs take a
#: neighbour's name): no flicker where a content hovers near a rule's threshold.
MIN_NAME_RUN = 3
#: A share of at least this of an eigenvector's amplitude makes a group dominant.
DOMINANT_SHARE = 0.5
#: The front tyre takes part in a steer oscillation (wobble, or the slow caster pair) with at
#: least this share; the weave's front-tyre lag is 0.01-0.04.
TYRE_SHARE = 0.1
#: Default speed sweep [m/s] of the ``stability`` command: start, stop, step.
DEFAULT_SPEEDS = (0.5, 10.0, 0.05)
#: A steady lean above this [deg] is reported: the eigenvalues are then those of a turn.
TURN_NOTE_DEG = 5.0
#: Largest number of speeds in one sweep (about 10 ms each).
MAX_SPEEDS = 2000

# Heading-frame states at constant speed and how the summary and StateSpace name them.
STATES = tuple(n for n in slip.LINEAR_STATES if n != "v_fwd")
_LABELS = {
    **{q: col for q, col in results.COORDINATE_COLUMNS.items()},
    **{u: col for u, col in results.SPEED_COLUMNS.items()},
    **{state: (col, "rad") for state, col in results.PATCH_STATE_COLUMNS.items()},
    **{state: (col, "m") for state, col in results.CARCASS_STATE_COLUMNS.items()},
    "v_fwd": ("forward_velocity", "m/s"), "v_lat": ("lateral_velocity", "m/s"),
    "fyr": ("fy_rear", "N"), "fyf": ("fy_front", "N"), "mzr": ("mz_rear", "N m"), "mzf": ("mz_front", "N m"),
}


def state_labels(transient=slip.transient.DEFAULT_TRANSIENT, constant_speed=True):
    """(name, unit) of each state of the linear model, in order.

    Parameters
    ----------
    transient : str
        Tyre transient form (names the four tyre states).
    constant_speed : bool
        Without the forward velocity (the default model).

    Returns
    -------
    list of (str, str)

    Example
    -------
    >>> state_labels()[:2]
    [('roll', 'rad'), ('steer', 'rad')]
    """
    names = slip.linear_states(transient)
    return [_LABELS[n] for n in names if not (constant_speed and n == "v_fwd")]


# ----------------------------------------------------------------- linear model

@dataclass
class LinearModel:
    """The slip model linearised about its steady motion at one speed.

    Attributes
    ----------
    speed : float
        Forward speed [m/s].
    loop : str
        ``"open"`` (steady motion without steer torque) or ``"closed"``
        (steady motion with the rider).
    A : ndarray (n, n)
        Open-loop state matrix (no steer torque beyond the steady one).
    B : ndarray (n, 1)
        Steer torque T7 [N m] input.
    K : ndarray (1, n)
        The rider's gains on these states (``T7 = -K x``); zero open loop.
    states : tuple of str
        Model state names (:data:`whipple_kick.slip.LINEAR_STATES` order).
    labels : list of (str, str)
        Readable name and unit of each state.
    steady : whipple_kick.slip.SteadyState
        The steady motion linearised about.
    found_by : str
        How the steady motion was found.
    """

    speed: float
    loop: str
    A: np.ndarray
    B: np.ndarray
    K: np.ndarray
    states: tuple
    labels: list
    steady: object
    found_by: str = "direct"

    @property
    def matrix(self):
        """State matrix of this loop: ``A`` open loop, ``A - B K`` closed loop."""
        return self.A - self.B @ self.K if self.loop == "closed" else self.A

    def state_space(self, closed=None):
        """``control.StateSpace`` with named states, input ``steer_torque`` [N m], outputs = states.

        Parameters
        ----------
        closed : bool, optional
            ``A - B K`` (the rider's loop closed; the input is then a steer
            torque added to the rider's) or ``A``; default: this model's loop.

        Example
        -------
        >>> sys = linear_model(Scenario(symmetric_tyres=True), 4.0).state_space()
        >>> sys.input_labels
        ['steer_torque']
        """
        import control as ct  # slow import: only when asked for
        closed = self.loop == "closed" if closed is None else closed
        names = [name for name, _ in self.labels]
        n = len(names)
        return ct.ss(self.A - self.B @ self.K if closed else self.A, self.B, np.eye(n), np.zeros((n, 1)),
                     states=names, inputs=["steer_torque"], outputs=names,
                     name=f"slip model at {self.speed:g} m/s ({'closed' if closed else 'open'} loop)")


def _constant_speed(A, B):
    keep = [i for i, n in enumerate(slip.LINEAR_STATES) if n != "v_fwd"]
    return A[np.ix_(keep, keep)], B[keep]


def _gains_vector(params, states):
    """The rider's gains on ``states`` (``T7 = -K x``; the yaw-angle gain is refused)."""
    if params.get("kq3", 0.0):
        raise InputError("a yaw-angle gain kq3 breaks the heading invariance the linear model needs")
    K = np.zeros((1, len(states)))
    for gain, state in (("kq4", "q4"), ("kq7", "q7"), ("ku3", "u3"), ("ku4", "u4"), ("ku7", "u7")):
        K[0, states.index(state)] = params.get(gain, 0.0)
    return K


def linearise(params, steady_state, loop, found_by="direct", constant_speed=True):
    """:class:`LinearModel` of the slip model with ``params`` about ``steady_state``.

    Parameters
    ----------
    params : mapping
        Slip-model parameters; their gains are the rider's (0 for ``loop="open"``).
    steady_state : whipple_kick.slip.SteadyState
        A steady motion of ``params``.
    loop : {"open", "closed"}
    found_by : str
        Carried into the model.
    constant_speed : bool
        Drop the forward velocity (default).

    Returns
    -------
    LinearModel

    Example
    -------
    Skipped as a doctest: a fragment, ``moore``, ``rear`` and ``front`` being a
    bicycle's Moore parameters and two tyres (:func:`linear_model` does all of
    this from a Scenario).

    >>> params = slip.model_parameters(moore, rear, front)              # doctest: +SKIP
    >>> model = linearise(params, slip.steady_state(params, 4.0), "open")   # doctest: +SKIP
    """
    rhs = slip.CompiledRHS(steady_state.params)
    J, B = slip.heading_linearisation(rhs, steady_state.x)
    states = slip.linear_states(rhs.transient)
    if constant_speed:
        J, B = _constant_speed(J, B)
        states = tuple(n for n in states if n not in ("v_fwd",))
    # The model as parametrised is A - B K; the open loop adds B K back.
    K = _gains_vector(params, list(slip.LINEAR_STATES if not constant_speed else STATES))
    return LinearModel(speed=float(steady_state.x[slip.X["u1"]]), loop=loop, A=J + B @ K, B=B,
                       K=K if loop == "closed" else np.zeros_like(K), states=tuple(states),
                       labels=state_labels(rhs.transient, constant_speed), steady=steady_state,
                       found_by=found_by)


@dataclass
class _Setup:
    """Everything of a scenario the sweep needs, built once."""

    scenario: object
    moore: dict
    design: dict
    info: dict
    tyres: tuple
    notes: list
    controller: str


def _setup(scenario, tyres=None):
    assembly.preflight(scenario)
    moore, design, info = assembly.build_bicycle(scenario)
    if tyres is None:
        rear, front, notes = assembly.build_tyres(scenario)
    else:
        (rear, front), notes = tyres, [f"tyres given: {tyres[0]!r} (rear), {tyres[1]!r} (front)"]
    return _Setup(scenario, moore, design, info, (rear, front), notes, scenario.controller)


def _base_params(setup):
    """Slip-model parameters of the scenario without steer control."""
    sc = setup.scenario
    return slip.model_parameters(setup.moore, *setup.tyres, symmetric=sc.symmetric_tyres,
                                 tyre_transient=sc.tyre_transient,
                                 reverse_camber=sc.camber_sign == "reversed", slip_speed=sc.slip_speed)


def _loop_params(setup, speed, loop, base=None):
    """Slip-model parameters at ``speed`` for ``loop`` (the rider's gains designed for that speed)."""
    params = dict(_base_params(setup) if base is None else base)
    if loop == "closed":
        gains, _ = assembly.controller_gains(setup.scenario.with_changes(speed=float(speed)),
                                               setup.design)
        params.update(gains)
    return params


def _steady(params, speed, guess):
    """(SteadyState, found_by): continued from ``guess``, else the robust search (may raise NoSteadyMotion)."""
    from . import steady
    if guess is not None:
        try:
            return slip.steady_state(params, speed, guess=guess), "continued"
        except FloatingPointError:
            pass
    found = steady.find_steady_state(params, speed)
    return found.steady, found.route


def linear_model(scenario, speed, loop="open", *, tyres=None):
    """The slip model of ``scenario`` linearised about its steady motion at ``speed`` [m/s].

    Parameters
    ----------
    scenario : whipple_kick.scenario.Scenario
        Bicycle, rider, tyres, controller (its speed is replaced by ``speed``).
    speed : float
        Forward speed [m/s].
    loop : {"open", "closed"}
        Without steer torque, or with the scenario's rider (designed at
        ``speed`` unless ``design_speed`` is set).
    tyres : (rear, front), optional
        Tyre objects instead of the scenario's (e.g. ``tyres.linear_tyre``).

    Returns
    -------
    LinearModel

    Example
    -------
    >>> from whipple_kick import Scenario
    >>> model = linear_model(Scenario(symmetric_tyres=True), 4.0)
    >>> model.state_space().nstates
    14
    """
    _check_loop(loop)
    speed = check_range("speed", speed, 0.0, 15.0, "m/s", low_open=True)
    setup = _setup(scenario.with_changes(speed=float(speed)), tyres)
    params = _loop_params(setup, speed, loop)
    steady_state, found_by = _steady(params, speed, None)
    return linearise(params, steady_state, loop, found_by)


def _check_loop(loop):
    if loop not in LOOPS:
        raise InputError(f"loop {loop!r} is unknown; choose one of {', '.join(LOOPS)}")


# ------------------------------------------------------------------ mode content

def _wheelbase(moore):
    from .benchmark import from_moore
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
    for name in model.states[-4:]:   # tyre slots: rear, front, rear, front
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
    power = np.abs(scaled) ** 2
    shares = np.array([power[0], power[1], power[2] + power[3], power[4] + power[5],
                       power[6] + power[8], power[7] + power[9]]).T
    total = shares.sum(axis=1, keepdims=True)
    shares = shares / np.where(total > 0, total, 1.0)
    return (shares[0], scaled[:, 0]) if single else (shares, scaled)


def name_mode(shares, real, frequency_hz):
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
    roll, steer, heading, vertical, rear, front = (float(s) for s in shares)
    if vertical >= DOMINANT_SHARE:
        return "vertical"
    if real:
        if rear + front >= DOMINANT_SHARE:
            return "relaxation_rear" if rear >= front else "relaxation_front"
        return "capsize" if roll >= steer else "caster"
    if steer >= max(roll, heading) and front > max(rear, roll, TYRE_SHARE):
        return "wobble" if frequency_hz >= WOBBLE_MIN_FREQUENCY_HZ else "caster"
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
    from scipy.optimize import linear_sum_assignment
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
            names = [name_mode(p["shares"], p["real"], p["frequency_hz"]) for p in branch]
            for p, name in zip(branch, _merge_short_runs(names, min_run), strict=True):
                p["mode"] = name


# ------------------------------------------------------------------ the sweep

class _Loop:
    """Linear models of one loop at any speed, with the steady motion continued between calls."""

    def __init__(self, setup, loop, wheelbase):
        self.setup, self.loop, self.wheelbase = setup, loop, wheelbase
        self.base = _base_params(setup)

    def model(self, speed, guess=None, other=None):
        """LinearModel at ``speed`` (NoSteadyMotion if there is none).

        ``other``: the other loop's steady motion at this speed. Where the
        rider's torque there is zero (upright straight running, symmetric
        tyres: ``T7 = -K x`` with x = 0) it is this loop's steady motion too,
        and no solve is needed.
        """
        params = _loop_params(self.setup, speed, self.loop, self.base)
        if other is not None:
            shared = slip.SteadyState(other.x, {**params, **{n: other.params[n] for n in slip.STEADY_PARAMETERS}},
                                      other.residual, other.unknowns)
            rhs = slip.CompiledRHS(shared.params)
            if abs(rhs.outputs(0.0, shared.x)[1][slip.OUT["T7"]]) < ZERO_TORQUE_N_M:
                return linearise(params, shared, self.loop, "the other loop's (no steer torque)")
        steady_state, found_by = _steady(params, speed, guess)
        return linearise(params, steady_state, self.loop, found_by)

    def eigen(self, model):
        """(eigenvalues, angle-like eigenvectors as columns, shares per eigenvalue)."""
        lam, vec = np.linalg.eig(model.matrix)
        shares, scaled = mode_content(model, lam, vec, self.wheelbase)
        return lam, scaled, shares


def _classic_eigen(canonical, speed, K=None):
    """Eigenvalues and eigenvectors of the classic model from its canonical matrices (rider gains K)."""
    M, C1, K0, K2 = (canonical[k] for k in ("M", "C1", "K0", "K2"))
    g = canonical["g"]
    Minv = np.linalg.inv(M)
    A = np.zeros((4, 4))
    A[:2, 2:] = np.eye(2)
    A[2:, :2] = -Minv @ (g * K0 + speed**2 * K2)
    A[2:, 2:] = -speed * Minv @ C1
    if K is not None:
        b = np.zeros((4, 1))
        b[2:, 0] = Minv[:, 1]
        A = A - b @ np.atleast_2d(K)
    return np.linalg.eig(A)


def _classic_content(lam, vec):
    """Shares of :data:`GROUPS` of the classic model's eigenvectors (roll and steer only)."""
    power = np.abs(vec[:2]) ** 2
    power = power / np.where(power.sum(axis=0) > 0, power.sum(axis=0), 1.0)
    shares = np.zeros((lam.size, len(GROUPS)))
    shares[:, 0], shares[:, 1] = power[0], power[1]
    return vec[:2], shares


@dataclass
class Stability:
    """Outcome of :func:`analyse`.

    Attributes
    ----------
    scenario : whipple_kick.scenario.Scenario
    speeds : ndarray
        Speeds of the sweep [m/s].
    eigenvalues : pandas.DataFrame
        One row per eigenvalue, loop and speed: ``model`` ("slip" or
        "no-slip"), ``loop``, ``speed_m_s``, ``track`` (the followed
        eigenvalue), ``mode`` (:data:`MODES`), ``real_1_s``, ``imag_1_s``,
        ``frequency_hz``, ``damping_ratio`` and the ``share_*`` of
        :data:`GROUPS`.
    steady : pandas.DataFrame
        The steady motion at each loop and speed (lean, steer, yaw rate,
        drift, rear-wheel torque, how it was found, or why there is none).
    summary : dict
        JSON-ready: per loop the weave and capsize speeds, the stable speed
        ranges, the wobble, each mode's speed range; the same for the no-slip model.
    models : dict
        ``(loop, speed index) -> LinearModel``.
    """

    scenario: object
    speeds: np.ndarray
    eigenvalues: object
    steady: object
    summary: dict = field(default_factory=dict)
    models: dict = field(default_factory=dict)

    def state_space(self, speed, loop="closed"):
        """``control.StateSpace`` of the linear model at the sweep speed nearest ``speed``."""
        _check_loop(loop)
        k = int(np.argmin(np.abs(self.speeds - speed)))
        if (loop, k) not in self.models:
            raise InputError(f"no {loop}-loop model at {self.speeds[k]:g} m/s (no steady motion there, "
                             "or that loop was not analysed)")
        return self.models[loop, k].state_space()


def parse_speeds(text):
    """Speeds [m/s] from ``START:STOP:STEP`` (STOP included when on the grid) or ``V1,V2,...``.

    Parameters
    ----------
    text : str

    Returns
    -------
    ndarray
        Strictly increasing speeds in (0, 15] m/s, at most :data:`MAX_SPEEDS`.

    Raises
    ------
    InputError
        One line naming the text, the rule and the unit.

    Example
    -------
    >>> parse_speeds("1:2:0.5")
    array([1. , 1.5, 2. ])
    """
    text = str(text).strip()
    try:
        parts = [float(p) for p in text.split(":" if ":" in text else ",")]
    except ValueError:
        parts = None
    if parts is None or (":" in text and len(parts) != 3):
        raise InputError(f"speeds {text!r} are not START:STOP:STEP or a comma-separated list (m/s)")
    if ":" not in text:
        return check_speeds(parts)
    start, stop, step = parts
    check_range("speed step", step, 0.0, None, "m/s", low_open=True)
    count = math.floor((stop - start) / step + 1e-9) + 1
    if count < 1:
        raise InputError(f"speeds {text!r}: STOP {stop:g} m/s is below START {start:g} m/s")
    if count > MAX_SPEEDS:
        raise InputError(f"speeds {text!r} give {count} speeds; allowed at most {MAX_SPEEDS}")
    # Rounded to 1e-12 m/s, so that 0.5 + 190 * 0.05 is 10 and not 10.000000000000009.
    return check_speeds(np.round(start + step * np.arange(count), 12))


def check_speeds(speeds):
    """Speeds as a strictly increasing array, each in (0, 15] m/s; InputError otherwise.

    Example
    -------
    >>> check_speeds([1, 2.5])
    array([1. , 2.5])
    """
    speeds = np.atleast_1d(np.asarray(speeds, dtype=float))
    if speeds.size == 0 or speeds.size > MAX_SPEEDS:
        raise InputError(f"give 1 to {MAX_SPEEDS} speeds, got {speeds.size}")
    for v in speeds:
        check_range("speed", float(v), 0.0, 15.0, "m/s", low_open=True)
    if np.any(np.diff(speeds) <= 0):
        raise InputError("speeds must increase strictly (m/s)")
    return speeds


def analyse(scenario, speeds, *, loops=None, tyres=None):
    """Eigenvalues of the slip model and of the no-slip model across ``speeds``, with named modes.

    Parameters
    ----------
    scenario : whipple_kick.scenario.Scenario
        Bicycle, rider, tyres, controller. Its kick and run fields are not
        used, nor its speed. With the measured tyres' zero-slip offsets the
        steady motions are turns (large ones where the loop has a real
        eigenvalue near zero): ``symmetric_tyres=True`` analyses straight
        running (the ``stability`` command's default).
    speeds : array_like
        Increasing speeds [m/s].
    loops : tuple of str, optional
        Default ``("open", "closed")``, or ``("open",)`` with
        ``controller="off"``.
    tyres : (rear, front), optional
        Tyre objects instead of the scenario's.

    Returns
    -------
    Stability

    Example
    -------
    >>> from whipple_kick import Scenario
    >>> res = analyse(Scenario(symmetric_tyres=True), [3.0, 3.5, 4.0, 4.5, 5.0], loops=("open",))
    >>> sorted(set(res.eigenvalues["mode"]))
    ['capsize', 'caster', 'lateral_rear', 'relaxation_front', 'relaxation_rear', 'vertical', 'weave', 'wobble']
    """
    import pandas as pd

    speeds = check_speeds(speeds)
    loops = _check_loops(scenario, loops)
    setup = _setup(scenario, tyres)
    wheelbase = _wheelbase(setup.moore)
    rows, steady_rows, models, contexts, raw = [], [], {}, {}, {}
    for loop in loops:
        contexts[loop] = _Loop(setup, loop, wheelbase)
        lams, vecs, shares = _sweep_loop(contexts[loop], speeds, models, steady_rows)
        rows += _named_rows("slip", loop, speeds, lams, vecs, shares, raw)
    rows += _classic_rows(setup, speeds, loops, raw)
    result = Stability(scenario, speeds, pd.DataFrame(rows), pd.DataFrame(steady_rows), models=models)
    result.summary = {"title": describe(scenario, setup.info), "scenario": scenario.to_dict(),
                      "bicycle": setup.info, "tyre_notes": setup.notes, "loops": list(loops),
                      **_summarise(result, raw, _refiners(contexts, setup, result))}
    return result


def _check_loops(scenario, loops):
    """The loops to analyse (default: open, and closed unless there is no rider); InputError if impossible."""
    if loops is None:
        loops = ("open",) if scenario.controller == "off" else LOOPS
    for loop in loops:
        _check_loop(loop)
    if "closed" in loops and scenario.controller == "off":
        raise InputError("the closed loop needs a rider: controller 'off' has none (choose lqr or thesis)")
    return tuple(loops)


def _sweep_loop(ctx, speeds, models, steady_rows):
    """Eigenvalues, angle-like eigenvectors and shares at each speed of one loop (None without steady motion).

    The steady motion is continued from the previous speed's solution (or
    taken from the other loop's where the steer torque is zero there);
    ``models`` and ``steady_rows`` receive each speed's model and steady motion.
    """
    from .steady import NoSteadyMotion
    lams, vecs, shares, guess = [], [], [], None
    for k, v in enumerate(speeds):
        other = models.get(("open" if ctx.loop == "closed" else "closed", k))
        try:
            model = ctx.model(float(v), guess, None if other is None else other.steady)
        except NoSteadyMotion as exc:
            steady_rows.append({"loop": ctx.loop, "speed_m_s": float(v), "found_by": None, "message": str(exc)})
            lams.append(None)
            vecs.append(None)
            shares.append(None)
            guess = None
            continue
        guess = model.steady.unknowns
        models[ctx.loop, k] = model
        steady_rows.append(_steady_row(ctx.loop, v, model))
        lam, vec, share = ctx.eigen(model)
        lams.append(lam)
        vecs.append(vec)
        shares.append(share)
    return lams, vecs, shares


def _steady_row(loop, speed, model):
    x = model.steady.x
    return {"loop": loop, "speed_m_s": float(speed), "found_by": model.found_by, "message": None,
            "roll_rad": float(x[slip.X["q4"]]), "steer_rad": float(x[slip.X["q7"]]),
            "yaw_rate_rad_s": float(x[slip.X["u3"]]), "lateral_velocity_m_s": float(x[slip.X["u2"]]),
            "rear_wheel_torque_n_m": float(model.steady.params["T6c"])}


def _named_rows(model_name, loop, speeds, lams, vecs, shares_all, raw=None):
    """Rows of the eigenvalue table for one loop: tracked, then named per branch.

    ``raw``, if given, receives ``(model_name, loop) -> (eigenvalues, vectors,
    track ids)`` per speed, for the summary's refinements.
    """
    ids = track(lams, vecs)
    if raw is not None:
        raw[model_name, loop] = (lams, vecs, ids)
    points = []
    for k, (lam, cur, shares) in enumerate(zip(lams, ids, shares_all, strict=True)):
        if lam is None:
            continue
        for j in range(lam.size):
            e = complex(lam[j])
            points.append({"model": model_name, "loop": loop, "speed_m_s": float(speeds[k]), "speed_index": k,
                           "track": int(cur[j]), "real": e.imag == 0.0, "real_1_s": e.real, "imag_1_s": e.imag,
                           "frequency_hz": abs(e.imag) / (2 * math.pi),
                           "damping_ratio": -e.real / abs(e) if e != 0 else 0.0, "shares": shares[j]})
    name_tracks(points)
    rows = []
    for p in points:
        shares = p.pop("shares")
        p.pop("real")
        rows.append({**p, **{f"share_{g}": float(s) for g, s in zip(GROUPS, shares, strict=True)}})
    return rows


def _canonical(setup):
    """The classic model's canonical matrices M, C1, K0, K2 (and g) of the scenario's bicycle."""
    from . import classic
    canonical = classic.canonical_matrices(setup.moore)
    canonical["g"] = float(setup.moore["g"])
    return canonical


def _classic_rows(setup, speeds, loops, raw=None):
    """The no-slip model's eigenvalues, tracked and named like the slip model's (roll and steer content)."""
    canonical = _canonical(setup)
    rows = []
    for loop in loops:
        lams, vecs, shares_all = [], [], []
        for v in speeds:
            K = None
            if loop == "closed":
                K = _classic_gains(setup, v)
            lam, vec = _classic_eigen(canonical, float(v), K)
            scaled, shares = _classic_content(lam, vec)
            lams.append(lam)
            vecs.append(scaled)
            shares_all.append(shares)
        rows += _named_rows("no-slip", loop, speeds, lams, vecs, shares_all, raw)
    return rows


def _classic_gains(setup, speed):
    from . import control
    gains, _ = assembly.controller_gains(setup.scenario.with_changes(speed=float(speed)), setup.design)
    return np.array([gains.get(n, 0.0) for n in control.GAIN_ORDER])


# ------------------------------------------------------------------ the summary

def _refiners(contexts, setup, result):
    """``(model, loop) -> eigen_at(speed, nearest index)``: eigenvalues and angle-like vectors at any speed."""
    out = {}
    for loop, ctx in contexts.items():
        def slip_at(v, k, ctx=ctx, loop=loop):
            near = result.models.get((loop, k))
            model = ctx.model(float(v), None if near is None else near.steady.unknowns)
            lam, vec, _ = ctx.eigen(model)
            return lam, vec
        out["slip", loop] = slip_at
    canonical = _canonical(setup)
    for loop in contexts:
        def classic_at(v, k, loop=loop):
            lam, vec = _classic_eigen(canonical, float(v), _classic_gains(setup, v) if loop == "closed" else None)
            return lam, _classic_content(lam, vec)[0]
        out["no-slip", loop] = classic_at
    return out


def _root(fun, a, b):
    """Root of ``fun`` in [a, b] by Brent's method (to 1e-9 m/s): ``(speed, None)``, or ``(None, reason)``.

    The sweep's samples say a sign changes between ``a`` and ``b``; the fresh
    linearisations at the ends may disagree (a mode matched to another
    eigenvalue, a steady motion continued to another branch). Then there is
    no bracket and no root is claimed: an estimate outside [a, b] would be a
    number without meaning.
    """
    from scipy.optimize import brentq
    fa, fb = fun(a), fun(b)
    if fa == 0.0:
        return a, None
    if fb == 0.0:
        return b, None
    if not (np.isfinite(fa) and np.isfinite(fb)) or fa * fb > 0:
        return None, (f"the real part does not change sign between {a:g} and {b:g} m/s on fresh "
                      f"linearisations ({fa:+.3g} and {fb:+.3g} 1/s), although the sweep's samples do")
    return float(brentq(fun, a, b, xtol=1e-9, rtol=1e-12)), None


class _Sweep:
    """One model and loop of a sweep: eigenvalues, tracks and names per speed, with refinement."""

    def __init__(self, table, speeds, raw, eigen_at):
        self.table, self.speeds, self.eigen_at = table, speeds, eigen_at
        self.lams, self.vecs, self.ids = raw
        # mode name of (speed index, track)
        self.name = {(int(r.speed_index), int(r.track)): r.mode for r in table.itertuples()}

    def present(self, k):
        return self.lams[k] is not None

    def values(self, k, mode):
        """Eigenvalues named ``mode`` at speed index ``k`` (with their tracks)."""
        if not self.present(k):
            return []
        return [(complex(l), int(t)) for l, t in zip(self.lams[k], self.ids[k], strict=True) if self.name[k, int(t)] == mode]

    def eigenvalue(self, k, track_id):
        if not self.present(k):
            return None
        hit = np.nonzero(self.ids[k] == track_id)[0]
        return complex(self.lams[k][hit[0]]) if hit.size else None

    def tracked_real_part(self, k, track_id):
        """Re of the eigenvalue continuing ``track_id`` from speed index k to k+1, as a function of speed."""
        j0 = int(np.nonzero(self.ids[k] == track_id)[0][0])
        j1 = int(np.nonzero(self.ids[k + 1] == track_id)[0][0])
        l0, l1 = self.lams[k][j0], self.lams[k + 1][j1]
        v0, v1 = self.speeds[k], self.speeds[k + 1]

        def real_part(v):
            if v == v0:
                return float(l0.real)
            if v == v1:
                return float(l1.real)
            s = (v - v0) / (v1 - v0)
            ref_lam = np.array([(1 - s) * l0 + s * l1])
            ref_vec = (self.vecs[k][:, [j0]] if s < 0.5 else self.vecs[k + 1][:, [j1]])
            lam, vec = self.eigen_at(v, k if s < 0.5 else k + 1)
            return float(lam[np.argmin(match_cost(ref_lam, ref_vec, lam, vec)[0])].real)
        return real_part

    def largest_real_part(self, v, k):
        lam, _ = self.eigen_at(v, k)
        return float(np.max(lam.real))

    def split_speed(self, k, track_id):
        """Where a pair turns real (or two reals merge) between speed indices k and k+1.

        Near such a point the discriminant is linear in speed: the squared
        imaginary part on the complex side and the squared half-distance of
        the two real eigenvalues on the other vanish at the same speed.
        """
        v0, v1 = self.speeds[k], self.speeds[k + 1]
        a, b = self.eigenvalue(k, track_id), self.eigenvalue(k + 1, track_id)
        if a is None or b is None:
            return 0.5 * (v0 + v1)
        side_complex, side_real, k_real = (a, b, k + 1) if a.imag != 0 else (b, a, k)
        partner = [complex(l) for l in self.lams[k_real] if l.imag == 0.0 and complex(l) != side_real]
        if side_complex.imag == 0 or not partner:
            return 0.5 * (v0 + v1)
        other = min(partner, key=lambda l: abs(l - side_real))
        im2, gap2 = side_complex.imag ** 2, ((side_real.real - other.real) / 2) ** 2
        frac = im2 / (im2 + gap2)
        return float(v0 + (v1 - v0) * (frac if a.imag != 0 else 1 - frac))


def _unstable(values):
    return any(l.real > 0 for l, _ in values)


def _weave_speed(sweep):
    """Lowest speed [m/s] above which the weave is stable, and how it stabilises (or None, reason).

    A weave eigenvalue's real part crossing zero is located by Brent's
    method on fresh linearisations (:meth:`_Sweep.tracked_real_part`); a
    weave pair that stops being a pair while unstable (splits into two real
    eigenvalues, one of them unstable) stops being an oscillatory
    instability there, located by the discriminant (:meth:`_Sweep.split_speed`).
    """
    n = len(sweep.speeds)
    unstable = [_unstable(sweep.values(k, "weave")) for k in range(n)]
    if not any(unstable):
        return None, "the weave is stable (or absent) at every speed of the sweep"
    for k in range(n - 1):
        if not (unstable[k] and not unstable[k + 1]) or not (sweep.present(k) and sweep.present(k + 1)):
            continue
        for lam, t in sweep.values(k, "weave"):
            nxt = sweep.eigenvalue(k + 1, t)
            if lam.real <= 0 or nxt is None:
                continue
            crossing, why = _root(sweep.tracked_real_part(k, t), sweep.speeds[k], sweep.speeds[k + 1])
            if sweep.name[k + 1, t] == "weave" and nxt.imag != 0.0:
                return (crossing, "the weave's real part crosses zero") if why is None else (None, why)
            # The pair split between the two speeds: still unstable then if a root stays positive.
            pair = [complex(l) for l in sweep.lams[k + 1] if l.imag == 0.0 and abs(l - nxt) < 4 * abs(lam.imag)]
            if not pair:
                return None, (f"the weave pair stops being the weave between {sweep.speeds[k]:g} and "
                              f"{sweep.speeds[k + 1]:g} m/s without turning into two real eigenvalues "
                              f"near it (it continues as {nxt.real:+.3g}{nxt.imag:+.3g}j 1/s, "
                              f"{sweep.name[k + 1, t]}); refine the speed grid there")
            if max(l.real for l in pair) > 0:
                return sweep.split_speed(k, t), ("the weave pair splits into two real eigenvalues while "
                                                 "unstable (one stays unstable)")
            if why is not None:
                return None, why
            return crossing, "the weave's real part crosses zero just before the pair splits"
    return None, "the weave is unstable up to the end of the sweep"


def _capsize_speed(sweep, above=None):
    """Lowest speed [m/s] (from ``above`` up) where a capsize eigenvalue becomes unstable, and how (or None).

    Within a capsize branch the zero crossing is located by Brent's method;
    a capsize branch that is born unstable (from a weave pair that splits)
    becomes unstable at the crossing of its continuation if that lies after
    the split, else at the split.
    """
    n = len(sweep.speeds)
    found, unlocated = [], []
    for k in range(n - 1):
        if not (sweep.present(k) and sweep.present(k + 1)):
            continue
        for lam, t in sweep.values(k + 1, "capsize"):
            before = sweep.eigenvalue(k, t)
            if lam.real <= 0 or before is None:
                continue
            same_branch = sweep.name[k, t] == "capsize" and before.imag == 0.0
            if before.real <= 0:
                crossing, why = _root(sweep.tracked_real_part(k, t), sweep.speeds[k], sweep.speeds[k + 1])
                if why is not None:
                    unlocated.append(why)
                    continue
                found.append((crossing, "the capsize eigenvalue crosses zero" + ("" if same_branch else
                                                                                   " just after the weave pair splits")))
            elif not same_branch:
                found.append((sweep.split_speed(k, t), "the capsize eigenvalue is born unstable where the "
                                                       "weave pair splits"))
    found = [f for f in found if above is None or f[0] >= above - 1e-9]
    if not found:
        return None, unlocated[0] if unlocated else "no capsize eigenvalue becomes unstable within the sweep"
    return min(found)


def _stable_ranges(sweep):
    """Speed intervals [m/s] where every eigenvalue has a negative real part.

    Boundaries between sweep speeds are located by Brent's method on the
    largest real part (continuous in speed); an interval touching the end
    of the sweep is marked open there (``"lower_open"``/``"upper_open"``).
    """
    n = len(sweep.speeds)
    stable = [sweep.present(k) and float(np.max(sweep.lams[k].real)) < 0 for k in range(n)]
    ranges = []
    for start, stop in _segments(stable):
        if not stable[start]:
            continue
        lo, hi, notes = sweep.speeds[start], sweep.speeds[stop - 1], []
        # A boundary that cannot be located stays at the last stable sweep speed, and says so.
        if start > 0 and sweep.present(start - 1):
            root, why = _root(lambda v, k=start: sweep.largest_real_part(v, k), sweep.speeds[start - 1], lo)
            lo = lo if why is not None else root
            notes += [f"lower end not located, the sweep speed is given: {why}"] if why is not None else []
        if stop < n and sweep.present(stop):
            root, why = _root(lambda v, k=stop - 1: sweep.largest_real_part(v, k), hi, sweep.speeds[stop])
            hi = hi if why is not None else root
            notes += [f"upper end not located, the sweep speed is given: {why}"] if why is not None else []
        ranges.append({"from_m_s": float(lo), "to_m_s": float(hi), "lower_open": start == 0,
                       "upper_open": stop == n, **({"note": "; ".join(notes)} if notes else {})})
    return ranges


def _mode_ranges(table):
    """Per mode: speeds where it exists, the largest real part and the frequency range."""
    out = {}
    for mode, g in table.groupby("mode", sort=False):
        worst = g.loc[g["real_1_s"].idxmax()]
        out[mode] = {"speeds_m_s": [float(g["speed_m_s"].min()), float(g["speed_m_s"].max())],
                     "largest_real_part_1_s": float(worst["real_1_s"]),
                     "at_speed_m_s": float(worst["speed_m_s"]),
                     "frequency_hz": [float(g["frequency_hz"].min()), float(g["frequency_hz"].max())]}
    return {m: out[m] for m in MODES if m in out}


def _wobble_summary(table):
    """The wobble of one loop: where it exists, its frequency and damping, the least damped point (or None)."""
    w = table[(table["mode"] == "wobble") & (table["imag_1_s"] > 0)]
    if w.empty:
        fast = table[(table["frequency_hz"] >= WOBBLE_MIN_FREQUENCY_HZ) & (table["imag_1_s"] > 0)]
        return {"exists": False,
                "fast_oscillations": {m: {"frequency_hz": [float(g["frequency_hz"].min()), float(g["frequency_hz"].max())],
                                          "largest_steer_share": float(g["share_steer"].max())}
                                      for m, g in fast.groupby("mode")}}
    least = w.loc[w["damping_ratio"].idxmin()]
    return {"exists": True,
            "speeds_m_s": [float(w["speed_m_s"].min()), float(w["speed_m_s"].max())],
            "frequency_hz": [float(w["frequency_hz"].min()), float(w["frequency_hz"].max())],
            "damping_ratio": [float(w["damping_ratio"].min()), float(w["damping_ratio"].max())],
            "least_damped": {"speed_m_s": float(least["speed_m_s"]), "frequency_hz": float(least["frequency_hz"]),
                             "damping_ratio": float(least["damping_ratio"]), "real_1_s": float(least["real_1_s"])},
            "unstable": bool((w["real_1_s"] > 0).any()),
            "mean_shares": {g: float(w[f"share_{g}"].mean()) for g in GROUPS}}


def _loop_summary(table, sweep):
    weave, weave_how = _weave_speed(sweep)
    capsize, capsize_how = _capsize_speed(sweep, above=weave)
    return {"weave_speed_m_s": weave, "weave_speed_how": weave_how,
            "capsize_speed_m_s": capsize, "capsize_speed_how": capsize_how,
            "stable_speed_ranges": _stable_ranges(sweep),
            "wobble": _wobble_summary(table) if "share_front_tyre" in table else None,
            "modes": _mode_ranges(table)}


def _summarise(result, raw, refiners):
    """The summary of :class:`Stability` (JSON-ready): see :func:`analyse`."""
    df, speeds = result.eigenvalues, result.speeds
    out = {"speeds_m_s": {"from": float(speeds[0]), "to": float(speeds[-1]), "count": int(speeds.size)},
           "constant_speed": True, "mode_descriptions": {m: MODE_DESCRIPTIONS[m] for m in MODES},
           "wobble_min_frequency_hz": WOBBLE_MIN_FREQUENCY_HZ}
    for model_name in ("slip", "no-slip"):
        block = {}
        for (name, loop), data in raw.items():
            if name != model_name:
                continue
            table = df[(df["model"] == name) & (df["loop"] == loop)]
            sweep = _Sweep(table, speeds, data, refiners[name, loop])
            block[loop] = _loop_summary(table, sweep)
            if name == "no-slip":
                block[loop].pop("wobble")
        out[model_name] = block
    steady = result.steady
    out["steady_motion"] = {}
    for loop, g in steady.groupby("loop"):
        found = g[g["found_by"].notna()]
        missing = g[g["found_by"].isna()]
        out["steady_motion"][loop] = {
            "largest_lean_rad": float(found["roll_rad"].abs().max()) if len(found) else None,
            "speeds_without_steady_motion": int(len(missing)),
            "first_reason": None if missing.empty else str(missing["message"].iloc[0])}
    return out


# ------------------------------------------------------------------ free response

def perturbed_state(model, vector, amplitude):
    """The steady motion's full state moved by ``amplitude`` along the real part of an eigenvector.

    Parameters
    ----------
    model : LinearModel
    vector : ndarray, complex
        Right eigenvector of ``model.matrix`` (states ``model.states``).
    amplitude : float
        Largest change of roll or steer [rad] (the other states in proportion).

    Returns
    -------
    ndarray
        Full state (:data:`whipple_kick.slip.STATE_NAMES`), pitch re-solved
        so the front contact stays on the ground.

    Example
    -------
    >>> from whipple_kick import Scenario
    >>> model = linear_model(Scenario(symmetric_tyres=True), 4.0)
    >>> lam, vec = np.linalg.eig(model.matrix)
    >>> x0 = perturbed_state(model, vec[:, 0], 1e-4)
    >>> x0.shape == model.steady.x.shape
    True
    """
    idx = {n: i for i, n in enumerate(model.states)}
    # Rotate the eigenvector so its largest roll/steer entry is real and positive.
    big = max((vector[idx["q4"]], vector[idx["q7"]]), key=abs)
    dz = (vector * (abs(big) / big)).real * (amplitude / abs(big))
    x = np.array(model.steady.x, dtype=float)
    for name, value in zip(model.states, dz, strict=True):
        x[slip.X[{"v_lat": "u2", "v_fwd": "u1"}.get(name, name)]] += value
    return slip.solve_pitch(slip.CompiledRHS(model.steady.params), x)


def free_response(model, vector, amplitude=1e-4, duration=2.0, rate=500.0, rtol=1e-11):
    """The nonlinear model's response from the steady motion displaced along an eigenvector (no input).

    Parameters
    ----------
    model : LinearModel
        Its loop's parameters (the rider's gains for ``"closed"``) are integrated.
    vector : ndarray, complex
        Right eigenvector of ``model.matrix``.
    amplitude : float
        Initial roll or steer displacement [rad] (:func:`perturbed_state`).
    duration, rate : float
        Time [s] and sample rate [Hz].
    rtol : float
        LSODA relative tolerance.

    Returns
    -------
    t : ndarray
        Times [s].
    deviation : ndarray (len(t), len(model.states))
        Heading-frame state minus its steady value.

    Example
    -------
    >>> from whipple_kick import Scenario
    >>> model = linear_model(Scenario(symmetric_tyres=True), 3.0, "closed")
    >>> lam, vec = np.linalg.eig(model.matrix)
    >>> k = int(np.argmax(lam.imag))
    >>> t, dev = free_response(model, vec[:, k], duration=1.0, rate=2000.0)
    >>> fit = fit_eigenvalue(t, np.column_stack([modal_coordinate(model, k, dev).real,
    ...                                          modal_coordinate(model, k, dev).imag]))
    >>> bool(abs(fit - lam[k]) < 1e-3 * abs(lam[k]))    # the nonlinear response decays at the eigenvalue
    True
    """
    from . import lsoda
    rhs = slip.CompiledRHS(model.steady.params)
    x0 = perturbed_state(model, vector, amplitude)
    traj = lsoda.integrate(rhs, x0, duration, rtol=rtol, output_rate=rate)
    if traj.failed or traj.fell:
        raise FloatingPointError(f"the free response did not complete: {traj.message}")
    keep = [slip.linear_states(rhs.transient).index(n) for n in model.states]
    z_ref = slip.heading_state(model.steady.x)[keep]
    deviation = np.array([slip.heading_state(x)[keep] for x in traj.x]) - z_ref
    return traj.t, deviation


def modal_coordinate(model, index, deviation):
    """The amplitude of mode ``index`` in a response: row ``index`` of the inverse eigenvector matrix times it.

    The left eigenvector filters out every other mode of the linear model, so a
    fit of this coordinate measures one mode's growth rate and frequency
    (the response itself is the nonlinear model's).

    Parameters
    ----------
    model : LinearModel
    index : int
        Eigenvalue index in ``numpy.linalg.eig(model.matrix)``.
    deviation : ndarray (n_t, n)
        Heading-frame deviations (:func:`free_response`).

    Returns
    -------
    ndarray, complex (n_t,)

    Example
    -------
    Skipped as a doctest: a fragment of :func:`free_response`'s example, which runs it.

    >>> eta = modal_coordinate(model, k, dev)     # see free_response    # doctest: +SKIP
    """
    _, V = np.linalg.eig(model.matrix)
    return deviation @ np.linalg.inv(V)[index]


def fit_eigenvalue(t, signals, oscillatory=True):
    """Growth rate and frequency of a free response: ``e^(s t) (a cos(w t) + b sin(w t))`` per signal.

    Variable projection: for each (s, w) the amplitudes a, b of every signal
    come from linear least squares; (s, w) minimise the residual
    (``scipy.optimize.least_squares``), started from the data alone (the
    spectrum's peak and the growth of the RMS from the first to the second
    half), not from a prediction.

    Parameters
    ----------
    t : ndarray
        Times [s], uniform.
    signals : ndarray (len(t), m)
        Signals to fit together (each scaled to its largest magnitude).
    oscillatory : bool
        False fits ``a e^(s t)`` (a real eigenvalue).

    Returns
    -------
    complex
        ``s + i w`` [1/s].

    Example
    -------
    >>> t = np.linspace(0.0, 3.0, 601)
    >>> y = np.exp(-0.5 * t) * np.cos(4.0 * t)
    >>> lam = fit_eigenvalue(t, y[:, None])
    >>> round(lam.real, 6), round(lam.imag, 6)
    (-0.5, 4.0)
    """
    from scipy.optimize import least_squares
    Y = np.asarray(signals, dtype=float)
    Y = Y / np.where(np.abs(Y).max(axis=0) > 0, np.abs(Y).max(axis=0), 1.0)
    half = len(t) // 2
    rms = lambda part: float(np.sqrt(np.mean(part ** 2)))
    s0 = math.log(rms(Y[half:]) / rms(Y[:half])) / (t[half] - t[0])
    if oscillatory:
        main = Y[:, np.argmax(np.var(Y, axis=0))]
        spectrum = np.abs(np.fft.rfft((main - main.mean()) * np.hanning(len(t)), n=8 * len(t)))
        w0 = 2 * math.pi * np.fft.rfftfreq(8 * len(t), t[1] - t[0])[np.argmax(spectrum[1:]) + 1]
    else:
        w0 = 0.0

    def basis(p):
        env = np.exp(p[0] * (t - t[0]))
        return np.column_stack([env * np.cos(p[1] * t), env * np.sin(p[1] * t)]) if oscillatory else env[:, None]

    def residual(p):
        B = basis(p)
        coef, *_ = np.linalg.lstsq(B, Y, rcond=None)
        return (B @ coef - Y).ravel()

    p = least_squares(residual, [s0, w0] if oscillatory else [s0], xtol=1e-14, ftol=1e-14, gtol=1e-14).x
    return complex(p[0], p[1] if oscillatory else 0.0)


# ------------------------------------------------------------------ the figure

#: Colour of each mode in stability.png.
MODE_COLOURS = {"weave": "tab:blue", "capsize": "tab:red", "caster": "tab:green", "wobble": "tab:purple",
                "lateral_rear": "tab:orange", "lateral_front": "tab:brown", "relaxation_rear": "tab:olive",
                "relaxation_front": "tab:cyan", "vertical": "tab:gray"}
#: Real-part range [1/s] of the left ("slow modes") panels, as Meijaard et al. (2007) Fig. 3.
SLOW_RANGE = (-10.0, 10.0)


def _branch_lines(table):
    """Per mode: (speeds, real parts, |imag| parts), its branches joined with NaN gaps (Im >= 0 only).

    One line per mode and part keeps the figure to a few dozen artists
    (drawing some 600 separate lines cost 0.3 s of the command's 5 s).
    """
    speeds_all = np.unique(np.round(table["speed_m_s"].to_numpy(), 9))
    lines = {}
    for (_track, mode), g in table.groupby(["track", "mode"], sort=False):
        g = g.sort_values("speed_m_s")
        if (g["imag_1_s"] < 0).all():
            continue   # the conjugate of a drawn pair
        order = np.searchsorted(speeds_all, np.round(g["speed_m_s"].to_numpy(), 9))
        breaks = np.nonzero(np.diff(order) > 1)[0] + 1   # gaps in speed end a branch too
        parts = lines.setdefault(mode, ([], [], []))
        for piece in np.split(np.arange(len(g)), breaks):
            sub = g.iloc[piece]
            for store, values in zip(parts, (sub["speed_m_s"], sub["real_1_s"], np.abs(sub["imag_1_s"])), strict=True):
                store += [*np.asarray(values, dtype=float), np.nan]
    return {mode: tuple(np.array(v) for v in parts) for mode, parts in lines.items()}


def _speed(value):
    return "none" if value is None else f"{value:.2f} m/s"


def range_text(interval):
    """``"a-b"`` [m/s] of a stable speed range, saying where it is cut by the sweep's ends.

    Example
    -------
    >>> range_text({"from_m_s": 0.5, "to_m_s": 4.33, "lower_open": True, "upper_open": False})
    '0.50 (sweep start)-4.33'
    """
    lo = f"{interval['from_m_s']:.2f}" + (" (sweep start)" if interval["lower_open"] else "")
    hi = f"{interval['to_m_s']:.2f}" + (" (sweep end)" if interval["upper_open"] else "")
    return f"{lo}-{hi}" + (" (an end not located: at a sweep speed)" if "note" in interval else "")


def speeds_text(summary, loop):
    """Weave and capsize speeds and stable ranges of one loop, slip and no-slip model, one line each.

    Example
    -------
    >>> from whipple_kick import Scenario
    >>> result = analyse(Scenario(symmetric_tyres=True), [3.0, 3.5, 4.0, 4.5, 5.0], loops=("open",))
    >>> print(speeds_text(result.summary, "open"))
    slip: weave 3.82 m/s, capsize none; stable none
    no-slip: weave 3.97 m/s, capsize none; stable 3.97-5.00 (sweep end) m/s
    """
    lines = []
    for model in ("slip", "no-slip"):
        info = summary.get(model, {}).get(loop)
        if info is None:
            continue
        ranges = ", ".join(range_text(r) for r in info["stable_speed_ranges"]) or "none"
        lines.append(f"{model}: weave {_speed(info['weave_speed_m_s'])}, capsize "
                     f"{_speed(info['capsize_speed_m_s'])}; stable {ranges}" + (" m/s" if ranges != "none" else ""))
    return "\n".join(lines)


def figure(result, path, title=None):
    """stability.png: real (solid) and imaginary (dashed) parts against speed, coloured by mode.

    One row per loop; the left panel shows the slow modes (as Meijaard et
    al. 2007, Fig. 3), the right all of them. The no-slip (knife-edge)
    model of the same bicycle and rider is drawn faintly in grey; the slip
    model's weave and capsize speeds are marked and its stable speed ranges
    shaded.

    Parameters
    ----------
    result : Stability
    path : str or pathlib.Path
        PNG file to write.
    title : str, optional

    Returns
    -------
    pathlib.Path

    Example
    -------
    >>> from whipple_kick import Scenario
    >>> _ = figure(analyse(Scenario(symmetric_tyres=True), [3.0, 3.5, 4.0, 4.5, 5.0]), "stability.png")
    """
    import pathlib

    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    from matplotlib.lines import Line2D

    df = result.eigenvalues
    loops = [loop for loop in LOOPS if loop in set(df["loop"])]
    # A bare Figure (no pyplot): pyplot's redraw hooks on every artist cost 0.1 s here.
    fig = Figure(figsize=(13, 4.6 * len(loops)))
    FigureCanvasAgg(fig)
    axes = fig.subplots(len(loops), 2, squeeze=False)
    used = set()
    for row, loop in enumerate(loops):
        slip_lines = _branch_lines(df[(df["model"] == "slip") & (df["loop"] == loop)])
        classic_lines = _branch_lines(df[(df["model"] == "no-slip") & (df["loop"] == loop)])
        used |= set(slip_lines)
        for col, ax in enumerate(axes[row]):
            _draw_panel(ax, slip_lines, classic_lines, result, loop, slow=col == 0)
    handles = [Line2D([], [], color=MODE_COLOURS[m], lw=2, label=m.replace("_", " ")) for m in MODES if m in used]
    handles += [Line2D([], [], color="k", lw=1.5, label="real part"),
                Line2D([], [], color="k", lw=1.2, ls="--", label="imaginary part"),
                Line2D([], [], color="0.55", lw=1.0, alpha=0.6, label="no-slip (knife-edge) model")]
    fig.legend(handles=handles, loc="lower center", ncol=min(len(handles), 7), fontsize=9, frameon=False)
    if title:
        fig.suptitle(title, fontsize=11)
    # Fixed margins: tight_layout costs 0.4 s of the command's 5 s budget.
    fig.subplots_adjust(left=0.06, right=0.985, bottom=0.06 + 0.14 / len(loops), top=0.93 if title else 0.96,
                        hspace=0.3, wspace=0.15)
    path = pathlib.Path(path)
    fig.savefig(path, dpi=110)
    return path


def _draw_panel(ax, slip_lines, classic_lines, result, loop, slow):
    """One panel of :func:`figure`: the no-slip model faint, the slip model by mode, speeds and ranges marked."""
    info = result.summary.get("slip", {}).get(loop, {})
    for v, re, im in classic_lines.values():
        ax.plot(v, re, color="0.55", lw=1.0, alpha=0.45, zorder=1)
        ax.plot(v, np.where(im > 0, im, np.nan), color="0.55", lw=1.0, ls="--", alpha=0.45, zorder=1)
    for mode, (v, re, im) in slip_lines.items():
        ax.plot(v, re, color=MODE_COLOURS[mode], lw=1.6, zorder=3)
        ax.plot(v, np.where(im > 0, im, np.nan), color=MODE_COLOURS[mode], lw=1.3, ls="--", zorder=3)
    for rng in info.get("stable_speed_ranges", []):
        ax.axvspan(rng["from_m_s"], rng["to_m_s"], color="tab:green", alpha=0.08, zorder=0)
    for key in ("weave_speed_m_s", "capsize_speed_m_s"):
        if info.get(key) is not None:
            ax.axvline(info[key], color="k", lw=0.8, ls=":", zorder=2)
    ax.axhline(0.0, color="k", lw=0.6)
    ax.set_xlim(result.speeds[0], result.speeds[-1])
    ax.set_xlabel("speed [m/s]")
    ax.grid(alpha=0.3)
    if slow:
        ax.text(0.99, 0.98, speeds_text(result.summary, loop), transform=ax.transAxes, fontsize=8,
                va="top", ha="right", bbox={"facecolor": "white", "alpha": 0.85, "edgecolor": "0.8"})
        ax.set_ylim(*SLOW_RANGE)
        ax.set_ylabel("eigenvalue [1/s]")
        ax.set_title(f"{loop} loop: slow modes" + (" (no rider control)" if loop == "open" else " (with the rider)"),
                     fontsize=10)
    else:
        ax.set_title(f"{loop} loop: all modes", fontsize=10)


# ------------------------------------------------------------------ pressure and load

#: The thesis' kick-plate grid: pressures [kPa] and static rear loads [N] (Chapter 8, Table 8.3).
THESIS_PRESSURES_KPA = (300.0, 400.0, 500.0)
THESIS_LOADS_N = (570.0, 635.0, 701.0)


def _at(table, speed, mode):
    """(eigenvalue with Im >= 0 named ``mode`` at ``speed`` with the largest real part, or None)."""
    sel = table[np.isclose(table["speed_m_s"], speed) & (table["mode"] == mode) & (table["imag_1_s"] >= 0)]
    if sel.empty:
        return None
    r = sel.loc[sel["real_1_s"].idxmax()]
    return complex(r["real_1_s"], r["imag_1_s"])


def _mode_columns(prefix, lam):
    if lam is None:
        return {f"{prefix}_real_1_s": None, f"{prefix}_frequency_hz": None, f"{prefix}_damping_ratio": None}
    return {f"{prefix}_real_1_s": lam.real, f"{prefix}_frequency_hz": abs(lam.imag) / (2 * math.pi),
            f"{prefix}_damping_ratio": -lam.real / abs(lam)}


def case_row(result, at_speed=3.0):
    """One row of :func:`pressure_load_table`: speeds, ranges and modes at ``at_speed`` of one analysis.

    Columns: pressure and load; the slip and no-slip weave and capsize
    speeds and the self-stable range (open loop); the stable speed range
    with the rider (closed loop); at ``at_speed`` the weave (open and closed
    loop) and the wobble (closed loop) as real part, frequency and damping
    ratio, and the closed loop's slowest eigenvalue (what a disturbance
    decays with); the wobble's least damping over the sweep.

    Example
    -------
    >>> from whipple_kick import Scenario
    >>> round(case_row(analyse(Scenario(symmetric_tyres=True), parse_speeds("2:6:0.1")))["weave_speed_m_s"], 2)
    3.86
    """
    sc, s, table = result.scenario, result.summary, result.eigenvalues
    speed = float(result.speeds[np.argmin(np.abs(result.speeds - at_speed))])
    rear, _ = sc.pressures
    row = {"pressure_kpa": rear, "fz_n": sc.fz_n, "at_speed_m_s": speed}
    first = lambda ranges: (ranges[0]["from_m_s"], ranges[0]["to_m_s"]) if ranges else (None, None)
    for model, tag in (("slip", ""), ("no-slip", "noslip_")):
        info = s[model]["open"]
        row[f"{tag}weave_speed_m_s"] = info["weave_speed_m_s"]
        row[f"{tag}capsize_speed_m_s"] = info["capsize_speed_m_s"]
        row[f"{tag}self_stable_from_m_s"], row[f"{tag}self_stable_to_m_s"] = first(info["stable_speed_ranges"])
    slip_table = table[table["model"] == "slip"]
    open_t, closed_t = slip_table[slip_table["loop"] == "open"], slip_table[slip_table["loop"] == "closed"]
    row.update(_mode_columns("open_weave", _at(open_t, speed, "weave")))
    if "closed" in s["slip"]:
        ranges = s["slip"]["closed"]["stable_speed_ranges"]
        row["closed_stable_ranges"] = "; ".join(range_text(r) for r in ranges) or "none"
        row.update(_mode_columns("closed_weave", _at(closed_t, speed, "weave")))
        row.update(_mode_columns("closed_wobble", _at(closed_t, speed, "wobble")))
        here = closed_t[np.isclose(closed_t["speed_m_s"], speed)]
        slowest = here.loc[here["real_1_s"].idxmax()]
        row["closed_slowest_real_1_s"] = float(slowest["real_1_s"])
        row["closed_slowest_mode"] = slowest["mode"]
    loop = "closed" if "closed" in s["slip"] else "open"
    wob = s["slip"][loop]["wobble"]
    row["wobble_least_damping_ratio"] = wob["least_damped"]["damping_ratio"] if wob["exists"] else None
    row["wobble_least_damped_at_m_s"] = wob["least_damped"]["speed_m_s"] if wob["exists"] else None
    return row


def pressure_load_table(pressures=THESIS_PRESSURES_KPA, loads=THESIS_LOADS_N, *, base=None, speeds=None,
                        at_speed=3.0):
    """Weave, wobble and stable speed ranges over pressures x rear loads (:func:`case_row` per case).

    Parameters
    ----------
    pressures : sequence of float
        Inflation pressures of both tyres [kPa] (default the thesis' 300, 400, 500).
    loads : sequence of float
        Static rear-tyre loads [N] the rider is sized for (default 570, 635, 701).
    base : whipple_kick.scenario.Scenario, optional
        Everything else (default: offsets removed, the default rider designed at each speed).
    speeds : array_like, optional
        Sweep speeds [m/s] (default :data:`DEFAULT_SPEEDS`).
    at_speed : float
        Speed [m/s] of the weave and wobble columns (default 3, the kick-plate runs').

    Returns
    -------
    pandas.DataFrame
        One row per case, loads outer, pressures inner.

    Example
    -------
    Skipped as a doctest: one full speed sweep (0.5-10 m/s every 0.05 m/s) per case,
    several seconds each (``scripts/stability_study.py`` runs the whole table).

    >>> table = pressure_load_table(pressures=(400.0,), loads=(635.0,))   # doctest: +SKIP
    >>> table[["pressure_kpa", "weave_speed_m_s", "capsize_speed_m_s"]]   # doctest: +SKIP
    """
    import pandas as pd
    base = Scenario(symmetric_tyres=True) if base is None else base
    speeds = parse_speeds("{}:{}:{}".format(*DEFAULT_SPEEDS)) if speeds is None else check_speeds(speeds)
    rows = []
    for load in loads:
        for pressure in pressures:
            sc = base.with_changes(pressure_kpa=float(pressure), fz_n=float(load),
                                         pressure_front_kpa=None, pressure_rear_kpa=None)
            rows.append(case_row(analyse(sc, speeds), at_speed))
    return pd.DataFrame(rows)


# ------------------------------------------------------------------ outputs

def describe(scenario, info=None):
    """One line naming the bicycle, rider, tyres, offsets and rider control of a stability analysis.

    Example
    -------
    >>> from whipple_kick import Scenario
    >>> describe(Scenario(symmetric_tyres=True, controller="off"))
    'T03 400 kPa (zero-slip offsets removed, carcass), balanceassist_v1; no rider control'
    """
    rear, front = scenario.pressures
    p = f"{rear:g}" if rear == front else f"{rear:g}/{front:g} (rear/front)"
    load = f", rear load {info['static_load_rear_n']:.0f} N" if info else ""
    offsets = "zero-slip offsets removed" if scenario.symmetric_tyres else "measured zero-slip offsets"
    if scenario.controller == "lqr":
        rider = ("LQR rider designed at each speed" if scenario.design_speed is None
                 else f"LQR rider designed at {scenario.design_speed:g} m/s")
    elif scenario.controller == "thesis":
        rider = "Table 8.4 rider"
    else:
        rider = "no rider control"
    scale = f" x{scenario.gain_scale:g}" if scenario.controller != "off" and scenario.gain_scale != 1 else ""
    return (f"{scenario.tyre} {p} kPa ({offsets}, {scenario.tyre_transient}), {scenario.bicycle}{load}; "
            f"{rider}{scale}")


def write(result, out, plot=True):
    """Write eigenvalues.csv, summary.json and (``plot``) stability.png into the folder ``out``.

    Returns
    -------
    list of str
        The file names written.

    Example
    -------
    >>> from whipple_kick import Scenario
    >>> import os
    >>> os.mkdir("out")
    >>> write(analyse(Scenario(symmetric_tyres=True), [3.0, 4.0]), "out")
    ['eigenvalues.csv', 'summary.json', 'stability.png']
    """
    import json
    import pathlib
    out = pathlib.Path(out)
    fileio.write_csv(result.eigenvalues, out / "eigenvalues.csv")
    summary = results.clean(result.summary)
    fileio.write_atomic(out / "summary.json", json.dumps(summary, indent=2, allow_nan=False) + "\n")
    files = ["eigenvalues.csv", "summary.json"]
    if plot:
        figure(result, out / "stability.png", title=result.summary.get("title"))
        files.append("stability.png")
    return files


def report_lines(summary):
    """The few lines the ``stability`` command prints: speeds and modes per loop.

    Example
    -------
    >>> from whipple_kick import Scenario
    >>> result = analyse(Scenario(symmetric_tyres=True), [3.0, 3.5, 4.0, 4.5, 5.0], loops=("open",))
    >>> print("\\n".join(report_lines(result.summary)))
      open loop (no rider control):
        slip: weave 3.82 m/s, capsize none; stable none
        no-slip: weave 3.97 m/s, capsize none; stable 3.97-5.00 (sweep end) m/s
        wobble 9.2-9.4 Hz, damping ratio 0.063-0.102 (least damped at 3.00 m/s), stable
        modes: weave, capsize, caster, wobble, lateral rear, relaxation rear, relaxation front, vertical
    """
    lines = []
    for loop in LOOPS:
        info = summary.get("slip", {}).get(loop)
        if info is None:
            continue
        lines.append(f"  {loop} loop ({'no rider control' if loop == 'open' else 'with the rider'}):")
        lines += ["    " + text for text in speeds_text(summary, loop).split("\n")]
        wob = info.get("wobble")
        if wob and wob["exists"]:
            least = wob["least_damped"]
            lines.append(f"    wobble {wob['frequency_hz'][0]:.1f}-{wob['frequency_hz'][1]:.1f} Hz, damping ratio "
                         f"{wob['damping_ratio'][0]:.3f}-{wob['damping_ratio'][1]:.3f} (least damped at "
                         f"{least['speed_m_s']:.2f} m/s), {'UNSTABLE somewhere' if wob['unstable'] else 'stable'}")
        elif wob is not None:
            lines.append("    no wobble (no steer-dominated oscillation with the front tyre lagging)")
        lines.append("    modes: " + ", ".join(m.replace("_", " ") for m in info["modes"]))
        lean = summary.get("steady_motion", {}).get(loop, {}).get("largest_lean_rad")
        if lean is not None and abs(lean) > math.radians(TURN_NOTE_DEG):
            lines.append(f"    note: the steady motion is a turn with up to {math.degrees(lean):.1f} deg of lean "
                         "(the tyres' zero-slip offsets); these are the eigenvalues of that turn")
    return lines


def pressure_load_figure(table, path):
    """Figure of :func:`pressure_load_table`: against pressure, one line per rear load.

    Panels: the open-loop weave and capsize speeds (the no-slip model's as
    faint horizontal lines); the closed loop's weave damping ratio and
    decay rate at the table's speed; the wobble's frequency and damping
    ratio there.

    Returns
    -------
    pathlib.Path

    Example
    -------
    Skipped as a doctest: the whole pressure-load table (a minute or more) and a PNG
    written into the current folder.

    >>> pressure_load_figure(pressure_load_table(), "stability_pressure_load.png")   # doctest: +SKIP
    """
    import pathlib

    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(14, 4.4))
    FigureCanvasAgg(fig)
    axes = fig.subplots(1, 3)
    rate_axis, wobble_damping_axis = axes[1].twinx(), axes[2].twinx()
    colours = dict(zip(sorted(set(table["fz_n"])), ("tab:blue", "tab:orange", "tab:green", "tab:red"), strict=True))
    at = float(table["at_speed_m_s"].iloc[0])
    for load, g in table.groupby("fz_n"):
        c, p = colours[load], g["pressure_kpa"]
        axes[0].plot(p, g["weave_speed_m_s"], "o-", color=c, label=f"{load:g} N: weave")
        axes[0].plot(p, g["capsize_speed_m_s"], "s--", color=c, label=f"{load:g} N: capsize")
        axes[0].axhline(g["noslip_weave_speed_m_s"].iloc[0], color=c, lw=0.8, alpha=0.4)
        axes[0].axhline(g["noslip_capsize_speed_m_s"].iloc[0], color=c, lw=0.8, ls="--", alpha=0.4)
        axes[1].plot(p, g["closed_weave_damping_ratio"], "o-", color=c)
        rate_axis.plot(p, -g["closed_slowest_real_1_s"], "s:", color=c)
        axes[2].plot(p, g["closed_wobble_frequency_hz"], "o-", color=c)
        wobble_damping_axis.plot(p, g["closed_wobble_damping_ratio"], "s:", color=c)
    axes[0].set_ylabel("speed [m/s]")
    axes[0].set_title("open loop: weave (o-) and capsize (s--) speeds;\nfaint: no-slip model", fontsize=10)
    axes[1].set_ylabel("weave damping ratio (o-)")
    rate_axis.set_ylabel("slowest decay rate [1/s] (s:)")
    axes[1].set_title(f"closed loop at {at:g} m/s: weave", fontsize=10)
    axes[2].set_ylabel("wobble frequency [Hz] (o-)")
    wobble_damping_axis.set_ylabel("wobble damping ratio (s:)")
    axes[2].set_title(f"closed loop at {at:g} m/s: wobble", fontsize=10)
    for ax in axes:
        ax.set_xlabel("tyre pressure [kPa]")
        ax.grid(alpha=0.3)
        ax.set_xticks(sorted(set(table["pressure_kpa"])))
    axes[0].legend(fontsize=7, ncol=1, loc="best")
    fig.subplots_adjust(left=0.05, right=0.93, bottom=0.13, top=0.86, wspace=0.6)
    path = pathlib.Path(path)
    fig.savefig(path, dpi=110)
    return path
