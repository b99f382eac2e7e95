"""One kick-plate run described: the :class:`Scenario` dataclass and its validation.

A :class:`Scenario` holds everything a run of the thesis' kick-plate test
(Dell'Orto 2025, Sections 8.3-8.4) depends on, with the project's choices as
defaults (:meth:`Scenario.thesis` gives the thesis' own): the bicycle and
rider, the tyres, the speed, the rider's control, the kick
(:mod:`whipple_kick.library.inputs` turns its fields into the plate's
motion), the numerics. :meth:`Scenario.validate` checks every field and
raises one-line :class:`~whipple_kick.errors.InputError` messages naming
the value, the allowed range and the unit. docs/simulate.md lists every
decision.

Example
-------
>>> sc = Scenario(pressure_kpa=300.0, fz_n=701.0).validate()
>>> sc.pressures, sc.with_changes(speed=4.0).lqr_design_speed
((300.0, 300.0), 4.0)
"""
from dataclasses import asdict, dataclass, fields, replace
import inspect

from whipple_kick.errors import InputError, check_range
from whipple_kick.library import inputs
from whipple_kick.model import carcass, parts, transient
from whipple_kick.model.slip import SLIP_SPEEDS

#: Rider models: the LQR designed on the linearised classic model, the thesis' Table 8.4 gains, or none.
CONTROLLERS = ("lqr", "thesis", "off")
#: Rear-frame entries halved by the "low inertia" variant (thesis Figure 8.9).
LOW_INERTIA_KEYS = ("IBxx", "IByy", "IBzz", "IBxz", "zB")
#: Table 8.4's gains were designed at this speed [m/s] (thesis Section 8.3).
THESIS_DESIGN_SPEED = 3.0
#: Tyre transient forms (:mod:`whipple_kick.model.transient`): the default and the others.
TYRE_TRANSIENTS = transient.TRANSIENTS
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
#: Pitch of an upright start: ``compressed`` (solved with the tyres' compressions: the front contact on
#: the ground) or ``uncompressed`` (solved with both tyres uncompressed, the compressions set after: the
#: front contact starts below the ground; the authors' published code).
START_PITCHES = ("compressed", "uncompressed")

#: The declared parts' scenario fields (:class:`whipple_kick.model.parts.Field`) by the field that selects
#: their part: each part's fields follow that field in :class:`Scenario` and share its group.
_PART_FIELDS = {}
for _part in parts.REGISTRY.values():
    if _part.fields:
        _PART_FIELDS.setdefault(_part.selected_by[0], []).extend(f.name for f in _part.fields)


def _with_part_fields(cls):
    """Give ``cls`` the declared parts' fields, each after the field that selects its part, and document them.

    For :class:`Scenario` and for the view of the step that reads them (:class:`BodySpec`).

    A part declares its fields once, with range, unit, default and source
    (:func:`whipple_kick.model.parts.fields`); the dataclass field, its
    entry in the class's docstring, its range check, its CLI flag and its
    refusal while the part is off all follow from that declaration.
    """
    annotations, documented = {}, []
    for name, annotation in inspect.get_annotations(cls).items():
        annotations[name] = annotation
        for part in parts.REGISTRY.values():
            if part.selected_by[:1] != (name,):
                continue
            for f in part.fields:
                annotations[f.name] = float
                if hasattr(cls, name):   # defaults where the class has them (Scenario), none in a view
                    setattr(cls, f.name, f.default)
                low = f"more than {f.low:g}" if f.refuse_low else f"{f.low:g}"   # its low end is refused (validate)
                documented.append(f"    {f.name} : float\n        The {f.label} of {part.title or part.name} "
                                  f"[{f.unit}], {low} to {f.high:g}; default {f.default:g}: {f.source}.\n")
    cls.__annotations__ = annotations
    # The entries join the docstring's list of fields: before its Notes, or at its end.
    notes = "\n    Notes\n    -----"
    cls.__doc__ = (cls.__doc__.replace(notes, "".join(documented) + notes, 1) if notes in cls.__doc__
                   else cls.__doc__.rstrip() + "\n" + "".join(documented))
    return cls


@dataclass(frozen=True)
@_with_part_fields
class Scenario:
    """One kick-plate run; the defaults are the project's choices, not all the thesis' (:meth:`thesis` has its).

    Units are SI except pressures [kPa]. ``None`` means "the default rule"
    described per field.

    Attributes
    ----------
    bicycle : str
        Bicycle parameter set (:func:`whipple_kick.library.bicycles.available`) or a
        path. A set without rider gets the Yeadon rider seated; a preset with
        the rider included is used as it is (then ``fz_n`` and
        ``rider_mass_kg`` must be None).
    fz_n, rider_mass_kg : float or None
        Static rear-tyre load [N] the rider's mass is chosen for, or the
        rider's mass [kg]; at most one. Default 635 N for a bicycle without rider.
    rear_load_share : float or None
        Fraction of the bicycle-rider's static weight on the rear tyre [1], in (0, 1). None (default): the
        rider sits in the seated posture and the share follows. Given: with ``fz_n`` (default 635 N) the
        weight is ``fz_n / rear_load_share``, which fixes the rider's mass; with ``rider_mass_kg`` the rear
        load follows; either way the whole rider is moved fore-aft along the bicycle's x axis (posture
        kept, at most 0.15 m) so that the static loads hold (:func:`whipple_kick.library.riders.for_load_share`).
    rider : str
        Yeadon rider file seated on a bicycle-only set, or ``"none"``
        (:data:`whipple_kick.library.riders.NO_RIDER`): the bicycle's
        parameters include its rider (a BicycleParameters ``Benchmark.txt``
        whose rear frame holds the rider, as the Meijaard benchmark's mB = 85
        kg: BicycleParameters cannot say so), so no rider is seated and the
        bicycle runs as it is, with its own load share; ``fz_n``,
        ``rider_mass_kg`` and ``rear_load_share`` must then be None. A
        bicycle-only set with ``"none"`` is refused.
    tyre : str
        Tyre on both wheels (default T03, the kick-plate bicycle's tyre).
    pressure_kpa : float
        Inflation pressure of both tyres [kPa], unless overridden per wheel by
        ``pressure_front_kpa`` / ``pressure_rear_kpa``.
    coefficient_set : str
        Magic-Formula coefficient set (``"table7_9"`` or, T03 only, ``"chapter8"``,
        the fit the thesis' Chapter 8 code used).
    friction : {"none", "plate", "thesis"}
        Friction mode of both tyres (:data:`whipple_kick.library.tyres.FRICTION_MODES`).
    symmetric_tyres : bool
        Zero the tyres' zero-slip offsets, so the steady motion is exactly upright.
    speed : float
        Forward speed [m/s] of the steady motion before the kick.
    controller : {"lqr", "thesis", "off"}
        LQR designed on the linearised classic model at ``design_speed``;
        the thesis' Table 8.4 gains (for 570/635/701 N); or no steer torque.
    design_speed : float or None
        LQR design speed [m/s]. Default None: the run's ``speed``, as a real
        rider adapts to the speed. Give 3.0 to fix the rider as the thesis
        did. Used by ``controller="lqr"`` only (Table 8.4's gains were
        designed at 3 m/s).
    gain_scale : float
        Multiplies every controller gain (thesis Figure 8.7: 0.5).
    thesis_load_n : float or None
        Rear load [N] whose Table 8.4 gains ``controller="thesis"`` uses;
        default ``fz_n``, or for a preset that already includes the rider the
        load it is labelled with (``balanceassist_635N``: 635 N).
    low_inertia : bool
        Halve the rear frame's IBxx, IByy, IBzz, IBxz and mass-centre height zB
        (thesis Figure 8.9). The LQR is still designed on the unmodified
        bicycle (the rider's controller does not change, the plant does).
    kick_displacement : float
        Plate travel [m] (>= 0; direction by ``kick_direction``). With a
        table the travel comes from the table: leave it at its default.
    kick_duration, kick_accel : float or None
        Plate travel time [s] or peak plate acceleration [m/s^2]; at most
        one. Default 0.150 s (13.3 m/s^2 for the thesis' 0.150 m). Not with
        a table.
    kick_profile : {"constant", "smooth", "table"}
        Constant acceleration (thesis), minimum-jerk quintic (finite jerk),
        or the plate displacement tabulated in ``kick_table``.
    kick_table : str or None
        CSV of the plate's lateral displacement (``kick_profile="table"``
        only; see :func:`whipple_kick.library.inputs.load_kick_table`): columns ``time`` [s, from the
        kick start, the trajectory's clock] and ``y`` [m, + to the right].
        The plate follows the clamped cubic spline through the rows
        (:func:`whipple_kick.library.inputs.cubic_segments`), rests at the first
        row's y before the first time and at the last row's y after the
        last; the table must lie within [-settle, duration].
    kick_direction : {"right", "left"}
        Plate moves to the bicycle's right (+y) or left; ``left`` mirrors a
        table's y.
    settle : float
        Steady running shown before the kick [s].
    duration : float
        Simulated time after the kick starts [s].
    rtol : float
        LSODA relative tolerance (thesis 1e-12).
    output_rate : float
        Samples per second of the trajectory [Hz].
    fall_angle_deg : float
        ``|roll|`` [deg] that counts as a fall and ends the run.
    steer_limit_deg : float or None
        ``|steer|`` [deg] that also ends the run as lost (``fall_reason``
        "steer"): past 90 deg the front wheel rolls backwards, which the tyre
        model (forward rolling, pneumatic trail behind the contact) does not
        describe, and no rider recovers from a fork turned over. Without
        steer control the fork turns over before the roll reaches 45 deg.
        None: no steer limit (a fork past 90 deg spins on, so 180 is not
        the same as no limit).
    piecewise : bool
        Restart the integrator at the kick's start and end (default). False
        integrates from -settle across the kick and the plate stop in one
        LSODA run, without the plate stop's impulse (for comparison only;
        not with a table, whose every interval is its own parameter set).
    tyre_transient : {"carcass", "contact_patch", "slip_lag", "force_lag"}
        How the tyre forces build up (:mod:`whipple_kick.model.transient`): a
        lateral carcass spring in series with a sliding contact patch
        (default: passive and friction-limited whatever the load does; the
        force lag at small slip, :mod:`whipple_kick.model.carcass`); lagged
        contact-patch slip and camber with a slip-dependent relaxation
        length (friction-limited, not passive under load changes); the same
        with a constant relaxation length; or the thesis' lagged force.
    carcass_sliding : {"peak", "curve"}
        The carcass tyre's friction limit once the patch slides past the
        curve's peak: the peak itself (default, a Coulomb plateau that uses
        nothing of the fit past the peak) or the steady curve at the
        wheel's kinematic slip (steady sliding follows the fit's falling
        branch). Carcass transient only.
    carcass_damping : float
        Lateral damping of each carcass [N s/m], parallel to its stiffness
        (default 0: the thesis' pure relaxation). Carcass transient only.
    carcass_stiffness_scale : float
        Factor on both carcass stiffnesses C_Fa(F_z0)/sigma0 (default 1; the
        identification of the rider's body varies it, scripts/identify_rider.py). Carcass transient only.
    lqr_model : {"whipple", "simulated"}
        The model the LQR rider (``controller="lqr"``) is designed on: the
        linearised Carvallo-Whipple model (default; full state, roll and
        steer), or the model the run simulates (tyres, body, arms, reflex),
        linearised about upright straight running at the design speed, with
        the law feeding back what the rider feels (roll, steer, their rates,
        and the upper body's lean and its rate when it leans), its gains
        LQR-optimal for that law (:func:`whipple_kick.simulate.control.output_feedback_lqr`).
    lqr_heading : bool
        With ``lqr_model="simulated"``: the law also feeds back the heading
        (yaw angle q3, gain kq3), so the rider steers back to the heading held
        before the kick. Needs straight steady running (``symmetric_tyres``).
    rider_body : {"rigid", "leaning"}
        The rider lumped rigidly into the rear frame (default), or an upper
        body (pelvis, trunk, head, upper arms) leaning on the saddle on the
        hip spring-damper (:func:`whipple_kick.library.riders.seat_with_body`).
    arms : {"off", "on"}
        "on": the forearms and hands turn with the bar and the arms are a
        spring-damper about the steer axis between the bar and the upper body
        (the rear frame with a rigid rider). "off" (default): the hands have
        no mechanical effect on the bar.
    reflex_delay : float
        Delay of the rider's reflex [s], a (3,4) Pade filter (:mod:`whipple_kick.model.reflex`); 0 none.
    reflex_roll, reflex_roll_rate, reflex_steer, reflex_steer_rate : float
        Reflex steer-torque gains on roll [N m/rad], roll rate [N m s/rad],
        steer [N m/rad] and steer rate [N m s/rad], ``T = -(g x)`` delayed;
        separate from the voluntary law (the controller). Default 0.
    carcass_viscosity : float
        Numerics: the sliding viscosity [N s/m] that regularises an
        undamped carcass' friction limit (a patch past the limit slides
        faster by the excess force over it;
        :data:`whipple_kick.model.carcass.SLIDING_VISCOSITY`). Smaller is closer
        to the Coulomb plateau and stiffer (at least 1e-3 N s/m: below,
        LSODA stalls); docs/validation.md shows the results converged.
    plate_stop : {"impulse", "resolve", "keep_speeds"}
        Speeds across the constant-acceleration profile's instant plate
        stop: the rear no-slip constraint's impulse (default), a re-solve
        of the dependent speeds only (the earlier model, which removes
        energy no force accounts for), or no jump at all with the rear
        contact left sliding along its heading (the authors' published
        code, :data:`PLATE_STOPS`). The other profiles stop the plate
        smoothly.
    kick_heading : {"fixed", "settled"}
        ``fixed`` (default): the post-kick run starts from the exact steady
        motion with heading N.x (perpendicular to the plate's motion) and
        the rear contact at the origin, whatever ``settle``; the settle is
        integrated separately and is display only. ``settled``: the steady
        motion starts so at -settle (the earlier model: with a steady turn
        the heading at the kick then depends on ``settle``).
    camber_sign : {"physical", "reversed"}
        Sign of the camber fed to the Magic Formula. ``physical`` (default):
        a leaning wheel is pushed toward the lean, as measured. ``reversed``:
        away from it, as in the thesis authors' published code (the curves
        evaluated at the opposite camber:
        :func:`whipple_kick.model.magic_formula.camber_reversed`). Not physical;
        it exists to explain that code's runs.
    start : {"steady", "upright"}
        ``steady`` (default): the run starts from the solved steady motion.
        ``upright``: from upright straight running with the tyre states at
        their zero-slip values and no rear-wheel torque
        (:func:`whipple_kick.simulate.steady.upright_state`), as the authors' code
        starts; with measured tyres this is not an equilibrium (their
        offsets act from t = 0). Needs ``settle = 0`` (the kick starts the run).
    start_pitch : {"compressed", "uncompressed"}
        Pitch of the upright start. ``compressed`` (default): solved with
        the tyres' compressions, so the front contact is on the ground.
        ``uncompressed``: solved with both tyres uncompressed and the
        compressions set after (vertical equilibrium at that pitch), as the
        authors' code starts: the front contact then starts below the ground
        by about the rear compression less the front one (3.2 mm at 500 kPa
        with ``balanceassist_635N``) and stays so (only the constraint's
        rate is imposed). Needs ``start = "upright"``.
    slip_speed : {"wheel_centre", "contact_point"}
        Whose forward speed along the wheel's heading the tyres' slip angle
        ``atan(v_sy / |v_x|)`` and relaxation ``sigma / |v_x|`` use: the
        wheel centre's (default) or the geometric contact point's, as the
        authors' code takes it. They differ while the wheel's centre moves
        relative to its contact (rolling, pitching, steering); the
        trajectory's ``rolling_speed_*`` columns are the speed in use.

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

    bicycle: str = "balanceassist_v1"
    fz_n: float | None = None
    rider_mass_kg: float | None = None
    rear_load_share: float | None = None
    rider: str = "jason"
    tyre: str = "T03"
    pressure_kpa: float = 400.0
    pressure_front_kpa: float | None = None
    pressure_rear_kpa: float | None = None
    coefficient_set: str = "table7_9"
    friction: str = "none"
    symmetric_tyres: bool = False
    speed: float = 3.0
    controller: str = "lqr"
    design_speed: float | None = None
    gain_scale: float = 1.0
    thesis_load_n: float | None = None
    low_inertia: bool = False
    kick_displacement: float = 0.150
    kick_duration: float | None = None
    kick_accel: float | None = None
    kick_profile: str = "constant"
    kick_table: str | None = None
    kick_direction: str = "right"
    settle: float = 0.5
    duration: float = 6.0
    rtol: float = 1e-10
    output_rate: float = 1000.0
    fall_angle_deg: float = 45.0
    steer_limit_deg: float | None = 90.0
    piecewise: bool = True
    tyre_transient: str = transient.DEFAULT_TRANSIENT
    carcass_sliding: str = carcass.DEFAULT_SLIDING
    carcass_damping: float = 0.0
    carcass_viscosity: float = carcass.SLIDING_VISCOSITY
    carcass_stiffness_scale: float = 1.0
    lqr_model: str = "whipple"
    lqr_heading: bool = False
    rider_body: str = "rigid"
    arms: str = "off"
    reflex_delay: float = 0.0
    reflex_roll: float = 0.0
    reflex_roll_rate: float = 0.0
    reflex_steer: float = 0.0
    reflex_steer_rate: float = 0.0
    plate_stop: str = "impulse"
    kick_heading: str = "fixed"
    camber_sign: str = "physical"
    start: str = "steady"
    start_pitch: str = "compressed"
    slip_speed: str = "wheel_centre"

    @classmethod
    def thesis(cls, pressure_kpa=400.0, **changes):
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
        return {field: getattr(self, field) for field in FIELD_GROUPS[name]}

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
        return self._view(BicycleSpec)

    @property
    def tyre_spec(self) -> "TyreSpec":
        """What :func:`~whipple_kick.simulate.assembly.build_tyres` reads (:class:`TyreSpec`).

        Example
        -------
        >>> Scenario(pressure_front_kpa=350.0).tyre_spec
        TyreSpec(tyre='T03', pressures=(400.0, 350.0), coefficient_set='table7_9', friction='none')
        """
        return self._view(TyreSpec)

    @property
    def body_spec(self) -> "BodySpec":
        """What :func:`~whipple_kick.simulate.assembly.rider_body` reads (:class:`BodySpec`)."""
        return self._view(BodySpec)

    @property
    def gains_spec(self) -> "GainsSpec":
        """What :func:`~whipple_kick.simulate.assembly.controller_gains` reads (:class:`GainsSpec`)."""
        return self._view(GainsSpec)

    @property
    def model_spec(self) -> "ModelSpec":
        """What :func:`~whipple_kick.simulate.assembly.model_parameters` reads (:class:`ModelSpec`)."""
        return self._view(ModelSpec)

    @property
    def design_spec(self) -> "DesignSpec":
        """What the LQR design on the simulated model reads (:class:`DesignSpec`)."""
        return DesignSpec(speed=float(self.lqr_design_speed), leaning=self.rider_body == "leaning",
                          heading=bool(self.lqr_heading), gain_scale=float(self.gain_scale),
                          model_options=tuple((name, getattr(self, name)) for name in DESIGN_MODEL_OPTIONS))

    def _view(self, spec_class):
        # The views' fields are named after the attributes they copy.
        return spec_class(**{f.name: getattr(self, f.name) for f in fields(spec_class)})

    def validate(self) -> "Scenario":
        """Check every field; raise :class:`InputError` naming value, range and unit. Returns ``self``."""
        check_range("speed", self.speed, 0.0, 15.0, "m/s", low_open=True)
        if self.design_speed is not None:
            check_range("design speed", self.design_speed, 0.0, 15.0, "m/s", low_open=True)
        check_range("duration", self.duration, 0.0, MAX_DURATION, "s", low_open=True)
        check_range("settle time", self.settle, 0.0, 60.0, "s")
        check_range("rtol", self.rtol, 1e-14, 1e-3, "(relative)")
        check_range("output rate", self.output_rate, 1.0, 1e5, "Hz")
        check_range("fall angle", self.fall_angle_deg, 0.0, 90.0, "deg", low_open=True, high_open=True)
        if self.steer_limit_deg is not None:
            check_range("steer limit", self.steer_limit_deg, 0.0, 180.0, "deg", low_open=True)
        check_range("gain scale", self.gain_scale, 0.0, 10.0, "(factor)")
        if self.controller not in CONTROLLERS:
            raise InputError(f"controller {self.controller!r} is unknown; choose one of {', '.join(CONTROLLERS)}")
        check_range("carcass damping", self.carcass_damping, 0.0, 1e4, "N s/m")
        check_range("carcass stiffness scale", self.carcass_stiffness_scale, 0.05, 20.0, "(factor)")
        for part in parts.REGISTRY.values():   # the declared parts' fields (the leaning upper body's hip)
            for f in part.fields:
                # With its part selected, a field that refuses its low end is allowed (low, high]: one range in
                # every message (the low end itself is refused with its reason).
                open_low = bool(f.refuse_low) and part.selected(self)
                value = getattr(self, f.name)
                if open_low and value == f.low:
                    raise InputError(f"{f.label} = {value:g} {f.unit} {f.refuse_low}; allowed "
                                     f"({f.low:g}, {f.high:g}] {f.unit} with {part.title or part.name}")
                check_range(f.label, value, f.low, f.high, f.unit, low_open=open_low)
        check_range("reflex delay", self.reflex_delay, 0.0, 0.5, "s")
        for label, value, unit in (("reflex roll gain", self.reflex_roll, "N m/rad"),
                                   ("reflex roll-rate gain", self.reflex_roll_rate, "N m s/rad"),
                                   ("reflex steer gain", self.reflex_steer, "N m/rad"),
                                   ("reflex steer-rate gain", self.reflex_steer_rate, "N m s/rad")):
            check_range(label, value, -1e4, 1e4, unit)
        if self.lqr_heading and (self.controller != "lqr" or self.lqr_model != "simulated"):
            raise InputError("lqr_heading needs the LQR rider designed on the model simulated "
                             "(controller 'lqr', lqr_model 'simulated')")
        # Below 1e-3 N s/m the plateau is so stiff that LSODA stalls at the plate stop (measured 5e-4).
        check_range("carcass sliding viscosity", self.carcass_viscosity, 1e-3, 10.0, "N s/m")
        for label, value, choices in (("tyre transient", self.tyre_transient, TYRE_TRANSIENTS),
                                      ("carcass sliding law", self.carcass_sliding, carcass.SLIDING_LAWS),
                                      ("plate stop", self.plate_stop, PLATE_STOPS),
                                      ("kick heading", self.kick_heading, KICK_HEADINGS),
                                      ("camber sign", self.camber_sign, CAMBER_SIGNS),
                                      ("start", self.start, STARTS),
                                      ("start pitch", self.start_pitch, START_PITCHES),
                                      ("slip speed", self.slip_speed, SLIP_SPEEDS),
                                      ("rider body", self.rider_body, RIDER_BODIES),
                                      ("LQR design model", self.lqr_model, LQR_MODELS),
                                      ("arms", self.arms, ARMS)):
            if value not in choices:
                raise InputError(f"{label} {value!r} is unknown; choose one of {', '.join(choices)}")
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
        self._refuse_unused()
        if self.low_inertia and (self.rider_body != "rigid" or self.arms != "off"):
            # Halving the rear frame's zB and inertias with the upper body split off it would lower the whole
            # mass centre far less than for the rigid rider (0.943 -> 0.773 m, not 0.500 m): not Figure 8.9's variant.
            raise InputError(f"low_inertia halves the rear frame with the whole rider lumped into it (thesis Figure "
                             f"8.9); it conflicts with rider_body {self.rider_body!r} / arms {self.arms!r}: allowed "
                             "with rider_body 'rigid' and arms 'off'")
        if self.fz_n is not None and self.rider_mass_kg is not None:
            raise InputError("give the rear-tyre load fz (N) or the rider mass (kg), not both")
        if self.fz_n is not None:
            check_range("rear-tyre load fz", self.fz_n, 0.0, None, "N", low_open=True)
        if self.rear_load_share is not None:
            check_range("rear load share", self.rear_load_share, 0.0, 1.0, "(unit 1)", low_open=True,
                        high_open=True)
        for name, p in (("pressure", self.pressure_kpa), ("front pressure", self.pressure_front_kpa),
                        ("rear pressure", self.pressure_rear_kpa)):
            if p is not None:
                check_range(name, p, 0.0, None, "kPa", low_open=True)
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
        for mechanism, condition, active, names in MECHANISM_FIELDS:
            for name in names:
                if name not in unused and getattr(self, name) != DEFAULTS[name] and not active(self):
                    unused[name] = f"{mechanism} ({condition})"
        if self.pressure_front_kpa is not None and self.pressure_rear_kpa is not None \
                and self.pressure_kpa != DEFAULTS["pressure_kpa"]:
            unused["pressure_kpa"] = "a tyre without its own pressure (pressure_front_kpa and pressure_rear_kpa are both given)"
        return unused

    def _refuse_unused(self):
        for name, why in self.unused_fields().items():
            raise UnusedFieldError(f"{name} = {_with_unit(name, getattr(self, name))} is read only by {why}, which "
                                   f"this scenario does not use: leave it at its default "
                                   f"{_with_unit(name, DEFAULTS[name])} (it would be ignored)", field=name, why=why)

    def to_dict(self) -> dict:
        """Fields as a plain dict (JSON-ready)."""
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
        import json
        import pathlib

        from whipple_kick import fileio
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
        import math
        import pathlib

        from whipple_kick.library.parameters import tomllib
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


#: Every field's default, by name.
DEFAULTS = {f.name: f.default for f in fields(Scenario)}

#: The unit of every number field, as a file writes it ("1": a factor or a fraction): the uncertainty study checks
#: an input's ``unit`` against it, and the refusals name it.
UNITS = {
    "fz_n": "N", "rider_mass_kg": "kg", "rear_load_share": "1", "pressure_kpa": "kPa", "pressure_front_kpa": "kPa",
    "pressure_rear_kpa": "kPa", "speed": "m/s", "design_speed": "m/s", "gain_scale": "1", "thesis_load_n": "N",
    "kick_displacement": "m", "kick_duration": "s", "kick_accel": "m/s^2", "settle": "s", "duration": "s",
    "rtol": "1", "output_rate": "Hz", "fall_angle_deg": "deg", "steer_limit_deg": "deg",
    "carcass_damping": "N s/m", "carcass_viscosity": "N s/m", "carcass_stiffness_scale": "1",
    **{f.name: f.unit for f in parts.fields()},
    "reflex_delay": "s", "reflex_roll": "N m/rad", "reflex_roll_rate": "N m s/rad", "reflex_steer": "N m/rad",
    "reflex_steer_rate": "N m s/rad",
}


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


#: Fields that may hold a file path (written absolute by :meth:`Scenario.to_file`).
_PATH_FIELDS = ("bicycle", "kick_table")


def _is_path(name, value):
    """Whether the value of field ``name`` is a file path rather than a shipped set's name."""
    text = str(value)
    return name == "kick_table" or text.endswith(".toml") or "/" in text or "\\" in text


_REFLEX_GAINS = ("reflex_roll", "reflex_roll_rate", "reflex_steer", "reflex_steer_rate")

#: Which mechanism reads which fields: (mechanism, when it is in use (words), when it is in use (test),
#: the fields nothing else reads). :meth:`Scenario.validate` refuses a field given other than its default
#: while its mechanism is off (:meth:`Scenario.unused_fields`): refused rather than warned, because a
#: warning is lost among a sweep's cases and the run's scenario.toml would still record a value that
#: did nothing. tests/simulate/test_unused_fields.py walks every field through every mechanism switch.
MECHANISM_FIELDS = (
    ("the carcass tyre", "tyre_transient 'carcass'", lambda s: s.tyre_transient == "carcass",
     ("carcass_sliding", "carcass_damping", "carcass_viscosity", "carcass_stiffness_scale")),
    # The declared parts' fields, used while the scenario selects the part (the leaning upper body's hip).
    *((part.title or part.name, f"{part.selected_by[0]} {part.selected_by[1]!r}", part.selected,
       tuple(f.name for f in part.fields)) for part in parts.REGISTRY.values() if part.fields),
    # "off" is no rider torque at all: neither the voluntary law nor the reflex steers.
    ("the rider's steer control", "controller 'lqr' or 'thesis'; controller 'off' applies no rider torque",
     lambda s: s.controller != "off", ("gain_scale", "reflex_delay") + _REFLEX_GAINS),
    ("the reflex", "a reflex gain other than 0", lambda s: any(getattr(s, g) != 0.0 for g in _REFLEX_GAINS),
     ("reflex_delay",)),
    ("the LQR rider", "controller 'lqr'", lambda s: s.controller == "lqr", ("design_speed", "lqr_model")),
    ("the LQR rider designed on the model simulated", "controller 'lqr', lqr_model 'simulated'",
     lambda s: s.controller == "lqr" and s.lqr_model == "simulated", ("lqr_heading",)),
    ("the thesis' Table 8.4 rider", "controller 'thesis'", lambda s: s.controller == "thesis", ("thesis_load_n",)),
    # The integration applies the plate stop's speed change only where the plate stops instantly.
    ("the instant plate stop", "kick_profile 'constant' and piecewise", lambda s: s.kick_profile == "constant"
     and s.piecewise, ("plate_stop",)),
    ("the steady start", "start 'steady'", lambda s: s.start == "steady", ("kick_heading",)),
    ("the upright start", "start 'upright'", lambda s: s.start == "upright", ("start_pitch",)),
)

#: Every field of :class:`Scenario` in exactly one group (a test checks it).
FIELD_GROUPS = {
    "physics": ("bicycle", "fz_n", "rider_mass_kg", "rear_load_share", "rider", "tyre", "pressure_kpa", "pressure_front_kpa",
                "pressure_rear_kpa", "coefficient_set", "friction", "symmetric_tyres", "speed", "controller",
                "design_speed", "gain_scale", "thesis_load_n", "low_inertia", "kick_displacement", "kick_duration",
                "kick_accel", "kick_profile", "kick_table", "kick_direction", "tyre_transient", "carcass_sliding",
                "carcass_damping", "carcass_stiffness_scale", "lqr_model", "lqr_heading", "rider_body", *_PART_FIELDS["rider_body"], "arms",
                *_PART_FIELDS["arms"], "reflex_delay", "reflex_roll", "reflex_roll_rate", "reflex_steer",
                "reflex_steer_rate"),
    "run": ("settle", "duration", "output_rate", "fall_angle_deg", "steer_limit_deg"),
    "numerics": ("rtol", "piecewise", "carcass_viscosity"),
    "compatibility": ("plate_stop", "kick_heading", "camber_sign", "start", "start_pitch", "slip_speed"),
}


# ------------------------------------------------------------------ what each step of the assembly reads
# One frozen (hashable) view per step of :mod:`whipple_kick.simulate.assembly`, built by the matching Scenario
# property (``scenario.bicycle_spec`` ...). A step takes its view, not the Scenario, so what it reads
# is declared here, a cache can be keyed on it, and a field outside it cannot change the step's result
# (tests/simulate/test_assembly.py walks every field). The views hold no defaults: the Scenario's are the only
# ones. Their fields are named after the Scenario attributes they copy (fields, or the derived
# ``pressures`` and ``lqr_design_speed``), except :class:`DesignSpec`'s.


@dataclass(frozen=True)
class BicycleSpec:
    """What :func:`~whipple_kick.simulate.assembly.build_bicycle` reads: the bicycle and the rider seated on it.

    Attributes
    ----------
    bicycle : str
        Bicycle parameter set or path.
    fz_n : float or None
        Static rear-tyre load [N] the rider's mass is chosen for.
    rider_mass_kg : float or None
        The rider's mass [kg].
    rear_load_share : float or None
        Fraction of the static weight on the rear tyre [1].
    rider : str
        Yeadon rider file, or "none" (the bicycle includes its rider).
    low_inertia : bool
        Halve the rear frame's inertias and mass-centre height (thesis Figure 8.9).
    rider_body : {"rigid", "leaning"}
        The rider lumped into the rear frame, or an upper body leaning on the saddle.
    arms : {"off", "on"}
        Whether the forearms turn with the bar.
    """

    bicycle: str
    fz_n: float | None
    rider_mass_kg: float | None
    rear_load_share: float | None
    rider: str
    low_inertia: bool
    rider_body: str
    arms: str

    @property
    def split(self) -> bool:
        """Whether the rider is split into legs, forearms and upper body (a leaning body or arms on the bar)."""
        return self.rider_body != "rigid" or self.arms_on_bar

    @property
    def leaning(self) -> bool:
        """Whether the upper body leans on the hip (otherwise it is merged into the rear frame)."""
        return self.rider_body == "leaning"

    @property
    def arms_on_bar(self) -> bool:
        """Whether the forearms and hands turn with the bar."""
        return self.arms == "on"


@dataclass(frozen=True)
class TyreSpec:
    """What :func:`~whipple_kick.simulate.assembly.build_tyres` reads: the tyres and their pressures.

    Attributes
    ----------
    tyre : str
        Tyre on both wheels.
    pressures : (float, float)
        (rear, front) inflation pressures [kPa] (:attr:`Scenario.pressures`).
    coefficient_set : str
        Magic-Formula coefficient set.
    friction : str
        Friction mode of both tyres.
    """

    tyre: str
    pressures: tuple
    coefficient_set: str
    friction: str


@dataclass(frozen=True)
@_with_part_fields
class BodySpec:
    """What :func:`~whipple_kick.simulate.assembly.rider_body` reads: the rider's body, arms and reflex.

    Attributes
    ----------
    rider_body : {"rigid", "leaning"}
        Selects the leaning upper body (the trunk part, :data:`whipple_kick.model.parts.TRUNK`).
    arms : {"off", "on"}
        Whether the arms' spring-damper acts about the steer axis.
    reflex_delay : float
        Delay of the reflex [s].
    reflex_roll, reflex_roll_rate, reflex_steer, reflex_steer_rate : float
        Reflex gains on roll [N m/rad], roll rate [N m s/rad], steer [N m/rad] and steer rate [N m s/rad].
    """

    rider_body: str
    arms: str
    reflex_delay: float
    reflex_roll: float
    reflex_roll_rate: float
    reflex_steer: float
    reflex_steer_rate: float


@dataclass(frozen=True)
class GainsSpec:
    """What :func:`~whipple_kick.simulate.assembly.controller_gains` and the thesis' gain look-up read.

    Attributes
    ----------
    controller : {"lqr", "thesis", "off"}
        The rider's voluntary law.
    gain_scale : float
        Factor on every gain [1].
    lqr_design_speed : float
        Speed [m/s] the LQR rider is designed at (:attr:`Scenario.lqr_design_speed`).
    thesis_load_n : float or None
        Rear load [N] of the Table 8.4 row ``controller="thesis"`` uses.
    fz_n, rider_mass_kg : float or None
        The rear load [N] or rider mass [kg] the rider is seated for (the row's default).
    bicycle : str
        Bicycle parameter set or path (a preset with rider is labelled with its load).
    rider : str
        Yeadon rider file, or "none" (the bicycle includes its rider).
    """

    controller: str
    gain_scale: float
    lqr_design_speed: float
    thesis_load_n: float | None
    fz_n: float | None
    rider_mass_kg: float | None
    bicycle: str
    rider: str


@dataclass(frozen=True)
class ModelSpec:
    """What :func:`~whipple_kick.simulate.assembly.model_parameters` reads: the compiled model's options.

    Attributes
    ----------
    symmetric_tyres : bool
        Zero the tyres' zero-slip offsets.
    tyre_transient : str
        How the tyre forces build up (:mod:`whipple_kick.model.transient`).
    camber_sign : {"physical", "reversed"}
        Sign of the camber the Magic Formula is fed.
    carcass_sliding : {"peak", "curve"}
        The carcass tyre's friction limit.
    carcass_damping : float
        Lateral damping of each carcass [N s/m].
    carcass_viscosity : float
        Sliding viscosity [N s/m] regularising the friction limit.
    carcass_stiffness_scale : float
        Factor on both carcass stiffnesses [1].
    slip_speed : {"wheel_centre", "contact_point"}
        Whose forward speed the tyres' slip angle uses.
    """

    symmetric_tyres: bool
    tyre_transient: str
    camber_sign: str
    carcass_sliding: str
    carcass_damping: float
    carcass_viscosity: float
    carcass_stiffness_scale: float
    slip_speed: str


#: The options of the compiled model the LQR design on the simulated model uses, in :class:`DesignSpec` order.
DESIGN_MODEL_OPTIONS = ("tyre_transient", "carcass_sliding", "carcass_damping", "carcass_viscosity", "slip_speed",
                        "carcass_stiffness_scale")


@dataclass(frozen=True)
class DesignSpec:
    """What the LQR design on the simulated model reads of a run's scenario, and nothing else.

    Attributes
    ----------
    speed : float
        Design speed [m/s].
    leaning : bool
        The rider's upper body leans (its lean and lean rate are fed back).
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
