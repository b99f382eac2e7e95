"""Assembly: bicycle, rider, tyres and the rider's gains -> the slip model's parameters and its steady motion.

The second step of a run (:func:`whipple_kick.simulate.simulation.run`): from a
validated :class:`~whipple_kick.simulate.scenario.Scenario` and its kick
(:mod:`whipple_kick.library.inputs`), :func:`assemble` seats the Yeadon rider on
the bicycle (:func:`build_bicycle`), loads the tyres (:func:`build_tyres`),
designs or looks up the rider's steer-torque gains (:func:`controller_gains`),
names every parameter of the compiled model (:func:`model_parameters`), finds the steady motion the
run starts from (:func:`whipple_kick.simulate.steady.start_state`) and judges whether the rider is
linearly stable about it (:func:`linear_stability`). The result is one
:class:`Assembly`, handed to the integration.

Each of those steps takes the part of the scenario it reads, a frozen view
(``scenario.bicycle_spec``, ``.tyre_spec``, ``.body_spec``, ``.gains_spec``,
``.model_spec``, ``.design_spec``: :mod:`whipple_kick.simulate.scenario`), not the
whole scenario: what a step reads is declared there, and the per-process caches
are keyed on it.

Example
-------
>>> import whipple_kick as wk
>>> sc = wk.Scenario(controller="thesis", fz_n=701.0)
>>> wk.assembly.controller_gains(sc.gains_spec, None)[0]["kq4"]   # Table 8.4, 701 N
-20.5164
"""
import copy
from dataclasses import dataclass
import functools
import pathlib

import numpy as np

from whipple_kick.errors import InputError, check_range
from whipple_kick.library import bicycleparameters, riders, thesis, tyres
from whipple_kick.model import benchmark, parts, slip, symbols
from whipple_kick.simulate import control, steady
from whipple_kick.simulate.scenario import Scenario

from .scenario import DEFAULTS, LOW_INERTIA_KEYS, SETTINGS, THESIS_DESIGN_SPEED

#: The rear load [N] a rider is seated for when neither ``fz_n`` nor ``rider_mass_kg`` is given (``fz_n``'s rule).
DEFAULT_REAR_LOAD_N = SETTINGS["fz_n"].none_means

#: ``|steady yaw rate|`` [rad/s] below which steady running counts as straight (a yaw-angle gain needs it).
STRAIGHT_YAW_RATE = 1e-9


@dataclass
class Assembly:
    """Everything a run integrates and reports about its set-up.

    Attributes
    ----------
    rear, front : whipple_kick.library.tyres.Tyre
        The tyres (or the caller's tyre objects).
    tyre_notes : list of str
        What the summary says about them (missing M_z data, custom tyres).
    moore : dict
        Moore parameters of the bicycle with rider (low-inertia change applied).
    bicycle : dict
        The summary's ``bicycle`` section: rider mass [kg], static loads [N], total mass [kg].
    gains : dict
        Steer-torque gains by name (N m/rad, N m s/rad).
    design_poles : ndarray or None
        The LQR design's closed-loop poles at its design speed [1/s].
    controller : str
        ``lqr``, ``thesis``, ``off`` or ``custom gains``.
    params : whipple_kick.model.slip.Parameters
        The compiled model's parameters (the steady drive torque T6c included) with their model (:attr:`model`).
    found : whipple_kick.simulate.steady.Found
        The steady motion stability is judged about, and how it was found.
    start : whipple_kick.simulate.steady.SteadyState
        The state the run starts from (the steady motion, or an upright start).
    stability : dict
        :func:`linear_stability`'s verdict.
    """

    rear: object
    front: object
    tyre_notes: list
    moore: dict
    bicycle: dict
    gains: dict
    design_poles: np.ndarray | None
    controller: str
    params: dict
    found: object
    start: object
    stability: dict

    @property
    def model(self):
        """The compiled model's description (parts, delay filter, tyre form) its parameters are for."""
        return self.params.model

    @property
    def reference(self):
        """The steady motion recovery is measured back to (upright running when the tyres allow none)."""
        return self.start if self.found.route == steady.SYMMETRIC_ROUTE else self.found.steady


def assemble(scenario, kick, *, tyres=None, gains=None) -> Assembly:
    """Build the model of one run: tyres, bicycle with rider, gains, parameters, steady motion, stability.

    Parameters
    ----------
    scenario : whipple_kick.simulate.scenario.Scenario
        Validated.
    kick : whipple_kick.library.inputs.Kick
        The plate motion (its first piece enters the parameters).
    tyres : (rear, front), optional
        Tyre objects instead of the scenario's tyre and pressures.
    gains : mapping, optional
        Steer-torque gains by name instead of the scenario's controller.

    Returns
    -------
    Assembly

    Raises
    ------
    InputError
        A tyre, bicycle, rider or gain the scenario names is unknown or out
        of range; no steady motion to start from
        (:class:`whipple_kick.simulate.steady.NoSteadyMotion`); a yaw-angle gain with
        a steady turn.
    """
    custom = None if gains is None else custom_gains(gains, scenario)
    # Tyres first: a pressure outside the measured range is the commonest mistake and cheap to find.
    if tyres is None:
        rear, front, notes = build_tyres(scenario.tyre_spec)
    else:
        _refuse_tyre_fields(scenario)
        rear, front = tyres
        notes = [f"custom tyre objects (the scenario's tyre and pressures are not used): "
                 f"rear {rear!r}, front {front!r}"]
    moore, design, info = build_bicycle(scenario.bicycle_spec)
    body = rider_body(scenario.body_spec, info)
    model = model_of(scenario.body_spec, scenario.tyre_transient)
    if custom is None and scenario.controller == "lqr" and scenario.lqr_model == "simulated":
        gains, poles = (simulated_design(scenario.design_spec, scenario.tyre_spec, scenario.bicycle_spec,
                                         scenario.body_spec) if tyres is None
                        else control.lqr_on_simulated_model(scenario.design_spec, moore, design, body, rear, front, model))
        controller = scenario.controller
    elif custom is None:
        gains, poles = controller_gains(scenario.gains_spec, design)
        controller = scenario.controller
    else:
        gains, poles, controller = custom, None, "custom gains"
    params = model_parameters(scenario.model_spec, kick, moore, body, rear, front, gains, model)
    found, start = steady.start_state(params, float(scenario.speed), start=scenario.start,
                                      start_pitch=scenario.start_pitch, advice=_steady_advice(scenario, controller))
    stability = linear_stability(scenario, no_slip_plant(moore, design, info), gains, found, controller)
    steady_yaw_rate = float(start.x[slip.X["u3"]])
    if gains.get("kq3", 0.0) and abs(steady_yaw_rate) > STRAIGHT_YAW_RATE:
        # In a steady turn the yaw angle grows without bound, and so would kq3's torque.
        raise InputError(f"a yaw-angle gain kq3 needs straight steady running, but the steady yaw rate is "
                         f"{steady_yaw_rate:.3g} rad/s (allowed |yaw rate| <= {STRAIGHT_YAW_RATE:g} rad/s): "
                         "use tyres without zero-slip offsets (the flag --symmetric-tyres; symmetric_tyres=True in Python)")
    return Assembly(rear, front, notes, moore, info, gains, poles, controller, start.params, found, start, stability)


#: Scenario fields the tyre objects of ``run(scenario, tyres=...)`` replace (what :func:`build_tyres` reads).
CUSTOM_TYRE_FIELDS = ("tyre", "pressure_kpa", "pressure_front_kpa", "pressure_rear_kpa", "coefficient_set", "friction")


def without_tyre_fields(scenario):
    """``scenario`` with the fields that tyre objects replace (:data:`CUSTOM_TYRE_FIELDS`) at their defaults.

    For ``run(scenario, tyres=(rear, front))`` where the scenario named the tyres the objects were made from
    (e.g. built with :func:`build_tyres` from it): the objects carry those settings now.
    """
    return scenario.with_changes(**{name: DEFAULTS[name] for name in CUSTOM_TYRE_FIELDS})


def _refuse_tyre_fields(scenario):
    """Tyre objects given replace the scenario's tyre, pressures, coefficient set and friction: one given as well
    would be ignored (a note in the summary is lost in a sweep), so it is refused, naming each such field."""
    given = [f for f in CUSTOM_TYRE_FIELDS if getattr(scenario, f) != DEFAULTS[f]]
    if given:
        raise InputError("tyres=(rear, front) replace the scenario's tyre fields, so "
                         + ", ".join(f"{f} = {getattr(scenario, f)!r}" for f in given)
                         + " would be ignored: leave " + ("it" if len(given) == 1 else "them") + " at the default ("
                         + ", ".join(f"{f} = {DEFAULTS[f]!r}" for f in given) + ") or load the tyres with "
                         "those options (whipple_kick.library.tyres.load)")


# ------------------------------------------------------------------ the parts

def model_of(body_spec, tyre_transient):
    """The compiled model a scenario asks for (:class:`whipple_kick.model.slip.Model`), from its settings.

    The declared parts its fields select (:func:`whipple_kick.model.parts.selected`: the leaning upper body,
    the arms on the bar), the reflex's delay filter when its ``reflex_delay`` is not 0 (the field's "0: none"),
    and its tyre transient form. ``body_spec`` is ``scenario.body_spec``.
    """
    return slip.Model(tuple(p.name for p in parts.selected(body_spec)), body_spec.reflex_delay != 0.0,
                      tyre_transient)


def model_parameters(spec, kick, moore, body, rear, front, gains, model):
    """The compiled model's parameters by name, with their model (before the steady drive torque is found).

    Parameters
    ----------
    spec : whipple_kick.simulate.scenario.ModelSpec
        The model's options (``scenario.model_spec``).
    kick : whipple_kick.library.inputs.Kick or None
        The plate motion (its first piece enters the parameters); None: the plate stays still (a linear
        analysis about the steady motion).
    moore : dict
        The bicycle with rider (:func:`build_bicycle`).
    body : dict
        The rider's body parameters (:func:`rider_body`).
    rear, front : whipple_kick.library.tyres.Tyre
    gains : dict or None
        Steer-torque gains by name.
    model : whipple_kick.model.slip.Model
        The model (:func:`model_of`).
    """
    return slip.model_parameters(moore, rear, front, spec, model=model, gains=gains, body=body,
                                 kick=None if kick is None else kick.model_kick())


def build_bicycle(spec):
    """Bicycle with rider for ``spec`` (``scenario.bicycle_spec``): (moore parameters, design parameters, info dict).

    The info holds the rider mass [kg] and the static loads [N] of the
    unmodified bicycle; ``moore`` has the low-inertia change applied if asked.
    ``design`` is the unmodified set the LQR is designed on: the whole rider
    lumped into the rear frame, also when ``moore`` splits it into a body. Cached per
    process on the spec and the bicycle file's stamp (a sweep over pressures, speeds or kicks
    seats the Yeadon rider once); callers get their own copies.
    """
    return _copied(_bicycle_setup(spec, _file_stamp(spec.bicycle)))


#: Leaf types :func:`_copied` shares instead of copying (immutable).
_IMMUTABLE = frozenset({float, int, str, bool, type(None), np.float64})


def _copied(value):
    """``copy.deepcopy(value)`` of nested dicts, lists and tuples, sharing their immutable leaves.

    Equal to the deep copy, for a tenth of its cost (a sweep copies the cached bicycle once a case);
    a leaf of another type is deep-copied.
    """
    kind = type(value)
    if kind in _IMMUTABLE:
        return value
    if kind is dict:
        return {k: v if type(v) in _IMMUTABLE else _copied(v) for k, v in value.items()}
    if kind is list:
        return [v if type(v) in _IMMUTABLE else _copied(v) for v in value]
    if kind is tuple:
        return tuple(_copied(v) for v in value)
    return copy.deepcopy(value)


def _file_stamp(name):
    """Modification time of a parameter file given by path (so an edited file is re-read)."""
    path = pathlib.Path(str(name))
    if path.suffix != ".toml" and bicycleparameters.is_bicycleparameters_path(name):
        return bicycleparameters.stamp(name)
    return path.stat().st_mtime_ns if path.suffix == ".toml" and path.is_file() else None


@functools.lru_cache(maxsize=256)
def _bicycle_setup(spec, _stamp):
    bike = bicycleparameters.load_bicycle(spec.bicycle, spec.rider)
    # The model's parts that split the rider (riders.carriers: the leaning upper body, the arms on the bar).
    model_parts = tuple(p.name for p in parts.selected(spec))
    split = bool(riders.carriers(model_parts))
    if split and bike.includes_rider:
        raise _lumped_rider_error(bike)
    _refuse_rider_file(bike, spec.rider)
    if bike.includes_rider:
        _refuse_load_on_preset(bike, spec.fz_n, spec.rider_mass_kg, spec.rear_load_share)
        combined, rider_mass = bike, None
    elif spec.rear_load_share is not None:
        # The rider is shifted fore-aft so that the share holds (riders.for_load_share).
        fz = DEFAULT_REAR_LOAD_N if spec.fz_n is None and spec.rider_mass_kg is None else spec.fz_n
        solution = riders.for_load_share(bike, spec.rear_load_share, fz_n=fz, rider_mass_kg=spec.rider_mass_kg,
                                          rider=spec.rider)
        combined, rider_mass, shift = solution.combined, solution.rider_mass_kg, solution.shift_m
    elif spec.rider_mass_kg is not None:
        rider = riders.yeadon_rider(spec.rider, mass_kg=spec.rider_mass_kg)
        combined, rider_mass = riders.seat(bike, rider), float(spec.rider_mass_kg)
    else:
        fz = DEFAULT_REAR_LOAD_N if spec.fz_n is None else spec.fz_n
        combined, rider_mass = riders.for_rear_load(bike, fz, rider=spec.rider,
                                                    load_range=_rear_load_range(spec.bicycle, _stamp, spec.rider))
    # The static loads and the Whipple model the LQR is designed on are the whole rider's: the split below
    # moves the upper body out of the bicycle's parameters, not out of the statics or the rider's mass.
    if spec.rear_load_share is None:
        shift = 0.0 if rider_mass is not None else None
    rear_n, front_n = riders.static_loads(combined)
    design = dict(combined.moore)
    body, body_mass, held = None, 0.0, ()
    if split:
        # The same rider, split as the model's parts declare: the legs in the rear frame, the forearms in
        # the front frame (on the bar), the upper body on its hip.
        rider = riders.yeadon_rider(spec.rider, mass_kg=rider_mass)
        combined, body, body_mass, held = riders.split_rider(bike, rider, model_parts, shift_m=shift)
    moore = dict(combined.moore)
    for hold, own in held:
        # A part the model lacks whose body the rear frame holds (the rigid rider's upper body with the
        # arms on the bar; the forearms turn with the bar).
        moore = hold(moore, own)
    if spec.low_inertia:
        bench = dict(combined.benchmark)
        for key in LOW_INERTIA_KEYS:
            bench[key] *= 0.5
        moore = benchmark.to_moore(bench)
    info = {"bicycle": bike.name, "includes_rider_preset": bike.includes_rider,
            # What the bicycle's source lacked, from defaults (a BicycleParameters set): name -> "value unit: source".
            "defaults": bicycleparameters.describe_defaults(bike),
            "rider_mass_kg": rider_mass, "static_load_rear_n": rear_n, "static_load_front_n": front_n,
            # The rider's fore-aft shift from the seated posture [m, forward positive]: 0 seated, None for a preset.
            "rider_shift_m": shift, "rear_load_share": rear_n / (rear_n + front_n),
            # The seated posture the parameters come from (shift included; riders.SeatedRider.posture), so a
            # drawing shows the rider the run had without seating it again; None for a preset.
            "rider_posture": None if bike.includes_rider else dict(combined.rider["posture"]),
            "total_mass_kg": sum(float(combined.benchmark[k]) for k in ("mR", "mB", "mH", "mF"))
            + body_mass, "body": body}
    return moore, design, info


def _refuse_load_on_preset(bike, fz_n, rider_mass_kg, share):
    """A preset with its rider lumped in seats no rider: a load, mass or share given with it would be ignored."""
    if fz_n is not None or rider_mass_kg is not None:
        raise InputError(f"bicycle {bike.name!r} already includes its rider; "
                         "do not give a rear-tyre load fz or a rider mass with it")
    if share is not None:
        raise InputError(f"rear load share = {share!r} (unit 1) would be ignored: bicycle {bike.name!r} already "
                         "includes its rider, whose place is fixed; allowed: none (or a bicycle-only set)")


def _refuse_rider_file(bike, rider_name):
    """A preset with its rider lumped in seats no Yeadon rider: a rider file given with it would be ignored."""
    default = Scenario.__dataclass_fields__["rider"].default
    if bike.includes_rider and rider_name not in (default, riders.NO_RIDER):
        raise InputError(f"bicycle {bike.name!r} already includes its rider; rider {rider_name!r} would be ignored: "
                         f"leave it at its default {default!r} (or {riders.NO_RIDER!r}) or choose a bicycle-only set")


def no_slip_plant(moore, design, info):
    """Moore parameters of the whole bicycle with rider, for the no-slip classic model of the run's plant.

    ``moore`` itself for a rider lumped into the rear frame; with a rider's body (``info["body"]``)
    ``moore`` holds the bicycle without the upper body, whose mass the classic model would leave out, so
    the lumped ``design`` set (the whole rider, locked at the hip) is the plant. (``low_inertia``, the one
    change ``design`` lacks, is refused with a body.)
    """
    return design if info.get("body") else moore


def _lumped_rider_error(bike):
    return InputError(f"bicycle {bike.name!r} has its rider lumped in already: a leaning rider or arms on the "
                      "bar need a bicycle-only set with a Yeadon rider (e.g. 'balanceassist_v1')")


@functools.lru_cache(maxsize=64)
def _rear_load_range(bicycle, _stamp, rider_name):
    # The rear loads a rider can give the bicycle (a probe rider seated, ~10 ms) do not depend on the load:
    # a sweep over loads finds them once per process.
    return riders.rear_load_range(bicycleparameters.load_bicycle(bicycle), rider_name)


def rider_body(spec, info):
    """The rider's body parameters by name (:func:`whipple_kick.model.slip.parameters.body_names`).

    ``spec`` is ``scenario.body_spec``, ``info`` :func:`build_bicycle`'s.
    The reflex (:data:`~whipple_kick.model.slip.parameters.RIGID_BODY`) in every model; each declared part
    the scenario selects adds its fields' parameters and its declared values, and those it takes from the
    rider's segments (:attr:`whipple_kick.model.parts.Part.from_rider`: the leaning upper body's placement
    and inertia from :func:`build_bicycle`); the arms on the bar (the arms part) their spring-damper. (The rigid rider with arms on the bar has its upper body in :func:`build_bicycle`'s
    rear frame.)
    """
    body = dict(slip.parameters.RIGID_BODY)
    rider = info.get("body") or {}
    for part in parts.selected(spec):   # the model with the selected parts, each as its declaration says
        body.update(part.field_parameters(spec))
        body.update({n: rider[n] for n in part.from_rider if n in rider})
    body.update(rq4=spec.reflex_roll, ru4=spec.reflex_roll_rate, rq7=spec.reflex_steer,
                ru7=spec.reflex_steer_rate, reflex_delay=spec.reflex_delay)
    return body


def simulated_design(design, tyres, bicycle, body):
    """:func:`~whipple_kick.simulate.control.lqr_on_simulated_model` on the scenario's own tyres and bicycle.

    ``design``, ``tyres``, ``bicycle`` and ``body`` are the scenario's ``design_spec``, ``tyre_spec``,
    ``bicycle_spec`` and ``body_spec``: all the design reads. Once per process for each (both kick
    directions, or any kick, of a case share one design); callers get their own copies.

    Returns
    -------
    gains : dict
        By name.
    poles : ndarray
        The design's closed-loop eigenvalues.
    """
    # Keyed on the bicycle file's stamp too, as build_bicycle is: an edited file is designed on again.
    gains, poles = _simulated_design(design, tyres, bicycle, body, _file_stamp(bicycle.bicycle))
    return dict(gains), np.array(poles)


@functools.lru_cache(maxsize=256)
def _simulated_design(design_spec, tyre_spec, bicycle_spec, body_spec, _stamp):
    rear, front, _ = build_tyres(tyre_spec)
    moore, design, info = build_bicycle(bicycle_spec)
    model = model_of(body_spec, dict(design_spec.model_options)["tyre_transient"])
    gains, poles = control.lqr_on_simulated_model(design_spec, moore, design, rider_body(body_spec, info), rear, front,
                                                  model)
    return tuple(gains.items()), tuple(poles)


def controller_gains(spec, design):
    """Steer-torque gains by name, and the LQR design's closed-loop poles at its design speed (or None).

    ``spec`` is ``scenario.gains_spec``; ``design`` the Whipple model the LQR rider is designed on
    (:func:`build_bicycle`'s; unused by the other controllers). The LQR rider is designed at
    :attr:`Scenario.lqr_design_speed` (the run's speed unless ``design_speed`` is given).
    """
    if spec.controller == "off":
        return dict.fromkeys(control.GAIN_ORDER, 0.0), None
    if spec.controller == "thesis":
        gains = control.thesis_gains(thesis_load(spec))
        return {k: spec.gain_scale * v for k, v in gains.items()}, None
    K, poles = control.whipple_lqr(design, float(spec.lqr_design_speed))
    return control.gains_dict(K, spec.gain_scale), poles


def thesis_load(spec):
    """Rear load [N] whose Table 8.4 row ``controller="thesis"`` uses (``spec``: ``scenario.gains_spec``).

    ``thesis_load_n`` if given, else ``fz_n``, else the load a preset with
    rider is labelled with (``balanceassist_635N``: 635 N), else :data:`DEFAULT_REAR_LOAD_N` for a
    bicycle whose rider is seated for the default load.
    """
    if spec.thesis_load_n is not None:
        return spec.thesis_load_n
    if spec.fz_n is not None:
        return spec.fz_n
    bike = bicycleparameters.load_bicycle(spec.bicycle, spec.rider)
    if bike.includes_rider and bike.thesis_rear_load_n is not None:
        return bike.thesis_rear_load_n
    if spec.rider_mass_kg is None and not bike.includes_rider:
        return DEFAULT_REAR_LOAD_N
    raise InputError(f"controller thesis uses Table 8.4 gains for a rear load of {thesis.loads_text(last=' or ')} N: "
                     "give fz (N), or thesis_load_n (--thesis-load N) for a rider given by mass or a preset with rider")


def thesis_gains_warning(spec):
    """One line when ``controller="thesis"`` uses the Table 8.4 gains of another load than the run's, else None.

    ``spec`` is ``scenario.gains_spec``. The run's load: the one a preset with rider is labelled with, or
    ``fz_n``.
    """
    if spec.controller != "thesis":
        return None
    bike = bicycleparameters.load_bicycle(spec.bicycle, spec.rider)
    own, what = ((bike.thesis_rear_load_n, f"bicycle {bike.name!r} is labelled") if bike.includes_rider
                 else (spec.fz_n, "the rider is seated for"))
    gains = thesis_load(spec)
    if own is None or abs(own - gains) < 1e-9:
        return None
    return (f"the Table 8.4 gains in use are those for {gains:g} N, but {what} a rear load of {own:g} N "
            f"(thesis_load_n = {gains:g} N; leave it unset for the gains of {own:g} N)")


def build_tyres(spec):
    """(rear, front) tyres and a list of notes about them, for ``spec`` (``scenario.tyre_spec``)."""
    notes = []
    rear_p, front_p = spec.pressures
    loaded = []
    for p in (rear_p, front_p):
        # missing_moment="zero" changes nothing for a tyre with M_z data (its flag says which it is).
        tyre = tyres.load(spec.tyre, p, coefficient_set=spec.coefficient_set,
                          friction=spec.friction, missing_moment="zero")
        loaded.append(tyre)
        if not tyre.has_aligning_moment:
            # Tyres without published M_z data: run with M_z = 0 and say so.
            note = f"{spec.tyre} has no published aligning-moment data: M_z = 0"
            if note not in notes:
                notes.append(note)
    return loaded[0], loaded[1], notes


def preflight(scenario):
    """Cheap checks of everything a user can get wrong, before any long work.

    It takes the whole scenario, as it checks the whole of it: field ranges
    (:meth:`~whipple_kick.simulate.scenario.Scenario.validate`), tyre name and
    pressure range, bicycle name and rider conflicts (a preset with its rider
    lumped in cannot lean or hold the bar), the Table 8.4 row of
    ``controller="thesis"``. Raises :class:`InputError`; returns ``scenario``.
    """
    scenario.validate()
    build_tyres(scenario.tyre_spec)
    bike = bicycleparameters.load_bicycle(scenario.bicycle, scenario.rider)
    if bike.includes_rider:
        _refuse_load_on_preset(bike, scenario.fz_n, scenario.rider_mass_kg, scenario.rear_load_share)
    if bike.includes_rider and (scenario.rider_body != "rigid" or scenario.arms == "on"):
        raise _lumped_rider_error(bike)
    _refuse_rider_file(bike, scenario.rider)
    if scenario.controller == "thesis":
        control.thesis_gains(thesis_load(scenario.gains_spec))
    return scenario


#: A closed-loop pole whose real part exceeds this [1/s] makes the rider linearly unstable (defined with the
#: steady search, which refuses an unstable steady turn as a start).
UNSTABLE_REAL_PART = steady.UNSTABLE_REAL_PART


def who_rides(scenario, controller_type):
    """How the summary and the messages name the rider in use."""
    if controller_type == "lqr":
        on = " on the model simulated" if scenario.lqr_model == "simulated" else ""
        return f"the LQR rider designed{on} at {scenario.lqr_design_speed:g} m/s"
    if controller_type == "thesis":
        return f"the thesis' Table 8.4 rider (designed at {THESIS_DESIGN_SPEED:g} m/s)"
    if controller_type == "off":
        return "the bicycle without steer control"
    return "the rider with the given gains"


def _steady_advice(scenario, controller_type):
    """What a user can change when there is no steady motion (for the one-line error)."""
    symmetric = "or tyres without zero-slip offsets (--symmetric-tyres, symmetric_tyres=True)"
    if controller_type == "lqr" and scenario.lqr_model == "whipple" and (
            scenario.rider_body != "rigid" or scenario.arms == "on"):
        # The rider designed on the Whipple model does not know the body or arms it rides with (measured:
        # with the forearms' mass on the bar the near-upright branch ends at 86 % of the offsets).
        return ("the rider is designed on the Whipple model without the rider's body or arms: design it on the "
                f"model simulated (--lqr-model simulated, lqr_model='simulated'), {symmetric}")
    if controller_type == "lqr" and scenario.design_speed is not None:
        return (f"the rider is designed at {scenario.design_speed:g} m/s: choose another design speed "
                f"(--design-speed; by default the run's speed) or another speed, {symmetric}")
    if controller_type == "thesis":
        return (f"Table 8.4's rider was designed at {THESIS_DESIGN_SPEED:g} m/s: choose controller lqr "
                f"(designed at the run's speed) or another speed, {symmetric}")
    if controller_type == "lqr":
        # At 4-8 m/s the rider designed at the run's speed is weak on the slip model; the 3 m/s design holds the
        # start there (measured over the speed envelope, docs/simulate.md).
        return (f"choose another speed or tyre pressure, a design speed for the rider (e.g. --design-speed "
                f"{THESIS_DESIGN_SPEED:g}), {symmetric}")
    return f"choose another speed, rider or tyre pressure, {symmetric}"


def linear_stability(scenario, moore, gains, found, controller_type):
    """Is the rider in use linearly stable at the run's speed?

    Poles of the slip model linearised about the steady motion at constant
    speed (:func:`whipple_kick.simulate.steady.lateral_poles`; decisive) and of the
    no-slip classic model of the same bicycle with the same gains
    (:func:`whipple_kick.simulate.control.closed_loop_poles`). A yaw-angle gain breaks
    the slip linearisation's heading invariance: then the classic model decides.

    Returns
    -------
    dict
        ``stable``, ``message`` (one line, None when stable), ``slowest_pole_1_s``,
        ``model`` (which linearisation decided), ``poles_slip_model_1_s``,
        ``poles_no_slip_model_1_s`` (each as [real, imag] pairs), ``criterion``.
    """
    classic = control.classic_closed_loop_poles(moore, float(scenario.speed), gains)
    slip_poles = None
    if not gains.get("kq3", 0.0):
        try:
            slip_poles = steady.lateral_poles(found.steady.params, found.steady.x)
        except FloatingPointError:   # the linearisation's pitch solve failed: the classic model decides
            slip_poles = None
    about = steady.SYMMETRIC_ABOUT if found.route == steady.SYMMETRIC_ROUTE else "the steady motion"
    decisive, model = ((slip_poles, f"slip model about {about}, constant speed")
                       if slip_poles is not None else (classic, "no-slip classic model"))
    slowest = decisive[0]
    stable = bool(slowest.real <= UNSTABLE_REAL_PART)
    message = None
    if not stable:
        message = (f"{who_rides(scenario, controller_type)} is linearly unstable at {scenario.speed:g} m/s: "
                   f"slowest closed-loop pole {_pole_text(slowest)} 1/s ({model}; no-slip model "
                   f"{_pole_text(classic[0])} 1/s)" + _stabilising_advice(scenario, controller_type))
    pairs = lambda poles: None if poles is None else [[float(p.real), float(p.imag)] for p in poles]
    return {"stable": stable, "message": message, "slowest_pole_1_s": pairs([slowest])[0], "model": model,
            "poles_slip_model_1_s": pairs(slip_poles), "poles_no_slip_model_1_s": pairs(classic),
            "criterion": f"unstable when a closed-loop pole has real part > {UNSTABLE_REAL_PART:g} 1/s"}


def _stabilising_advice(scenario, controller_type):
    """What may make an unstable rider stable, as the end of :func:`linear_stability`'s message ("" if nothing)."""
    if controller_type != "lqr":
        return ""
    changes = []
    if scenario.lqr_model == "whipple" and (scenario.rider_body != "rigid" or scenario.arms == "on"):
        body = " and ".join(part for part, used in (("a leaning upper body", scenario.rider_body != "rigid"),
                                                    ("arms on the bar", scenario.arms == "on")) if used)
        changes.append(f"the rider is designed on the Whipple model without {body}: design it on the model "
                       "simulated (--lqr-model simulated, lqr_model='simulated')")
    if scenario.design_speed is not None and scenario.design_speed != scenario.speed:
        changes.append(f"it is designed at {scenario.design_speed:g} m/s: leave the design speed unset (the run's "
                       "speed)")
    return "; " + "; or ".join(changes) if changes else ""


def _pole_text(pole):
    text = f"{pole.real:+.3f}"
    return text + (f" +- {abs(pole.imag):.3f}j" if abs(pole.imag) > 1e-9 else "")


#: Scenario fields that choose or shape the rider's voluntary gains: user-given gains replace them all.
CONTROLLER_FIELDS = ("controller", "design_speed", "gain_scale", "thesis_load_n", "lqr_model", "lqr_heading")


def custom_gains(gains, scenario=None):
    """Check user-given steer-torque gains (by name) and fill the missing ones with 0.

    Every gain given is used (none is dropped): a declared part's gains need a
    scenario that selects it (the upper body's lean gains ``kq11``/``ku11``
    need ``scenario.rider_body="leaning"``: a rigid rider has no lean to feed back). With ``scenario``, its fields that the given gains
    replace (:data:`CONTROLLER_FIELDS`) must be at their defaults.
    """
    known = slip.gain_names()   # every declared part's gains, read now: a part declared after the import too
    unknown = sorted(set(gains) - set(known))
    if unknown:
        raise InputError(f"unknown steer-torque gain(s) {unknown}; known: {list(known)}")
    if scenario is not None:
        for name in CONTROLLER_FIELDS:
            if getattr(scenario, name) != DEFAULTS[name]:
                raise InputError(f"{name} = {getattr(scenario, name)!r} is replaced by the given gains (it would be "
                                 f"ignored): leave it at its default {DEFAULTS[name]!r} with gains=")
        for part in parts.REGISTRY.values():   # a part's gains feed back its states: a model without it has none
            given = [n for n in part.gains if gains.get(n, 0.0) != 0.0]
            if given and not part.selected(scenario):
                field, value = part.selected_by or ("", "")
                title = part.title or part.name
                states = ", ".join(dict.fromkeys(part.gains[n] for n in given))
                raise InputError(f"gain(s) {given} feed back {title}'s states ({states}), which only "
                                 + (f"{field} {value!r} has (here {getattr(scenario, field, 'off')!r})"
                                    if field else "a model with it has") + f"; allowed: 0 or {title}")
    # The four of the thesis' law always; the others (yaw, the upper body's lean) when given.
    names = control.GAIN_ORDER + tuple(n for n in known if n in gains and n not in control.GAIN_ORDER)
    return {name: check_range(f"gain {name}", gains.get(name, 0.0), None, None, symbols.info(name).unit)
            for name in names}


def control_law(gains):
    """``T7 = -(kq4 q4 + ...)`` with the gains in use (gain k<x> multiplies state <x>), for the summary."""
    return "T7 = -(" + " + ".join(f"{name} {name[1:]}" for name in gains) + ")"
