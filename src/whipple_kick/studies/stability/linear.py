"""The slip model linearised about its steady motion at one speed (:class:`LinearModel`)."""
from dataclasses import dataclass, field

import numpy as np

from whipple_kick.errors import InputError, check_range
from whipple_kick.model import slip
from whipple_kick.model.transient import DEFAULT_TRANSIENT, FORMS
from whipple_kick.simulate import assembly, control, results, steady

from ._constants import LOOPS

# Heading-frame states at constant speed of the rigid rider (a leaning rider or a delayed reflex adds
# its states after them: :func:`active_states`), and how the summary and StateSpace name them.
STATES = tuple(n for n in slip.LINEAR_STATES if n != "v_fwd")
_LABELS = {
    **{q: col for q, col in results.COORDINATE_COLUMNS.items()},
    **{u: col for u, col in results.SPEED_COLUMNS.items()},
    **{state: (col, "rad") for state, col in results.PATCH_STATE_COLUMNS.items()},
    **{state: (col, "m") for state, col in results.CARCASS_STATE_COLUMNS.items()},
    "v_fwd": ("forward_velocity", "m/s"), "v_lat": ("lateral_velocity", "m/s"),
    "fyr": ("fy_rear", "N"), "fyf": ("fy_front", "N"), "mzr": ("mz_rear", "N m"), "mzf": ("mz_front", "N m"),
    # the reflex delay filter's states (controllable canonical form, torque-like)
    **{name: (f"reflex_filter_{name.rsplit('_', 1)[1]}", "N m") for name in slip.REFLEX_STATES},
}


def active_states(transient=DEFAULT_TRANSIENT, body=(), constant_speed=True):
    """State names of the linear model: :func:`whipple_kick.model.slip.linear_states` then the rider body's.

    Parameters
    ----------
    transient : str
        Tyre transient form (names the four tyre states).
    body : tuple of str
        The body states the linearisation includes
        (:func:`whipple_kick.model.slip.linear.body_states`): the upper body's lean
        the parts' states (q11, u11 of the leaning upper body), the reflex filter's states when the
        delay is not 0; none for the rigid rider.
    constant_speed : bool
        Without the forward velocity (the default model).

    Example
    -------
    >>> active_states(body=("q11", "u11"))[-3:]
    ('camber_patch_f', 'q11', 'u11')
    """
    names = tuple(slip.linear_states(transient)) + tuple(body)
    return tuple(n for n in names if not (constant_speed and n == "v_fwd"))


def state_labels(transient=DEFAULT_TRANSIENT, constant_speed=True, body=()):
    """(name, unit) of each state of the linear model, in order.

    Parameters
    ----------
    transient : str
        Tyre transient form (names the four tyre states).
    constant_speed : bool
        Without the forward velocity (the default model).
    body : tuple of str
        The rider body's states after them (:func:`active_states`).

    Returns
    -------
    list of (str, str)

    Example
    -------
    >>> state_labels()[:2]
    [('roll', 'rad'), ('steer', 'rad')]
    """
    # The declared parts' states (the leaning upper body's lean and its rate) and the form's state columns read
    # now: a part or form declared after this module was imported counts too; a form's state it gives no column
    # is named as it is, without a unit.
    labels = {**results.part_columns(),
              **{n: (col, unit) for col, source, n, unit in FORMS[transient].columns if source == "state"}, **_LABELS}
    return [labels.get(n, (n, "")) for n in active_states(transient, body, constant_speed)]


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
        Model state names (:data:`whipple_kick.model.slip.LINEAR_STATES` order, then
        the rider body's states the model has: :func:`active_states`).
    labels : list of (str, str)
        Readable name and unit of each state.
    steady : whipple_kick.simulate.steady.SteadyState
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
        >>> from whipple_kick import Scenario
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


def _constant_speed(A, B, names):
    keep = [i for i, n in enumerate(names) if n != "v_fwd"]
    return A[np.ix_(keep, keep)], B[keep]


def _gains_vector(params, states):
    """The rider's gains on ``states`` (``T7 = -K x``; the yaw-angle gain is refused).

    A gain on the upper body's lean needs the lean among ``states`` (a
    leaning rider); on a locked hip it multiplies a state that stays 0.
    """
    if params.get("kq3", 0.0):
        raise InputError("a yaw-angle gain kq3 breaks the heading invariance the linear model needs")
    K = np.zeros((1, len(states)))
    for gain, state in slip.gain_states().items():   # q3 is not among the states (kq3 is refused above)
        if state in states:
            K[0, states.index(state)] = params.get(gain, 0.0)
    return K


def linearise(params, steady_state, loop, found_by="direct", constant_speed=True):
    """:class:`LinearModel` of the slip model with ``params`` about ``steady_state``.

    Parameters
    ----------
    params : mapping
        Slip-model parameters; their gains are the rider's (0 for ``loop="open"``).
    steady_state : whipple_kick.simulate.steady.SteadyState
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
    >>> model = linearise(params, steady.steady_state(params, 4.0), "open")   # doctest: +SKIP
    """
    rhs = slip.CompiledRHS(steady_state.params)
    J, B = slip.heading_linearisation(rhs, steady_state.x)
    body = tuple(slip.linear.body_states(rhs))
    if constant_speed:
        J, B = _constant_speed(J, B, slip.LINEAR_STATES + body)
    states = active_states(rhs.transient, body, constant_speed)
    # The model as parametrised is A - B K; the open loop adds B K back (the body's passive
    # hip and arms and the delayed reflex stay: they are the model's, not the voluntary law's).
    K = _gains_vector(params, list(active_states(DEFAULT_TRANSIENT, body, constant_speed)))
    return LinearModel(speed=float(steady_state.x[slip.X["u1"]]), loop=loop, A=J + B @ K, B=B,
                       K=K if loop == "closed" else np.zeros_like(K), states=states,
                       labels=state_labels(rhs.transient, constant_speed, body), steady=steady_state,
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
    #: The no-slip model's bicycle with its rider: the rigid rider's (the same rider lumped into the rear
    #: frame, arms off the bar) when the scenario splits the body. (``design`` is that rider's already.)
    classic_moore: dict = None
    #: The LQR rider designed on the model simulated, by design speed (``lqr_model="simulated"``).
    designs: dict = field(default_factory=dict)


def _setup(scenario, tyres=None):
    assembly.preflight(scenario)
    moore, design, info = assembly.build_bicycle(scenario.bicycle_spec)
    if tyres is None:
        rear, front, notes = assembly.build_tyres(scenario.tyre_spec)
    else:
        (rear, front), notes = tyres, [f"tyres given: {tyres[0]!r} (rear), {tyres[1]!r} (front)"]
    # The no-slip reference's rider is the rigid one: the whole rider lumped, as in the run's verdict.
    classic_moore = assembly.no_slip_plant(moore, design, info)
    return _Setup(scenario, moore, design, info, (rear, front), notes, scenario.controller, classic_moore)


def _base_params(setup):
    """Slip-model parameters of the scenario without steer control (with the rider's body, arms and reflex).

    The run's own (:func:`whipple_kick.simulate.assembly.model_parameters`): every model option of the
    scenario, the carcass tyre's damping, stiffness scale, sliding law and viscosity included.
    """
    sc = setup.scenario
    return assembly.model_parameters(sc.model_spec, None, setup.moore, assembly.rider_body(sc.body_spec, setup.info),
                                     *setup.tyres, None, assembly.model_of(sc.body_spec, sc.tyre_transient))


def _loop_params(setup, speed, loop, base=None):
    """Slip-model parameters at ``speed`` for ``loop`` (the rider's gains designed for that speed).

    With ``lqr_model="simulated"`` the LQR rider is designed on the model
    simulated (:func:`whipple_kick.simulate.control.lqr_on_simulated_model`), once
    per design speed.
    """
    params = (_base_params(setup) if base is None else base).copy()
    if loop == "closed":
        params.update(_rider_gains(setup, speed))
    return params


def _rider_gains(setup, speed):
    """The rider's gains by name at ``speed`` (the LQR on the simulated model cached per design speed)."""
    sc = setup.scenario.with_changes(speed=float(speed))
    if sc.controller != "lqr" or sc.lqr_model != "simulated":
        return assembly.controller_gains(sc.gains_spec, setup.design)[0]
    key = float(sc.lqr_design_speed)
    if key not in setup.designs:
        try:
            setup.designs[key] = control.lqr_on_simulated_model(
                sc.design_spec, setup.moore, setup.design, assembly.rider_body(sc.body_spec, setup.info),
                *setup.tyres, assembly.model_of(sc.body_spec, sc.tyre_transient))[0]
        except InputError as exc:
            setup.designs[key] = NoRiderDesign(f"no LQR rider designed on the model simulated at {key:g} m/s: "
                                               f"{exc}")
    if isinstance(setup.designs[key], NoRiderDesign):
        raise setup.designs[key]
    return setup.designs[key]


class NoRiderDesign(InputError):
    """The LQR rider could not be designed on the model simulated at a speed (the sweep leaves it out there)."""


def _steady(params, speed, guess):
    """(SteadyState, found_by): continued from ``guess``, else the robust search (may raise NoSteadyMotion).

    Only near-upright motions inside the tyres' measured range
    (:func:`whipple_kick.simulate.steady.start_problem`), stable or not: a
    continued motion that has left them is searched for afresh, and a speed
    with none is left out as having no near-upright steady motion.
    """
    if guess is not None:
        try:
            continued = steady.steady_state(params, speed, guess=guess)
        except FloatingPointError:
            continued = None
        if continued is not None and steady.start_problem(continued) is None:
            return continued, "continued"
    found = steady.find_steady_state(params, speed, hold=False)
    return found.steady, found.route


def linear_model(scenario, speed, loop="open", *, tyres=None):
    """The slip model of ``scenario`` linearised about its steady motion at ``speed`` [m/s].

    Parameters
    ----------
    scenario : whipple_kick.simulate.scenario.Scenario
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
    >>> from whipple_kick.studies.stability import linear_model
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
