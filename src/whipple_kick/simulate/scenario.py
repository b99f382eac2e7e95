"""One kick-plate run described: the :class:`Scenario` dataclass and its validation.

A :class:`Scenario` holds everything a run of the thesis' kick-plate test
(Dell'Orto 2025, Sections 8.3-8.4) depends on, with the project's choices as
defaults (:meth:`Scenario.thesis` gives the thesis' own): the bicycle and
rider, the tyres, the speed, the rider's control, the kick
(:mod:`whipple_kick.library.inputs` turns its fields into the plate's
motion), the numerics. Each field is declared once, in the class body
(:func:`whipple_kick.simulate.settings.setting`): its default, unit, range,
group, the mechanism that reads it, the assembly steps' views that hold it
and its command-line flag; the documentation, :meth:`Scenario.validate`'s
per-field checks, :data:`FIELD_GROUPS`, :data:`MECHANISM_FIELDS`, the views
and the flags of :mod:`whipple_kick.cli` follow.
:meth:`Scenario.validate` raises one-line
:class:`~whipple_kick.errors.InputError` messages naming the value, the
allowed range and the unit. docs/simulate.md lists every decision.

Example
-------
>>> sc = Scenario(pressure_kpa=300.0, fz_n=701.0).validate()
>>> sc.pressures, sc.with_changes(speed=4.0).lqr_design_speed
((300.0, 300.0), 4.0)
"""
from dataclasses import asdict, dataclass, fields, make_dataclass, replace
import functools
import json
import math
import pathlib

from whipple_kick import fileio
from whipple_kick.errors import InputError, check_range
from whipple_kick.library import inputs, thesis, tyres
from whipple_kick.library.parameters import tomllib
from whipple_kick.model import carcass, parts, transient
from whipple_kick.model.slip import SLIP_SPEEDS

from . import criteria
from . import settings as _settings
from .settings import CASE_COMMANDS, EVERY_COMMAND, SIMULATE, part_setting, setting

#: Rider models: the LQR designed on the linearised classic model, the thesis' Table 8.4 gains, or none.
CONTROLLERS = ("lqr", "thesis", "off")
#: Rear-frame entries halved by the "low inertia" variant (thesis Figure 8.9).
LOW_INERTIA_KEYS = ("IBxx", "IByy", "IBzz", "IBxz", "zB")
#: Table 8.4's gains were designed at this speed [m/s] (thesis Section 8.3).
THESIS_DESIGN_SPEED = 3.0
#: Tyre transient forms (:func:`whipple_kick.model.transient.transients`), read when listed: a form declared after
#: the package was imported is a choice too.
TYRE_TRANSIENTS = criteria.Listing(transient.transients)
#: What happens to the speeds when the thesis' plate stops instantly (2 m/s to 0):
#: ``impulse`` (the rear no-slip constraint's impulse, momentum-consistent),
#: ``resolve`` (only the dependent speeds re-solved, as before the impulse existed)
#: or ``keep_speeds`` (no speed jumps; the rear contact is left sliding along its
#: heading at a constant velocity for the rest of the run: the authors' published code).
PLATE_STOPS = ("impulse", "resolve", "keep_speeds")
#: Heading at the kick start: ``fixed`` (heading N.x, perpendicular to the plate's
#: motion, whatever the settle time; the settle is display only) or ``settled``
#: (the steady motion starts at heading N.x at -settle, as before).
KICK_HEADINGS = ("fixed", "settled")
#: Sign of the camber the Magic Formula is fed: ``physical`` (a leaning wheel is
#: pushed toward the lean) or ``reversed`` (away from it: the authors' published code).
CAMBER_SIGNS = ("physical", "reversed")
#: The model the LQR rider is designed on.
LQR_MODELS = ("whipple", "simulated")
#: The rider's body: lumped into the rear frame, or an upper body leaning on the saddle.
RIDER_BODIES = ("rigid", "leaning")
#: The arms: no mechanical effect on the bar, or forearms turning with it and a spring-damper about the steer axis.
ARMS = ("off", "on")
#: State at the start of the run: ``steady`` (the solved steady motion) or
#: ``upright`` (upright straight running, not an equilibrium with measured tyres:
#: the authors' published code).
STARTS = ("steady", "upright")
#: The longest run [s] after the kick start (``duration``).
MAX_DURATION = 120.0
#: Pitch of an upright start: ``compressed`` (solved with the tyres' compressions: the
#: front contact on the ground) or ``uncompressed`` (solved with both tyres uncompressed,
#: the compressions set after: the front contact starts below the ground; the authors' published code).
START_PITCHES = ("compressed", "uncompressed")

_REFLEX_GAINS = ("reflex_roll", "reflex_roll_rate", "reflex_steer", "reflex_steer_rate")


@dataclass(frozen=True)
class Mechanism:
    """A mechanism of a run that reads some fields (:attr:`Setting.mechanisms <whipple_kick.simulate.settings.Setting>`).

    ``title`` and ``condition`` are words for the refusal message; ``active(scenario)`` says whether the
    scenario uses it.
    """

    title: str
    condition: str
    active: object


#: The mechanisms the fields name (besides the declared parts, each its own mechanism), in the order a refusal
#: looks for them. :meth:`Scenario.validate` refuses a field given other than its default while a
#: mechanism that reads it is off (:meth:`Scenario.unused_fields`): refused rather than warned, because a
#: warning is lost among a sweep's cases and the run's scenario.toml would still record a value that did nothing.
MECHANISMS = {
    "carcass": Mechanism("the carcass tyre", "tyre_transient 'carcass'", lambda s: s.tyre_transient == "carcass"),
    # "off" is no rider torque at all: neither the voluntary law nor the reflex steers.
    "steer_control": Mechanism("the rider's steer control",
                               "controller 'lqr' or 'thesis'; controller 'off' applies no rider torque",
                               lambda s: s.controller != "off"),
    "reflex": Mechanism("the reflex", "a reflex gain other than 0",
                        lambda s: any(getattr(s, g) != 0.0 for g in _REFLEX_GAINS)),
    "lqr": Mechanism("the LQR rider", "controller 'lqr'", lambda s: s.controller == "lqr"),
    "lqr_simulated": Mechanism("the LQR rider designed on the model simulated",
                               "controller 'lqr', lqr_model 'simulated'",
                               lambda s: s.controller == "lqr" and s.lqr_model == "simulated"),
    "thesis_rider": Mechanism("the thesis' Table 8.4 rider", "controller 'thesis'", lambda s: s.controller == "thesis"),
    # The integration applies the plate stop's speed change only where the plate stops instantly.
    "plate_stop": Mechanism("the instant plate stop", "kick_profile 'constant' and piecewise",
                            lambda s: s.kick_profile == "constant" and s.piecewise),
    "steady_start": Mechanism("the steady start", "start 'steady'", lambda s: s.start == "steady"),
    "upright_start": Mechanism("the upright start", "start 'upright'", lambda s: s.start == "upright"),
}


def _mechanism(key):
    """The :class:`Mechanism` called ``key``: one of :data:`MECHANISMS`, or a declared part (read while selected)."""
    if key in MECHANISMS:
        return MECHANISMS[key]
    part = parts.REGISTRY[key]
    return Mechanism(part.title or part.name, f"{part.selected_by[0]} {part.selected_by[1]!r}", part.selected)


def mechanism_fields(cls):
    """``(mechanism, when it is in use (words), when it is in use (test), fields)`` of ``cls``'s declarations.

    The mechanisms of :data:`MECHANISMS` (the carcass tyre first), with each declared part's after the carcass
    tyre, as :data:`MECHANISM_FIELDS` is for :class:`Scenario`.
    """
    declared = {}
    for s in _settings.settings(cls).values():
        for key in s.mechanisms:
            declared.setdefault(key, []).append(s.name)
    keys = list(MECHANISMS)
    keys[1:1] = [k for k in declared if k not in MECHANISMS]   # the parts, after the carcass tyre
    out = []
    for key in keys:
        if key in declared:
            m = _mechanism(key)
            out.append((m.title, m.condition, m.active, tuple(declared[key])))
    return tuple(out)


_BICYCLE_AND_RIDER, _TYRES, _BODY, _RIDING = "bicycle and rider", "tyres", "rider's body", "riding and control"
_KICK, _RUN = "kick", "run and output"


#: Types whose values :func:`dataclasses.asdict` copies as themselves (immutable scalars).
_ATOMS = frozenset((str, float, int, bool, type(None)))


@functools.cache
def _field_names(cls):
    """The names of dataclass ``cls``' fields, in order (what :func:`dataclasses.asdict` walks)."""
    return tuple(f.name for f in fields(cls))


@_settings.documented
@dataclass(frozen=True)
class Scenario:
    """One kick-plate run; the defaults are the project's choices, not all the thesis' (:meth:`thesis` has its).

    Units are SI except pressures [kPa]. ``None`` means "the default rule"
    described per field. Each field is declared once, below, with
    :func:`~whipple_kick.simulate.settings.setting`; its entry here comes
    from that declaration.

    Notes
    -----
    The fields fall in four groups (:data:`FIELD_GROUPS`; :attr:`physics`,
    :attr:`run`, :attr:`numerics`, :attr:`compatibility` give each as a
    dict): the **physics** of the bicycle, rider, tyres, control and kick;
    the **run** (how long, how densely sampled, when it counts as lost);
    the **numerics** (tolerances and integration choices that must not
    change the answer beyond their stated accuracy); and the
    **compatibility** switches that reproduce another model's assumptions
    (the thesis' or its authors' code's: plate stop, heading at the kick,
    camber sign, start, start pitch, slip speed), each at the project's own
    choice by default. Construction stays flat: ``Scenario(speed=4.0,
    rtol=1e-12, camber_sign="reversed")``. Each step of the assembly
    (:mod:`whipple_kick.simulate.assembly`) reads its own frozen view:
    :attr:`bicycle_spec`, :attr:`tyre_spec`, :attr:`body_spec`,
    :attr:`gains_spec`, :attr:`model_spec`, :attr:`design_spec`.
    """

    bicycle: str = setting(
        "balanceassist_v1",
        "Bicycle parameter set (:func:`whipple_kick.library.bicycles.available`) or a path. A set without rider "
        "gets the Yeadon rider seated; a preset with the rider included is used as it is (then ``fz_n`` and "
        "``rider_mass_kg`` must be None).",
        views=("bicycle", "gains"), commands=EVERY_COMMAND, section=_BICYCLE_AND_RIDER, metavar="NAME",
        help="bicycle parameter set or .toml path (default {default}; presets with the rider included: "
             "balanceassist_635N, balanceassist_701N, browser_with_rider), or a BicycleParameters bicycle folder "
             "(<data>/bicycles/<Name>) or <Name>Benchmark.txt")
    fz_n: float | None = setting(
        None,
        f"Static rear-tyre load [N] the rider's mass is chosen for; at most one of it and ``rider_mass_kg``. "
        f"Default {thesis.REFERENCE_LOAD_N:g} N for a bicycle without rider.",
        unit="N", low=0.0, low_open=True, label="rear-tyre load fz", none_means=thesis.REFERENCE_LOAD_N,
        views=("bicycle", "gains"), commands=CASE_COMMANDS, section=_BICYCLE_AND_RIDER, flag="--fz", metavar="N",
        exclusive="who", help="static rear-tyre load in N that the rider's mass is chosen for (default {none_means})")
    rider_mass_kg: float | None = setting(
        None, "The rider's mass [kg]; at most one of it and ``fz_n``.",
        unit="kg", views=("bicycle", "gains"), commands=CASE_COMMANDS, section=_BICYCLE_AND_RIDER,
        flag="--rider-mass", metavar="KG", exclusive="who", help="rider mass in kg")
    rear_load_share: float | None = setting(
        None,
        "Fraction of the bicycle-rider's static weight on the rear tyre [1], in (0, 1). None (default): the "
        "rider sits in the seated posture and the share follows. Given: with ``fz_n`` (default "
        f"{thesis.REFERENCE_LOAD_N:g} N) the weight is ``fz_n / rear_load_share``, which fixes the rider's mass; "
        "with ``rider_mass_kg`` the rear load follows; either way the whole rider is moved fore-aft along the "
        "bicycle's x axis (posture kept, at most 0.15 m) so that the static loads hold "
        "(:func:`whipple_kick.library.riders.for_load_share`).",
        unit="(unit 1)", low=0.0, high=1.0, low_open=True, high_open=True, label="rear load share",
        views=("bicycle",), commands=CASE_COMMANDS, section=_BICYCLE_AND_RIDER, flag="--rear-share",
        metavar="FRACTION",
        help="share of the static weight on the rear tyre, in (0, 1): the rider is moved fore-aft (at most 0.15 m, "
             "posture kept) so that it holds, with --fz's load (its mass follows) or --rider-mass (default: the "
             "seated posture's share)")
    rider: str = setting(
        "jason",
        "Yeadon rider file seated on a bicycle-only set, or ``\"none\"`` (:data:`whipple_kick.library.riders.NO_RIDER`): "
        "the bicycle's parameters include its rider (a BicycleParameters ``Benchmark.txt`` whose rear frame holds "
        "the rider, as the Meijaard benchmark's mB = 85 kg: BicycleParameters cannot say so), so no rider is "
        "seated and the bicycle runs as it is, with its own load share; ``fz_n``, ``rider_mass_kg`` and "
        "``rear_load_share`` must then be None. A bicycle-only set with ``\"none\"`` is refused.",
        views=("bicycle", "gains"), commands=EVERY_COMMAND, section=_BICYCLE_AND_RIDER, metavar="NAME",
        help="Yeadon rider seated on a bicycle-only set (default {default}; available: {riders}), or none: the "
             "bicycle's parameters include its rider (a BicycleParameters Benchmark.txt whose rear frame holds the "
             "rider, as the Meijaard benchmark's mB = 85 kg), which then runs as it is, with its own load share "
             "(no --fz, --rider-mass or --rear-share)")
    tyre: str = setting(
        "T03", "Tyre on both wheels (default T03, the kick-plate bicycle's tyre).",
        views=("tyre",), commands=EVERY_COMMAND, section=_TYRES, metavar="NAME",
        help="tyre on both wheels (default {default}; available: {tyres})")
    pressure_kpa: float = setting(
        thesis.REFERENCE_PRESSURE_KPA,
        "Inflation pressure of both tyres [kPa], unless overridden per wheel by ``pressure_front_kpa`` / "
        "``pressure_rear_kpa``.",
        unit="kPa", low=0.0, low_open=True, label="pressure", views=("tyre",), commands=CASE_COMMANDS,
        section=_TYRES, flag="--pressure", metavar="KPA",
        help="inflation pressure of both tyres in kPa (default {default})")
    pressure_front_kpa: float | None = setting(
        None, "Front tyre pressure [kPa] (default: ``pressure_kpa``).",
        unit="kPa", low=0.0, low_open=True, label="front pressure", views=("tyre",), commands=CASE_COMMANDS,
        section=_TYRES, flag="--pressure-front", metavar="KPA",
        help="front tyre pressure in kPa (with --pressure-rear, instead of --pressure)")
    pressure_rear_kpa: float | None = setting(
        None, "Rear tyre pressure [kPa] (default: ``pressure_kpa``).",
        unit="kPa", low=0.0, low_open=True, label="rear pressure", views=("tyre",), commands=CASE_COMMANDS,
        section=_TYRES, flag="--pressure-rear", metavar="KPA",
        help="rear tyre pressure in kPa (with --pressure-front, instead of --pressure)")
    coefficient_set: str = setting(
        "table7_9",
        "Magic-Formula coefficient set (``\"table7_9\"`` or, T03 only, ``\"chapter8\"``, the fit the thesis' "
        "Chapter 8 code used).",
        views=("tyre",), commands=EVERY_COMMAND, section=_TYRES, metavar="SET",
        help="Magic-Formula coefficients: table7_9 (default, thesis Table 7.9) or chapter8 (T03 only: the fit the "
             "thesis' Chapter 8 code used)")
    friction: str = setting(
        "none", "Friction mode of both tyres (:data:`whipple_kick.library.tyres.FRICTION_MODES`).",
        choices=tyres.FRICTION_MODES, check_choices=False, views=("tyre",), commands=EVERY_COMMAND, section=_TYRES,
        help="friction correction rig -> plate: none (default), plate (peak x 1.30), thesis (whole curves x 1.32, "
             "as the thesis' code)")
    symmetric_tyres: bool = setting(
        False, "Zero the tyres' zero-slip offsets, so the steady motion is exactly upright.",
        views=("model",), commands=("simulate", "validate"), section=_TYRES,
        help="zero the tyres' zero-slip offsets (exactly upright steady running)")
    speed: float = setting(
        3.0, "Forward speed [m/s] of the steady motion before the kick.",
        unit="m/s", low=0.0, high=15.0, low_open=True, views=("gains", "design"), commands=SIMULATE,
        section=_RIDING, metavar="M/S", help="forward speed in m/s (default {default})")
    controller: str = setting(
        "lqr",
        f"LQR designed on the linearised classic model at ``design_speed``; the thesis' Table 8.4 gains (for "
        f"{thesis.loads_text('/')} N); or no steer torque.",
        choices=CONTROLLERS, views=("gains",), commands=EVERY_COMMAND, section=_RIDING,
        help=f"lqr: designed on the linearised classic model (default); thesis: Table 8.4 gains "
             f"({thesis.loads_text()} N only); off: no steer torque")
    design_speed: float | None = setting(
        None,
        "LQR design speed [m/s]. Default None: the run's ``speed``, as a real rider adapts to the speed. Give "
        "3.0 to fix the rider as the thesis did. Used by ``controller=\"lqr\"`` only (Table 8.4's gains were "
        "designed at 3 m/s).",
        unit="m/s", low=0.0, high=15.0, low_open=True, label="design speed", mechanisms=("lqr",),
        views=("gains", "design"), commands=EVERY_COMMAND, section=_RIDING, metavar="M/S",
        help=f"LQR design speed in m/s (default: {{design_default}}, as a real rider adapts; the thesis fixed it at "
             f"{THESIS_DESIGN_SPEED:g})")
    gain_scale: float = setting(
        1.0, "Multiplies every controller gain (thesis Figure 8.7: 0.5).",
        unit="(factor)", low=0.0, high=10.0, mechanisms=("steer_control",), views=("gains", "design"),
        commands=EVERY_COMMAND, section=_RIDING, metavar="FACTOR",
        help="multiply every controller gain (default {default}; the thesis also ran 0.5)")
    thesis_load_n: float | None = setting(
        None,
        "Rear load [N] whose Table 8.4 gains ``controller=\"thesis\"`` uses; default ``fz_n``, or for a preset "
        "that already includes the rider the load it is labelled with (``balanceassist_635N``: 635 N).",
        unit="N", mechanisms=("thesis_rider",), views=("gains",), commands=CASE_COMMANDS, section=_RIDING,
        flag="--thesis-load", metavar="N",
        help=f"rear load in N whose Table 8.4 gains --controller thesis uses ({thesis.loads_text(last=' or ')}; "
             f"default --fz, or the load a preset with rider is labelled with)")
    low_inertia: bool = setting(
        False,
        "Halve the rear frame's IBxx, IByy, IBzz, IBxz and mass-centre height zB (thesis Figure 8.9). The LQR "
        "is still designed on the unmodified bicycle (the rider's controller does not change, the plant does).",
        views=("bicycle",), commands=EVERY_COMMAND, section=_BICYCLE_AND_RIDER,
        help="halve the rear frame's inertias and mass-centre height (thesis Figure 8.9)")
    kick_displacement: float = setting(
        inputs.DEFAULT_DISPLACEMENT,
        "Plate travel [m] (>= 0; direction by ``kick_direction``). With a table the travel comes from the "
        "table: leave it at its default.",
        unit="m", commands=SIMULATE, section=_KICK, metavar="M", help="plate travel in m (default {default:.3f})")
    kick_duration: float | None = setting(
        None,
        f"Plate travel time [s]; at most one of it and ``kick_accel``. Default {inputs.DEFAULT_DURATION:.3f} s "
        "(13.3 m/s^2 for the thesis' 0.150 m). Not with a table.",
        unit="s", none_means=inputs.DEFAULT_DURATION, commands=SIMULATE, section=_KICK, metavar="S",
        exclusive="how", help="plate travel time in s (default {none_means:.3f})")
    kick_accel: float | None = setting(
        None, "Peak plate acceleration [m/s^2]; at most one of it and ``kick_duration``. Not with a table.",
        unit="m/s^2", commands=SIMULATE, section=_KICK, metavar="M/S2", exclusive="how",
        help="peak plate acceleration in m/s^2 (sets the duration)")
    kick_profile: str = setting(
        "constant",
        "Constant acceleration (thesis), minimum-jerk quintic (finite jerk), or the plate displacement "
        "tabulated in ``kick_table``.",
        choices=inputs.PROFILES, check_choices=False, commands=SIMULATE, section=_KICK,
        help="constant acceleration (default, thesis), smooth (minimum jerk) or table (plate displacement from "
             "--kick-table)")
    kick_table: str | None = setting(
        None,
        "CSV of the plate's lateral displacement (``kick_profile=\"table\"`` only; see "
        ":func:`whipple_kick.library.inputs.load_kick_table`): columns ``time`` [s, from the kick start, the "
        "trajectory's clock] and ``y`` [m, + to the right]. The plate follows the clamped cubic spline through "
        "the rows (:func:`whipple_kick.library.inputs.cubic_segments`), rests at the first row's y before the "
        "first time and at the last row's y after the last; the table must lie within [-settle, duration].",
        commands=SIMULATE, section=_KICK, metavar="FILE",
        help="CSV of the plate's displacement, columns time (from the kick start) and y (+ right), units in the "
             "header: 'time [s]' or 'time [ms]', 'y [m]' or 'y [mm]' (none: s, m); a header-less file is read as "
             "two columns time [s], y [m]. The plate follows the clamped cubic spline through the rows (implies "
             "--kick-profile table; not with --kick-accel/--kick-duration/--kick-displacement)")
    kick_direction: str = setting(
        "right", "Plate moves to the bicycle's right (+y) or left; ``left`` mirrors a table's y.",
        choices=inputs.DIRECTIONS, check_choices=False, commands=SIMULATE, section=_KICK,
        help="direction the plate moves (default {default})")
    settle: float = setting(
        0.5, "Steady running shown before the kick [s].",
        unit="s", low=0.0, high=60.0, label="settle time", group="run", commands=SIMULATE, section=_RUN,
        metavar="S", help="steady running shown before the kick in s (default {default})")
    duration: float = setting(
        6.0, "Simulated time after the kick starts [s].",
        unit="s", low=0.0, high=MAX_DURATION, low_open=True, group="run", commands=SIMULATE, section=_RUN,
        metavar="S", help=f"simulated time after the kick start in s (default {{default}}, at most {MAX_DURATION:g})")
    rtol: float = setting(
        1e-10, "LSODA relative tolerance (thesis 1e-12).",
        unit="(relative)", low=1e-14, high=1e-3, group="numerics", commands=SIMULATE, section=_RUN,
        metavar="RTOL", help="LSODA relative tolerance (default {default}; the thesis used 1e-12)")
    output_rate: float = setting(
        1000.0, "Samples per second of the trajectory [Hz].",
        unit="Hz", low=1.0, high=1e5, group="run", commands=SIMULATE, section=_RUN, metavar="HZ",
        help="samples per second of the run in Hz (default {default}: about 1 MB of trajectory.csv per simulated "
             "second); the metrics are computed from these samples, e.g. the recovery time to 1/HZ")
    fall_angle_deg: float = setting(
        45.0, "``|roll|`` [deg] that counts as a fall and ends the run.",
        unit="deg", low=0.0, high=90.0, low_open=True, high_open=True, label="fall angle", group="run")
    steer_limit_deg: float | None = setting(
        90.0,
        "``|steer|`` [deg] that also ends the run as lost (``fall_reason`` \"steer\"): past 90 deg the front wheel "
        "rolls backwards, which the tyre model (forward rolling, pneumatic trail behind the contact) does not "
        "describe, and no rider recovers from a fork turned over. Without steer control the fork turns over "
        "before the roll reaches 45 deg. None: no steer limit (a fork past 90 deg spins on, so 180 is not the "
        "same as no limit).",
        unit="deg", low=0.0, high=180.0, low_open=True, label="steer limit", group="run")
    piecewise: bool = setting(
        True,
        "Restart the integrator at the kick's start and end (default). False integrates from -settle across "
        "the kick and the plate stop in one LSODA run, without the plate stop's impulse (for comparison only; "
        "not with a table, whose every interval is its own parameter set).",
        group="numerics")
    tyre_transient: str = setting(
        transient.DEFAULT_TRANSIENT,
        "How the tyre forces build up (:mod:`whipple_kick.model.transient`, each form as declared there): "
        + "; ".join(f"{name}{' (default)' * (name == transient.DEFAULT_TRANSIENT)}: {form.description}"
                    for name, form in transient.FORMS.items()) + ".",
        choices=TYRE_TRANSIENTS, label="tyre transient", views=("model", "design"), commands=EVERY_COMMAND,
        section=_TYRES,
        help="how the tyre forces build up: " + "; ".join(
            f"{name}{' (default)' * (name == transient.DEFAULT_TRANSIENT)}: {form.description}"
            for name, form in transient.FORMS.items()))
    carcass_sliding: str = setting(
        carcass.DEFAULT_SLIDING,
        "The carcass tyre's friction limit once the patch slides past the curve's peak: the peak itself "
        "(default, a Coulomb plateau that uses nothing of the fit past the peak) or the steady curve at the "
        "wheel's kinematic slip (steady sliding follows the fit's falling branch). Carcass transient only.",
        choices=carcass.SLIDING_LAWS, label="carcass sliding law", mechanisms=("carcass",), views=("model", "design"),
        commands=EVERY_COMMAND, section=_TYRES,
        help="carcass tyre past the curve's peak: peak (default: the force stays at the peak) or curve (it follows "
             "the steady curve at the kinematic slip: the fit's falling branch)")
    carcass_damping: float = setting(
        0.0,
        "Lateral damping of each carcass [N s/m], parallel to its stiffness (default 0: the thesis' pure "
        "relaxation). Carcass transient only.",
        unit="N s/m", low=0.0, high=1e4, mechanisms=("carcass",), views=("model", "design"), commands=EVERY_COMMAND,
        section=_TYRES, metavar="N_S_PER_M",
        help="lateral damping of each carcass, parallel to its stiffness (default {default}: pure relaxation)")
    carcass_viscosity: float = setting(
        carcass.SLIDING_VISCOSITY,
        "Numerics: the sliding viscosity [N s/m] that regularises an undamped carcass' friction limit (a patch "
        "past the limit slides faster by the excess force over it; "
        ":data:`whipple_kick.model.carcass.SLIDING_VISCOSITY`). Smaller is closer to the Coulomb plateau and "
        "stiffer (at least 1e-3 N s/m: below, LSODA stalls, measured at 5e-4 at the plate stop); "
        "docs/validation.md shows the results converged.",
        unit="N s/m", low=1e-3, high=10.0, label="carcass sliding viscosity", group="numerics",
        mechanisms=("carcass",), views=("model", "design"))
    carcass_stiffness_scale: float = setting(
        1.0,
        "Factor on both carcass stiffnesses C_Fa(F_z0)/sigma0 (default 1; the identification of the rider's "
        "body varies it, scripts/identify_rider.py). Carcass transient only.",
        unit="(factor)", low=0.05, high=20.0, mechanisms=("carcass",), views=("model", "design"),
        commands=EVERY_COMMAND, section=_TYRES, metavar="FACTOR",
        help="factor on both carcass stiffnesses C_Fa/sigma0, in [0.05, 20] (default {default})")
    lqr_model: str = setting(
        "whipple",
        "The model the LQR rider (``controller=\"lqr\"``) is designed on: the linearised Carvallo-Whipple model "
        "(default; full state, roll and steer), or the model the run simulates (tyres, body, arms, reflex), "
        "linearised about upright straight running at the design speed, with the law feeding back what the "
        "rider feels (roll, steer, their rates, and the upper body's lean and its rate when it leans), its gains "
        "LQR-optimal for that law (:func:`whipple_kick.simulate.control.output_feedback_lqr`).",
        choices=LQR_MODELS, label="LQR design model", mechanisms=("lqr",), commands=EVERY_COMMAND, section=_RIDING,
        help="what the LQR rider is designed on: whipple (default: the classic model, full state) or simulated "
             "(the model the run simulates, feeding back roll, steer, their rates and the upper body's lean)")
    lqr_heading: bool = setting(
        False,
        "With ``lqr_model=\"simulated\"``: the law also feeds back the heading (yaw angle q3, gain kq3), so the "
        "rider steers back to the heading held before the kick. Needs straight steady running "
        "(``symmetric_tyres``).",
        mechanisms=("lqr_simulated",), views=("design",), commands=EVERY_COMMAND, section=_RIDING,
        help="with --lqr-model simulated: the rider also holds the heading held before the kick (needs "
             "--symmetric-tyres: straight steady running)")
    rider_body: str = setting(
        "rigid",
        "The rider lumped rigidly into the rear frame (default), or an upper body (pelvis, trunk, head, upper "
        "arms) leaning on the saddle on the hip spring-damper (:func:`whipple_kick.library.riders.split_rider`; "
        "the trunk part, :data:`whipple_kick.model.parts.TRUNK`).",
        choices=RIDER_BODIES, label="rider body", views=("bicycle", "body", "design"), commands=EVERY_COMMAND,
        section=_BODY,
        help="rigid (default: the rider lumped into the rear frame) or leaning (the upper body leans on the saddle "
             "on the hip spring-damper)")
    hip_stiffness: float = part_setting("trunk", "hip_stiffness")
    hip_damping: float = part_setting("trunk", "hip_damping")
    arms: str = setting(
        "off",
        "\"on\": the forearms and hands turn with the bar and the arms are a spring-damper about the steer axis "
        "between the bar and the upper body (the rear frame with a rigid rider). \"off\" (default): the hands "
        "have no mechanical effect on the bar.",
        choices=ARMS, label="arms", views=("bicycle", "body"), commands=EVERY_COMMAND, section=_BODY,
        help="on: the forearms turn with the bar and the arms are a spring-damper about the steer axis; off "
             "(default): no mechanical effect on the bar")
    arm_stiffness: float = part_setting("arms", "arm_stiffness")
    arm_damping: float = part_setting("arms", "arm_damping")
    reflex_delay: float = setting(
        0.0, "Delay of the rider's reflex [s], a (3,4) Pade filter (:mod:`whipple_kick.model.reflex`); 0 none.",
        unit="s", low=0.0, high=0.5, label="reflex delay", mechanisms=("steer_control", "reflex"), views=("body",),
        commands=EVERY_COMMAND, section=_BODY, metavar="S",
        help="delay of the rider's reflex steer torque (a Pade filter; at most 0.5 s) in s (default {default})")
    reflex_roll: float = setting(
        0.0,
        "Reflex steer-torque gain on roll [N m/rad], ``T = -(g x)`` delayed; separate from the voluntary law "
        "(the controller). Default 0.",
        unit="N m/rad", low=-1e4, high=1e4, label="reflex roll gain", mechanisms=("steer_control",),
        views=("body",), commands=EVERY_COMMAND, section=_BODY,
        help="reflex steer-torque gain on roll, T = -gain x roll (a positive gain steers against the roll) in "
             "N m/rad (default {default})")
    reflex_roll_rate: float = setting(
        0.0, "Reflex steer-torque gain on roll rate [N m s/rad] (as ``reflex_roll``).",
        unit="N m s/rad", low=-1e4, high=1e4, label="reflex roll-rate gain", mechanisms=("steer_control",),
        views=("body",), commands=EVERY_COMMAND, section=_BODY,
        help="reflex steer-torque gain on roll rate in N m s/rad (default {default})")
    reflex_steer: float = setting(
        0.0, "Reflex steer-torque gain on steer [N m/rad] (as ``reflex_roll``).",
        unit="N m/rad", low=-1e4, high=1e4, label="reflex steer gain", mechanisms=("steer_control",),
        views=("body",), commands=EVERY_COMMAND, section=_BODY,
        help="reflex steer-torque gain on steer in N m/rad (default {default})")
    reflex_steer_rate: float = setting(
        0.0, "Reflex steer-torque gain on steer rate [N m s/rad] (as ``reflex_roll``).",
        unit="N m s/rad", low=-1e4, high=1e4, label="reflex steer-rate gain", mechanisms=("steer_control",),
        views=("body",), commands=EVERY_COMMAND, section=_BODY,
        help="reflex steer-torque gain on steer rate in N m s/rad (default {default})")
    plate_stop: str = setting(
        "impulse",
        "Speeds across the constant-acceleration profile's instant plate stop: the rear no-slip constraint's "
        "impulse (default), a re-solve of the dependent speeds only (the earlier model, which removes energy no "
        "force accounts for), or no jump with the rear contact left sliding (``keep_speeds``, the authors' "
        "code). The other profiles stop the plate smoothly.",
        choices=PLATE_STOPS, label="plate stop", group="compatibility", mechanisms=("plate_stop",),
        commands=SIMULATE, section=_KICK,
        help="speeds across the constant profile's instant plate stop: impulse (default: the rear no-slip "
             "constraint's impulse), resolve (dependent speeds only, the earlier model) or keep_speeds (no jump; "
             "the rear contact is left sliding along its heading, as the authors' published code)")
    kick_heading: str = setting(
        "fixed",
        "``fixed`` (default): the post-kick run starts from the exact steady motion with heading N.x "
        "(perpendicular to the plate's motion) and the rear contact at the origin, whatever ``settle``; the "
        "settle is integrated separately and is display only. ``settled``: the steady motion starts so at "
        "-settle (the earlier model: with a steady turn the heading at the kick then depends on ``settle``).",
        choices=KICK_HEADINGS, label="kick heading", group="compatibility", mechanisms=("steady_start",),
        commands=SIMULATE, section=_KICK,
        help="fixed (default): heading perpendicular to the plate at the kick start, whatever --settle; settled: "
             "the steady motion starts so at -settle (the earlier model)")
    camber_sign: str = setting(
        "physical",
        "Sign of the camber fed to the Magic Formula. ``physical`` (default): a leaning wheel is pushed toward "
        "the lean, as measured. ``reversed``: away from it, as in the thesis authors' published code (the "
        "curves evaluated at the opposite camber: :func:`whipple_kick.model.magic_formula.camber_reversed`). "
        "Not physical; it exists to explain that code's runs.",
        choices=CAMBER_SIGNS, label="camber sign", group="compatibility", views=("model",), commands=EVERY_COMMAND,
        section=_TYRES,
        help="physical (default: a leaning wheel is pushed toward the lean) or reversed (away from it, as the "
             "thesis authors' published code; not physical)")
    start: str = setting(
        "steady",
        "``steady`` (default): the run starts from the solved steady motion. ``upright``: from upright straight "
        "running with the tyre states at their zero-slip values and no rear-wheel torque "
        "(:func:`whipple_kick.simulate.steady.upright_state`), as the authors' code starts; with measured tyres "
        "this is not an equilibrium (their offsets act from t = 0). Needs ``settle = 0`` (the kick starts the "
        "run).",
        choices=STARTS, label="start", group="compatibility", commands=SIMULATE, section=_RUN,
        help="steady (default: the solved steady motion) or upright (upright straight running, not an equilibrium "
             "with measured tyres, as the authors' code; needs --settle 0)")
    start_pitch: str = setting(
        "compressed",
        "Pitch of the upright start. ``compressed`` (default): solved with the tyres' compressions, so the front "
        "contact is on the ground. ``uncompressed``: solved with both tyres uncompressed and the compressions "
        "set after (vertical equilibrium at that pitch), as the authors' code starts: the front contact then "
        "starts below the ground by about the rear compression less the front one (3.2 mm at 500 kPa with "
        "``balanceassist_635N``) and stays so (only the constraint's rate is imposed). Needs "
        "``start = \"upright\"``.",
        choices=START_PITCHES, label="start pitch", group="compatibility", mechanisms=("upright_start",),
        commands=SIMULATE, section=_RUN,
        help="pitch of the upright start: compressed (default: solved with the tyres' compressions, the front "
             "contact on the ground) or uncompressed (solved without them, as the authors' code: the front contact "
             "starts a few mm below the ground); needs --start upright")
    slip_speed: str = setting(
        "wheel_centre",
        "Whose forward speed along the wheel's heading the tyres' slip angle ``atan(v_sy / |v_x|)`` and "
        "relaxation ``sigma / |v_x|`` use: the wheel centre's (default) or the geometric contact point's, as the "
        "authors' code takes it. They differ while the wheel's centre moves relative to its contact (rolling, "
        "pitching, steering); the trajectory's ``rolling_speed_*`` columns are the speed in use.",
        choices=SLIP_SPEEDS, label="slip speed", group="compatibility", views=("model", "design"),
        commands=EVERY_COMMAND, section=_TYRES,
        help="whose forward speed the tyres' slip angle and relaxation use: wheel_centre (default) or "
             "contact_point (as the thesis authors' published code)")

    @classmethod
    def thesis(cls, pressure_kpa=thesis.REFERENCE_PRESSURE_KPA, **changes):
        """The Chapter 8 runs as the authors' code made them.

        Bicycle+rider preset ``balanceassist_635N``, the Table 8.4 gains of
        the preset's load (635 N; ``bicycle="balanceassist_701N"`` gets the
        701 N column, ``thesis_load_n`` another row), T03 with the
        ``chapter8`` coefficients and the ``thesis`` friction mode, the
        thesis' lagged-force tyre transient (``tyre_transient="force_lag"``),
        LSODA rtol 1e-12. The plate stop and the heading at the kick are the
        project's (impulse, fixed). ``changes`` override any field.

        Example
        -------
        >>> import whipple_kick as wk
        >>> sc = Scenario.thesis(bicycle="balanceassist_701N")
        >>> wk.assembly.thesis_load(sc.gains_spec), wk.assembly.thesis_gains_warning(sc.gains_spec) is None
        (701.0, True)
        """
        base = dict(bicycle="balanceassist_635N", controller="thesis",
                    coefficient_set="chapter8", friction="thesis", rtol=1e-12,
                    pressure_kpa=pressure_kpa, tyre_transient="force_lag")
        base.update(changes)
        return cls(**base)

    @classmethod
    def authors_code(cls, pressure_kpa=500.0, **changes):
        """The thesis authors' published code (bicycle-kickplate-model, ``base_simulation.py``), reproduced.

        For explaining that code's runs, not for predictions: it feeds the
        camber to the Magic Formula with the opposite sign (camber thrust
        away from the lean), starts from upright running that is not an
        equilibrium, and leaves the rear contact sliding after the plate
        stops. :meth:`thesis` with ``camber_sign="reversed"``,
        ``start="upright"``, ``settle=0`` (the kick at t = 0),
        ``plate_stop="keep_speeds"``, ``start_pitch="uncompressed"`` (the
        front contact starts below the ground) and
        ``slip_speed="contact_point"``; their standard run is at 500 kPa.
        Each of these can be switched back alone through ``changes``
        (``start="steady"`` also switches the start pitch back, which only an
        upright start has). docs/validation.md ("The authors' published
        code") compares it with that code's stored runs.

        Example
        -------
        >>> Scenario.authors_code().camber_sign, Scenario.authors_code(start="steady", settle=0.5).start
        ('reversed', 'steady')
        >>> Scenario.authors_code(slip_speed="wheel_centre").start_pitch
        'uncompressed'
        """
        upright = changes.get("start", "upright") == "upright"
        base = dict(camber_sign="reversed", start="upright", settle=0.0, plate_stop="keep_speeds",
                    start_pitch="uncompressed" if upright else "compressed", slip_speed="contact_point")
        base.update(changes)
        return cls.thesis(pressure_kpa, **base)

    # ------------------------------------------------------------ derived values

    @property
    def physics(self) -> dict:
        """The physics fields (:data:`FIELD_GROUPS`) and their values."""
        return self._group("physics")

    @property
    def run(self) -> dict:
        """The run's fields: duration, settle, sampling and when it counts as lost."""
        return self._group("run")

    @property
    def numerics(self) -> dict:
        """The numerical choices: tolerance, piecewise integration, the carcass tyre's regularisation."""
        return self._group("numerics")

    @property
    def compatibility(self) -> dict:
        """The switches that reproduce another model's assumptions (each at the project's choice by default).

        Example
        -------
        >>> Scenario.authors_code().compatibility["camber_sign"], Scenario().compatibility["camber_sign"]
        ('reversed', 'physical')
        """
        return self._group("compatibility")

    def _group(self, name):
        return {field: getattr(self, field) for field in _settings.groups(type(self))[name]}

    @property
    def lqr_design_speed(self) -> float:
        """Speed [m/s] the LQR rider is designed at: ``design_speed``, or the run's speed."""
        return self.speed if self.design_speed is None else self.design_speed

    @property
    def pressures(self) -> tuple[float, float]:
        """(rear, front) pressures [kPa]."""
        rear = self.pressure_kpa if self.pressure_rear_kpa is None else self.pressure_rear_kpa
        front = self.pressure_kpa if self.pressure_front_kpa is None else self.pressure_front_kpa
        return rear, front

    # ------------------------------------------------------------ what each step of the assembly reads

    @property
    def bicycle_spec(self) -> "BicycleSpec":
        """What :func:`~whipple_kick.simulate.assembly.build_bicycle` reads (:class:`BicycleSpec`)."""
        return self.view("bicycle")

    @property
    def tyre_spec(self) -> "TyreSpec":
        """What :func:`~whipple_kick.simulate.assembly.build_tyres` reads (:class:`TyreSpec`).

        Example
        -------
        >>> Scenario(pressure_front_kpa=350.0).tyre_spec
        TyreSpec(tyre='T03', pressures=(400.0, 350.0), coefficient_set='table7_9', friction='none')
        """
        return self.view("tyre")

    @property
    def body_spec(self) -> "BodySpec":
        """What :func:`~whipple_kick.simulate.assembly.rider_body` reads (:class:`BodySpec`)."""
        return self.view("body")

    @property
    def gains_spec(self) -> "GainsSpec":
        """What :func:`~whipple_kick.simulate.assembly.controller_gains` reads (:class:`GainsSpec`)."""
        return self.view("gains")

    @property
    def model_spec(self) -> "ModelSpec":
        """What :func:`~whipple_kick.simulate.assembly.model_parameters` reads (:class:`ModelSpec`)."""
        return self.view("model")

    @property
    def design_spec(self) -> "DesignSpec":
        """What the LQR design on the simulated model reads (:class:`DesignSpec`)."""
        return DesignSpec(speed=float(self.lqr_design_speed), leaning=self.rider_body == "leaning",
                          heading=bool(self.lqr_heading), gain_scale=float(self.gain_scale),
                          model_options=tuple((name, getattr(self, name)) for name in design_model_options(type(self))))

    def view(self, name):
        """The frozen view ``name`` (a key of :data:`VIEWS`): the fields declared with it, as the step reads them."""
        view = view_class(type(self), name)
        return view(**{f.name: getattr(self, f.name) for f in fields(view)})

    def validate(self) -> "Scenario":
        """Check every field; raise :class:`InputError` naming value, range and unit. Returns ``self``.

        Each field against its declared range or choices (in field order), a declared part's field also
        against its refused low end while the scenario selects the part; then the rules between fields; then
        the fields given to a mechanism this scenario does not use (:meth:`unused_fields`); then the kick.
        """
        for s in _settings.settings(type(self)).values():
            value = getattr(self, s.name)
            # With its part selected, a field that refuses its low end is allowed (low, high]: one range in
            # every message (the low end itself is refused with its reason).
            if s.refuse_low and parts.REGISTRY[s.part].selected(self):
                part = parts.REGISTRY[s.part]
                if value == s.low:
                    raise InputError(f"{s.words} = {float(value):g} {s.unit} {s.refuse_low}; allowed "
                                     f"({s.low:g}, {s.high:g}] {s.unit} with {part.title or part.name}")
                check_range(s.words, value, s.low, s.high, s.unit, low_open=True)
            s.check(value)
        if self.lqr_heading and (self.controller != "lqr" or self.lqr_model != "simulated"):
            raise InputError("lqr_heading needs the LQR rider designed on the model simulated "
                             "(controller 'lqr', lqr_model 'simulated')")
        if self.start == "upright" and self.settle != 0.0:
            raise InputError(f"settle time = {self.settle:g} s conflicts with start 'upright' (upright running is "
                             "not a steady motion: the kick starts the run); allowed: 0 s")
        if self.start_pitch == "uncompressed" and self.start != "upright":
            raise InputError(f"start pitch 'uncompressed' conflicts with start {self.start!r} (the steady motion "
                             "solves its pitch with the compressions); allowed: start 'upright'")
        if self.plate_stop == "keep_speeds" and not self.piecewise:
            raise InputError("plate stop 'keep_speeds' needs piecewise = True (the single LSODA run re-solves "
                             "the speeds at the plate stop)")
        if self.controller == "off" and self.gain_scale != 1.0:
            raise InputError(f"gain scale = {self.gain_scale:g} conflicts with controller off "
                             "(there are no gains to scale)")
        if self.fz_n is not None and self.rider_mass_kg is not None:
            raise InputError("give the rear-tyre load fz (N) or the rider mass (kg), not both")
        self._refuse_unused()
        if self.low_inertia and (self.rider_body != "rigid" or self.arms != "off"):
            # Halving the rear frame's zB and inertias with the upper body split off it would lower the whole
            # mass centre far less than for the rigid rider (0.943 -> 0.773 m, not 0.500 m): not Figure 8.9's variant.
            raise InputError(f"low_inertia halves the rear frame with the whole rider lumped into it (thesis Figure "
                             f"8.9); it conflicts with rider_body {self.rider_body!r} / arms {self.arms!r}: allowed "
                             "with rider_body 'rigid' and arms 'off'")
        inputs.kick_of(self)
        return self

    def unused_fields(self) -> dict:
        """Fields given (other than their defaults) that no mechanism of this scenario reads: field -> why.

        From :data:`MECHANISM_FIELDS`; :meth:`validate` refuses each of them
        (a field accepted and then ignored would let a sweep over it return
        identical rows). A field equal to its default is never "given".

        Example
        -------
        >>> Scenario(thesis_load_n=570.0).unused_fields()
        {'thesis_load_n': "the thesis' Table 8.4 rider (controller 'thesis')"}
        """
        unused = {}
        defaults = {name: s.default for name, s in _settings.settings(type(self)).items()}
        for mechanism, condition, active, names in mechanism_fields(type(self)):
            for name in names:
                if name not in unused and getattr(self, name) != defaults[name] and not active(self):
                    unused[name] = f"{mechanism} ({condition})"
        if self.pressure_front_kpa is not None and self.pressure_rear_kpa is not None \
                and self.pressure_kpa != defaults["pressure_kpa"]:
            unused["pressure_kpa"] = "a tyre without its own pressure (pressure_front_kpa and pressure_rear_kpa are both given)"
        return unused

    def _refuse_unused(self):
        for name, why in self.unused_fields().items():
            default = _settings.settings(type(self))[name].default
            raise UnusedFieldError(f"{name} = {_with_unit(name, getattr(self, name))} is read only by {why}, which "
                                   f"this scenario does not use: leave it at its default "
                                   f"{_with_unit(name, default)} (it would be ignored)", field=name, why=why)

    def to_dict(self) -> dict:
        """Fields as a plain dict (JSON-ready)."""
        values = {name: getattr(self, name) for name in _field_names(type(self))}
        # Fields of strings, numbers, booleans and None (as always): asdict's deep copies would be the values.
        if set(map(type, values.values())) <= _ATOMS:
            return values
        return asdict(self)

    def to_file(self, path, *, note=None) -> None:
        """Write the scenario as a TOML file that :meth:`from_file` (and ``simulate --scenario``) reads back.

        Every field is written, ``None`` as the string ``"none"`` (TOML has no
        null). File paths (``kick_table``, a ``bicycle`` given as a path) are
        written absolute, so the file reruns the case from any folder.
        ``note`` adds a comment line (e.g. what the file cannot reproduce).

        Example
        -------
        >>> import pathlib, tempfile
        >>> with tempfile.TemporaryDirectory() as folder:   # removed afterwards
        ...     path = pathlib.Path(folder) / "scenario.toml"
        ...     Scenario(pressure_kpa=300.0, design_speed=3.0).to_file(path)
        ...     Scenario.from_file(path) == Scenario(pressure_kpa=300.0, design_speed=3.0)
        True
        """
        lines = ["# whipple_kick scenario: one kick-plate run. Rerun it with `simulate --scenario FILE` (flags override",
                 "# its values) or wk.run(wk.Scenario.from_file(FILE)). Units: SI, pressures in kPa; \"none\": the",
                 "# field's rule for no value (see help(wk.Scenario)). Paths relative to this file's folder."]
        if note:
            lines.append(f"# NOTE: {note}")
        for name, value in asdict(self).items():
            if value is not None and name in _PATH_FIELDS and _is_path(name, value):
                value = str(pathlib.Path(value).resolve())
            text = ('"none"' if value is None else ("true" if value else "false") if isinstance(value, bool)
                    else repr(float(value)) if isinstance(value, (int, float)) else json.dumps(str(value)))
            lines.append(f"{name} = {text}")
        fileio.write_atomic(path, "\n".join(lines) + "\n")

    @classmethod
    def from_file(cls, path) -> "Scenario":
        """The scenario of a TOML file (as :meth:`to_file` writes it; keys left out keep their defaults), validated.

        Relative paths in it (``kick_table``, a ``bicycle`` path) are taken
        relative to the file's folder.

        Raises
        ------
        InputError
            One line naming the file and the bad key or value: a missing or
            non-TOML file, an unknown key, a value of the wrong type, or a
            value out of range (:meth:`validate`).

        Example
        -------
        >>> sc = Scenario.from_file("kick_run/scenario.toml")    # doctest: +SKIP
        >>> wk.run(sc.with_changes(pressure_kpa=300.0))          # doctest: +SKIP
        """
        file = pathlib.Path(path)
        label = f"scenario file {str(path)!r}"
        try:
            with open(file, "rb") as fh:
                data = tomllib.load(fh)
        except FileNotFoundError:
            raise InputError(f"{label} does not exist") from None
        except IsADirectoryError:
            raise InputError(f"{label} is a folder, not a file") from None
        except OSError as exc:   # no permission, an I/O error: the input cannot be read
            raise InputError(f"{label} cannot be read: {exc.strerror or exc}") from None
        except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
            raise InputError(f"{label} is not valid TOML: {exc}") from None
        types = {f.name: f.type for f in fields(cls)}
        values = {}
        for key, value in data.items():
            if key not in types:
                raise InputError(f"{label}: unknown key {key!r}; known keys: {', '.join(types)}")
            kinds = {types[key], *getattr(types[key], "__args__", ())}   # float | None -> {float, None}
            optional = type(None) in kinds
            if optional and value == "none":
                value = None
            elif float in kinds and isinstance(value, (int, float)) and not isinstance(value, bool) \
                    and math.isfinite(value):
                value = float(value)
            elif not ((bool in kinds and isinstance(value, bool)) or (str in kinds and isinstance(value, str))):
                want = "true or false" if bool in kinds else "a string" if str in kinds else "a finite number"
                raise InputError(f"{label}: {key} = {value!r} is not {want}" + (' (or "none")' if optional else ""))
            elif key in _PATH_FIELDS and _is_path(key, value) and not pathlib.Path(value).is_absolute():
                value = str(file.parent / value)
            values[key] = value
        try:
            return cls(**values).validate()
        except InputError as exc:
            raise InputError(f"{label}: {exc}") from None

    def with_changes(self, **changes) -> "Scenario":
        """A copy with fields changed (not validated: :meth:`validate` does that).

        Example
        -------
        >>> Scenario().with_changes(pressure_kpa=300.0).pressure_kpa
        300.0
        """
        return replace(self, **changes)




def with_parts(*declared, base=None):
    """A Scenario class whose fields select and set the declared parts ``declared`` (:class:`~whipple_kick.model.parts.Part`).

    For each part, the field that selects it (:attr:`~whipple_kick.model.parts.Part.selected_by`: "off" by
    default, or the part's value), unless ``base`` (default :class:`Scenario`) has it, then its fields
    (:func:`~whipple_kick.simulate.settings.part_setting`), all derived from its declaration: validated,
    refused while the part is not selected, held by the body's view (so the run's model has the part; by
    the bicycle's too when it carries some of the rider's segments) and given command-line flags
    (``whipple_kick.cli._simulate_parser(cls)``). The parts must be declared
    (:func:`whipple_kick.model.parts.declare`) before the class is made and while it is used.

    Example
    -------
    ``ShiftScenario = with_parts(SHIFT)``; ``ShiftScenario(shift="on", shift_stiffness=2000.0)``.
    """
    base = Scenario if base is None else base
    have = {f.name for f in fields(base)}
    members = []
    for part in declared:
        if parts.REGISTRY.get(part.name) is not part:
            raise ValueError(f"part {part.name!r} is not the declared one (declare it first: parts.declare)")
        if not part.selected_by:
            raise ValueError(f"part {part.name!r} has no selected_by: no scenario field selects it")
        name, value = part.selected_by
        if name not in have:
            if value == "off":
                raise ValueError(f"part {part.name!r}: the value that selects it may not be 'off' (the default)")
            title = part.title or part.name
            members.append((name, str, setting(
                "off", f'"{value}": {title}, {part.description}; "off" (default): a model without it '
                f"(the part {part.name!r}, :mod:`{part.build.__module__}`).", choices=("off", value),
                label=name.replace("_", " "), commands=EVERY_COMMAND, section=_BODY,
                # The body's view holds it (the run's model has the part); the bicycle's too when the part
                # carries some of the rider's segments (the rider is split for it: riders.split_rider).
                views=("body",) + (("bicycle",) if part.split is not None else ()),
                help=f"{value}: {title}; off (default): without it")))
            have.add(name)
        members += [(f.name, float, part_setting(part.name, f.name)) for f in part.fields if f.name not in have]
        have.update(f.name for f in part.fields)
    names = "".join(p.name.title().replace("_", "") for p in declared)
    return make_dataclass(f"{base.__name__}With{names}", members, bases=(base,), frozen=True, namespace={
        "__doc__": f"{base.__name__} with the fields of the part(s) {', '.join(p.name for p in declared)} "
                   "(:func:`whipple_kick.simulate.scenario.with_parts`).", "__module__": base.__module__})


#: Every field's default, by name.
DEFAULTS = {f.name: f.default for f in fields(Scenario)}

#: The unit of every number field, as a file writes it ("1": a factor, a fraction, a relative tolerance): the
#: uncertainty study checks an input's ``unit`` against it, and the refusals name it. From the declarations.
UNITS = {name: ("1" if s.unit.startswith("(") else s.unit) for name, s in _settings.settings(Scenario).items()
         if s.unit}


def _with_unit(name, value):
    """A field's value as a message writes it: with its unit (:data:`UNITS`) where it is a number."""
    unit = UNITS.get(name)
    if unit is None or isinstance(value, bool) or not isinstance(value, (int, float)):
        return repr(value)
    return f"{value!r} (unit 1)" if unit == "1" else f"{value!r} {unit}"


class UnusedFieldError(InputError):
    """A field given other than its default that no mechanism of the scenario reads (:meth:`Scenario.unused_fields`).

    ``field`` and ``why`` (the mechanism and when it is in use) let a caller name the field as its user gave
    it: the command line names the flag.
    """

    def __init__(self, message, *, field=None, why=None):
        super().__init__(message)
        self.field, self.why = field, why
#: Every field's declaration (:class:`whipple_kick.simulate.settings.Setting`), by name, in field order.
SETTINGS = _settings.settings(Scenario)

#: Fields that may hold a file path (written absolute by :meth:`Scenario.to_file`).
_PATH_FIELDS = ("bicycle", "kick_table")


def _is_path(name, value):
    """Whether the value of field ``name`` is a file path rather than a shipped set's name."""
    text = str(value)
    return name == "kick_table" or text.endswith(".toml") or "/" in text or "\\" in text


#: Which mechanism reads which fields, from the declarations (:func:`mechanism_fields`): (mechanism, when it is
#: in use (words), when it is in use (test), the fields nothing else reads). tests/simulate/test_unused_fields.py
#: walks every field through every mechanism switch.
MECHANISM_FIELDS = mechanism_fields(Scenario)

#: Every field of :class:`Scenario` in exactly one group, from the declarations (a test checks it).
FIELD_GROUPS = _settings.groups(Scenario)


# ------------------------------------------------------------------ what each step of the assembly reads
# One frozen (hashable) view per step of :mod:`whipple_kick.simulate.assembly`, built by the matching Scenario
# property (``scenario.bicycle_spec`` ...). A step takes its view, not the Scenario, so what it reads
# is declared (each field's ``views``), a cache can be keyed on it, and a field outside it cannot change the
# step's result (tests/simulate/test_assembly.py walks every field). The views hold no defaults: the Scenario's
# are the only ones. Their fields are named after the Scenario attributes they copy: the fields declared with
# the view, or a derived attribute (``pressures``, ``lqr_design_speed``) in place of the fields it comes from.
# Each view is built for its Scenario class (a subclass's view holds the subclass's fields too); below, the
# module's names are the views of :class:`Scenario`. :class:`DesignSpec` is written out: its fields are not
# named after the Scenario's.


class _BicycleView:
    """What :func:`~whipple_kick.simulate.assembly.build_bicycle` reads: the bicycle and the rider seated on it."""

    __slots__ = ()


class _TyreView:
    """What :func:`~whipple_kick.simulate.assembly.build_tyres` reads: the tyres and their (rear, front) pressures."""

    __slots__ = ()


class _BodyView:
    """What :func:`~whipple_kick.simulate.assembly.rider_body` reads: the rider's body, its parts' fields, arms and reflex."""

    __slots__ = ()


class _GainsView:
    """What :func:`~whipple_kick.simulate.assembly.controller_gains` and the thesis' gain look-up read."""

    __slots__ = ()


class _ModelView:
    """What :func:`~whipple_kick.simulate.assembly.model_parameters` reads: the compiled model's options."""

    __slots__ = ()


#: The views: name -> (class name, base with its methods, derived attributes and the fields each replaces).
VIEWS = {
    "bicycle": ("BicycleSpec", _BicycleView, ()),
    "tyre": ("TyreSpec", _TyreView, (("pressures", ("pressure_kpa", "pressure_front_kpa", "pressure_rear_kpa")),)),
    "body": ("BodySpec", _BodyView, ()),
    "gains": ("GainsSpec", _GainsView, (("lqr_design_speed", ("speed", "design_speed")),)),
    "model": ("ModelSpec", _ModelView, ()),
}


def view_class(cls, name):
    """The frozen view class ``name`` (:data:`VIEWS`) of Scenario class ``cls``."""
    class_name, base, derived = VIEWS[name]
    return _settings.view_class(cls, name, class_name, base, derived)


def design_model_options(cls):
    """The options of the compiled model the LQR design on the simulated model uses: the fields declared with
    both the ``model`` and the ``design`` view."""
    return tuple(s.name for s in _settings.settings(cls).values() if {"model", "design"} <= set(s.views))


BicycleSpec = view_class(Scenario, "bicycle")
TyreSpec = view_class(Scenario, "tyre")
BodySpec = view_class(Scenario, "body")
GainsSpec = view_class(Scenario, "gains")
ModelSpec = view_class(Scenario, "model")
#: The options of the compiled model the LQR design on the simulated model uses, in :class:`DesignSpec` order.
DESIGN_MODEL_OPTIONS = design_model_options(Scenario)


@dataclass(frozen=True)
class DesignSpec:
    """What the LQR design on the simulated model reads of a run's scenario, and nothing else.

    Attributes
    ----------
    speed : float
        Design speed [m/s].
    leaning : bool
        The rider's upper body leans. Read by nothing now (what is fed back is the model's parts' declared
        gains); it keeps designs for a rigid and a leaning rider apart in the design's cache key.
    heading : bool
        The heading is fed back too (yaw-angle gain ``kq3``).
    gain_scale : float
        Factor on the designed gains [-].
    model_options : tuple of (name, value)
        Keyword options of :func:`whipple_kick.model.slip.model_parameters`
        (tyre transient, carcass, slip speed: :data:`DESIGN_MODEL_OPTIONS`).
    """

    speed: float
    leaning: bool
    heading: bool
    gain_scale: float
    model_options: tuple
