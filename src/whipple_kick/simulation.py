"""One kick-plate run end to end: scenario in, time histories and summary out.

A :class:`Scenario` describes one run of the thesis' kick-plate test
(Dell'Orto 2025, Sections 8.3-8.4) with the thesis' settings as defaults;
:func:`run` builds the bicycle with rider, the tyres and the controller,
finds the steady motion, integrates the compiled slip model piecewise across
the kick and returns a :class:`Result` (a pandas DataFrame of the time
histories and a JSON-ready summary).

Time is measured from the start of the kick: the run starts at
``-settle`` (steady running shown before the kick) and ends at
``duration`` (or at the fall). docs/simulate.md lists every decision.
"""
import copy
from dataclasses import asdict, dataclass, field, fields, replace
import functools
import math
import pathlib
import time

import numpy as np

from . import energy
from .errors import InputError, check_range

#: Kick-plate profiles the compiled model can represent (its ``kick_profile`` parameter).
KICK_PROFILES = {"constant": 0, "smooth": 1}
#: Tabulated plate motion: a clamped cubic spline through ``kick_table``, one
#: compiled-model segment (``kick_profile`` 2) per table interval.
TABLE_PROFILE = "table"
#: Every ``Scenario.kick_profile`` value.
PROFILES = (*KICK_PROFILES, TABLE_PROFILE)
#: The compiled model's cubic-segment profile (y = c0 + c1 tau + c2 tau^2 + c3 tau^3).
_SEGMENT_PROFILE = 2
#: Peak |acceleration| of each profile as a multiple of displacement/duration^2:
#: constant acceleration 2 D/T^2; minimum-jerk quintic 10/sqrt(3) D/T^2 (at s = 0.2113).
PEAK_ACCEL_FACTOR = {"constant": 2.0, "smooth": 10.0 / math.sqrt(3.0)}
CONTROLLERS = ("lqr", "thesis", "off")
DIRECTIONS = ("right", "left")
#: Rear-frame entries halved by the "low inertia" variant (thesis Figure 8.9).
LOW_INERTIA_KEYS = ("IBxx", "IByy", "IBzz", "IBxz", "zB")
#: Table 8.4's gains were designed at this speed [m/s] (thesis Section 8.3).
THESIS_DESIGN_SPEED = 3.0
#: |steady yaw rate| [rad/s] below which steady running counts as straight (a yaw-angle gain needs it).
_STRAIGHT_YAW_RATE = 1e-9

# Moore's coordinates and speeds, named for the trajectory table.
_COORDINATE_COLUMNS = {
    "q1": ("x_rear", "m"), "q2": ("y_rear", "m"), "q3": ("yaw", "rad"), "q4": ("roll", "rad"),
    "q5": ("pitch", "rad"), "q6": ("rear_wheel_angle", "rad"), "q7": ("steer", "rad"),
    "q8": ("front_wheel_angle", "rad"), "q9": ("compression_rear", "m"),
    "q10": ("compression_front", "m"),
}
_SPEED_COLUMNS = {
    "u1": ("u1", "m/s"), "u2": ("u2", "m/s"), "u3": ("yaw_rate", "rad/s"), "u4": ("roll_rate", "rad/s"),
    "u5": ("pitch_rate", "rad/s"), "u6": ("rear_wheel_rate", "rad/s"), "u7": ("steer_rate", "rad/s"),
    "u8": ("front_wheel_rate", "rad/s"), "u9": ("compression_rate_rear", "m/s"),
    "u10": ("compression_rate_front", "m/s"),
}
# Named outputs of the compiled model: output name -> (column, unit).
_OUTPUT_COLUMNS = {
    "slip_r": ("slip_rear", "rad"), "slip_f": ("slip_front", "rad"),
    "camber_r": ("camber_rear", "rad"), "camber_f": ("camber_front", "rad"),
    "vx_r": ("rolling_speed_rear", "m/s"), "vx_f": ("rolling_speed_front", "m/s"),
    "fz_r": ("fz_rear", "N"), "fz_f": ("fz_front", "N"),
    "fy_ss_r": ("fy_steady_rear", "N"), "fy_ss_f": ("fy_steady_front", "N"),
    "mz_ss_r": ("mz_steady_rear", "N m"), "mz_ss_f": ("mz_steady_front", "N m"),
    "T7": ("steer_torque", "N m"),
    "yp": ("plate_y", "m"), "vp": ("plate_velocity", "m/s"), "ap": ("plate_acceleration", "m/s^2"),
    "kinetic_energy": ("kinetic_energy", "J"), "potential_energy": ("potential_energy", "J"),
    "spring_energy": ("spring_energy", "J"), "sliding_power": ("sliding_power", "W"),
    "holonomic": ("holonomic_residual", "m"),
    # The force and moment each tyre applies to the bicycle, in every transient form.
    "fy_r": ("fy_rear", "N"), "fy_f": ("fy_front", "N"), "mz_r": ("mz_rear", "N m"), "mz_f": ("mz_front", "N m"),
    "sigma_r": ("relaxation_length_rear", "m"), "sigma_f": ("relaxation_length_front", "m"),
}
# Contact-patch states (transient forms contact_patch and slip_lag only).
_PATCH_STATE_COLUMNS = {
    "slip_patch_r": ("slip_patch_rear", "rad"), "slip_patch_f": ("slip_patch_front", "rad"),
    "camber_patch_r": ("camber_patch_rear", "rad"), "camber_patch_f": ("camber_patch_front", "rad"),
}
#: Energy balance residual column [J] (:func:`whipple_kick.energy.balance_residual`).
BALANCE_COLUMN = "energy_balance_residual"
#: Unit of every trajectory column.
UNITS = {"time": "s", **{c: u for c, u in _COORDINATE_COLUMNS.values()},
         **{c: u for c, u in _SPEED_COLUMNS.values()},
         **{c: u for c, u in _PATCH_STATE_COLUMNS.values()},
         **{c: u for c, u in _OUTPUT_COLUMNS.values()},
         **{c: u for c, u in energy.COLUMNS.values()}, BALANCE_COLUMN: "J"}


#: Tyre transient forms (:mod:`whipple_kick.transient`): the default and the others.
TYRE_TRANSIENTS = ("contact_patch", "slip_lag", "force_lag")
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
#: State at the start of the run: ``steady`` (the solved steady motion) or
#: ``upright`` (upright straight running, not an equilibrium with measured tyres:
#: the authors' published code).
STARTS = ("steady", "upright")


class SimulationError(RuntimeError):
    """The integration failed numerically (not a user mistake).

    Attributes
    ----------
    partial : Result or None
        What was computed before the failure (trajectory up to it, summary
        with ``status`` "failed"), when there is anything.
    """

    def __init__(self, message, partial=None):
        super().__init__(message)
        self.partial = partial


@dataclass(frozen=True)
class Scenario:
    """One kick-plate run; the defaults are the thesis' simulation settings.

    Units are SI except pressures [kPa]. ``None`` means "the default rule"
    described per field.

    Attributes
    ----------
    bicycle : str
        Bicycle parameter set (:func:`whipple_kick.bicycles.available`) or a
        path. A set without rider gets the Yeadon rider seated; a preset with
        the rider included is used as it is (then ``fz_n`` and
        ``rider_mass_kg`` must be None).
    fz_n, rider_mass_kg : float or None
        Static rear-tyre load [N] the rider's mass is chosen for, or the
        rider's mass [kg]; at most one. Default 635 N for a bicycle without rider.
    rider : str
        Yeadon rider file.
    tyre : str
        Tyre on both wheels (default T03, the kick-plate bicycle's tyre).
    pressure_kpa : float
        Inflation pressure of both tyres [kPa], unless overridden per wheel by
        ``pressure_front_kpa`` / ``pressure_rear_kpa``.
    coefficient_set : str
        Magic-Formula coefficient set (``"table7_9"`` or, T03 only, ``"chapter8"``,
        the fit the thesis' Chapter 8 code used).
    friction : {"none", "plate", "thesis"}
        Friction mode of both tyres (:data:`whipple_kick.tyres.FRICTION_MODES`).
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
        only; see :func:`load_kick_table`): columns ``time`` [s, from the
        kick start, the trajectory's clock] and ``y`` [m, + to the right].
        The plate follows the clamped cubic spline through the rows
        (:func:`whipple_kick.slip.cubic_segments`), rests at the first
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
        |roll| [deg] that counts as a fall and ends the run.
    steer_limit_deg : float or None
        |steer| [deg] that also ends the run as lost (``fall_reason``
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
    tyre_transient : {"contact_patch", "slip_lag", "force_lag"}
        How the tyre forces build up (:mod:`whipple_kick.transient`):
        lagged contact-patch slip and camber with a slip-dependent
        relaxation length (default, passive and friction-limited); the same
        with a constant relaxation length; or the thesis' lagged force.
    plate_stop : {"impulse", "resolve"}
        Speeds across the constant-acceleration profile's instant plate
        stop: the rear no-slip constraint's impulse (default) or a re-solve
        of the dependent speeds only (the earlier model, which removes
        energy no force accounts for). The other profiles stop the plate
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
        :func:`whipple_kick.magic_formula.camber_reversed`). Not physical;
        it exists to explain that code's runs.
    start : {"steady", "upright"}
        ``steady`` (default): the run starts from the solved steady motion.
        ``upright``: from upright straight running with the tyre states at
        their zero-slip values and no rear-wheel torque
        (:func:`whipple_kick.slip.upright_state`), as the authors' code
        starts; with measured tyres this is not an equilibrium (their
        offsets act from t = 0). Needs ``settle = 0`` (the kick starts the run).
    """

    bicycle: str = "balanceassist_v1"
    fz_n: float | None = None
    rider_mass_kg: float | None = None
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
    tyre_transient: str = "contact_patch"
    plate_stop: str = "impulse"
    kick_heading: str = "fixed"
    camber_sign: str = "physical"
    start: str = "steady"

    @classmethod
    def thesis(cls, pressure_kpa=400.0, **changes):
        """The Chapter 8 runs as the authors' code made them.

        Bicycle+rider preset ``balanceassist_635N``, Table 8.4 gains for
        635 N, T03 with the ``chapter8`` coefficients and the ``thesis``
        friction mode, the thesis' lagged-force tyre transient
        (``tyre_transient="force_lag"``), LSODA rtol 1e-12. The plate stop
        and the heading at the kick are the project's (impulse, fixed).
        ``changes`` override any field.
        """
        base = dict(bicycle="balanceassist_635N", controller="thesis", thesis_load_n=635.0,
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
        ``start="upright"``, ``settle=0`` (the kick at t = 0) and
        ``plate_stop="keep_speeds"``; their standard run is at 500 kPa.
        Each of these can be switched back alone through ``changes``.
        docs/validation.md ("The authors' published code") compares it with
        that code's stored run.

        Example
        -------
        >>> Scenario.authors_code().camber_sign, Scenario.authors_code(start="steady", settle=0.5).start
        ('reversed', 'steady')
        """
        base = dict(camber_sign="reversed", start="upright", settle=0.0, plate_stop="keep_speeds")
        base.update(changes)
        return cls.thesis(pressure_kpa, **base)

    # ------------------------------------------------------------ derived values

    @property
    def lqr_design_speed(self):
        """Speed [m/s] the LQR rider is designed at: ``design_speed``, or the run's speed."""
        return self.speed if self.design_speed is None else self.design_speed

    @property
    def pressures(self):
        """(rear, front) pressures [kPa]."""
        rear = self.pressure_kpa if self.pressure_rear_kpa is None else self.pressure_rear_kpa
        front = self.pressure_kpa if self.pressure_front_kpa is None else self.pressure_front_kpa
        return rear, front

    def kick_timing(self):
        """(duration [s], peak |acceleration| [m/s^2], signed displacement [m]) of the kick.

        For a table: the table's time span, the spline's peak |y''| and its
        net travel y(last) - y(first), mirrored for ``kick_direction="left"``.
        """
        if self.kick_direction not in DIRECTIONS:
            raise InputError(f"kick direction {self.kick_direction!r} is unknown; choose right or left")
        if self.kick_profile == TABLE_PROFILE or self.kick_table is not None:
            table = self.kick_table_spline()
            return table.duration, table.peak_acceleration, table.displacement
        if self.kick_profile not in KICK_PROFILES:
            hint = ""
            if str(self.kick_profile).lower() in ("tabulated", "csv") or str(self.kick_profile).endswith(".csv"):
                hint = "; for a tabulated plate motion use kick_profile='table' with kick_table='FILE.csv'"
            raise InputError(f"kick profile {self.kick_profile!r} is unknown; choose one of "
                             f"{', '.join(PROFILES)}{hint}")
        disp = check_range("kick displacement", self.kick_displacement, 0.0, 1.0, "m")
        factor = PEAK_ACCEL_FACTOR[self.kick_profile]
        if self.kick_duration is not None and self.kick_accel is not None:
            raise InputError("give the kick's duration (s) or its peak acceleration (m/s^2), not both")
        if self.kick_accel is not None:
            accel = check_range("kick peak acceleration", self.kick_accel, 0.0, 1000.0, "m/s^2", low_open=True)
            if disp == 0.0:
                raise InputError("a kick acceleration needs a kick displacement > 0 m")
            dur = math.sqrt(factor * disp / accel)
        else:
            dur = 0.150 if self.kick_duration is None else self.kick_duration
            dur = check_range("kick duration", dur, 0.0, 10.0, "s", low_open=True)
            accel = factor * disp / dur**2
        if dur > self.duration:
            raise InputError(f"kick duration = {dur:g} s is longer than the run duration "
                             f"{self.duration:g} s; allowed (0, {self.duration:g}] s")
        sign = 1.0 if self.kick_direction == "right" else -1.0
        return dur, accel, sign * disp

    def kick_table_spline(self):
        """The tabulated kick, checked against the other fields: a :class:`KickTable`.

        Raises
        ------
        InputError
            No table with ``kick_profile="table"``, a table with another
            profile, a conflicting kick field, a bad file (one line naming
            the file and the problem) or a table outside [-settle, duration].
        """
        if self.kick_profile != TABLE_PROFILE:
            raise InputError(f"kick table {self.kick_table!r} needs kick_profile 'table', "
                             f"not {self.kick_profile!r}")
        if self.kick_table is None:
            raise InputError("kick profile 'table' needs a kick table: kick_table='FILE.csv' "
                             "with columns time (s) and y (m)")
        # The table alone sets the plate motion; a second description of it is a mistake.
        for name, value, unit in (("kick duration", self.kick_duration, "s"),
                                  ("kick peak acceleration", self.kick_accel, "m/s^2")):
            if value is not None:
                raise InputError(f"{name} = {value!r} {unit} conflicts with kick table {str(self.kick_table)!r} "
                                 "(the table sets the plate motion)")
        default_disp = next(f.default for f in fields(Scenario) if f.name == "kick_displacement")
        if self.kick_displacement != default_disp:
            raise InputError(f"kick displacement = {self.kick_displacement!r} m conflicts with kick table "
                             f"{str(self.kick_table)!r} (the table sets the plate travel)")
        if not self.piecewise:
            raise InputError(f"piecewise = False is not possible with kick table {str(self.kick_table)!r}: "
                             "every table interval is integrated with its own parameters")
        times, y = load_kick_table(self.kick_table)
        name = str(self.kick_table)
        if times[0] < -self.settle or times[-1] > self.duration:
            raise InputError(f"kick table {name!r} spans [{times[0]:g}, {times[-1]:g}] s, outside the run "
                             f"[-settle, duration] = [{-self.settle:g}, {self.duration:g}] s; times are "
                             "from the kick start: trim the table or change settle/duration")
        sign = 1.0 if self.kick_direction == "right" else -1.0
        return KickTable.from_points(name, times, sign * y)

    def validate(self):
        """Check every field; raise :class:`InputError` naming value, range and unit."""
        check_range("speed", self.speed, 0.0, 15.0, "m/s", low_open=True)
        if self.design_speed is not None:
            check_range("design speed", self.design_speed, 0.0, 15.0, "m/s", low_open=True)
        check_range("duration", self.duration, 0.0, 120.0, "s", low_open=True)
        check_range("settle time", self.settle, 0.0, 60.0, "s")
        check_range("rtol", self.rtol, 1e-14, 1e-3, "(relative)")
        check_range("output rate", self.output_rate, 1.0, 1e5, "Hz")
        check_range("fall angle", self.fall_angle_deg, 0.0, 90.0, "deg", low_open=True, high_open=True)
        if self.steer_limit_deg is not None:
            check_range("steer limit", self.steer_limit_deg, 0.0, 180.0, "deg", low_open=True)
        check_range("gain scale", self.gain_scale, 0.0, 10.0, "(factor)")
        if self.controller not in CONTROLLERS:
            raise InputError(f"controller {self.controller!r} is unknown; choose one of {', '.join(CONTROLLERS)}")
        for label, value, choices in (("tyre transient", self.tyre_transient, TYRE_TRANSIENTS),
                                      ("plate stop", self.plate_stop, PLATE_STOPS),
                                      ("kick heading", self.kick_heading, KICK_HEADINGS),
                                      ("camber sign", self.camber_sign, CAMBER_SIGNS),
                                      ("start", self.start, STARTS)):
            if value not in choices:
                raise InputError(f"{label} {value!r} is unknown; choose one of {', '.join(choices)}")
        if self.start == "upright" and self.settle != 0.0:
            raise InputError(f"settle time = {self.settle:g} s conflicts with start 'upright' (upright running is "
                             "not a steady motion: the kick starts the run); allowed: 0 s")
        if self.plate_stop == "keep_speeds" and not self.piecewise:
            raise InputError("plate stop 'keep_speeds' needs piecewise = True (the single LSODA run re-solves "
                             "the speeds at the plate stop)")
        if self.controller == "off" and self.gain_scale != 1.0:
            raise InputError(f"gain scale = {self.gain_scale:g} conflicts with controller off "
                             "(there are no gains to scale)")
        if self.fz_n is not None and self.rider_mass_kg is not None:
            raise InputError("give the rear-tyre load fz (N) or the rider mass (kg), not both")
        if self.fz_n is not None:
            check_range("rear-tyre load fz", self.fz_n, 0.0, None, "N", low_open=True)
        for name, p in (("pressure", self.pressure_kpa), ("front pressure", self.pressure_front_kpa),
                        ("rear pressure", self.pressure_rear_kpa)):
            if p is not None:
                check_range(name, p, 0.0, None, "kPa", low_open=True)
        self.kick_timing()
        return self

    def to_dict(self):
        """Fields as a plain dict (JSON-ready)."""
        return asdict(self)


# ------------------------------------------------------------ tabulated kick

def load_kick_table(path):
    """Read a kick-plate table: (times [s], y [m]) as float arrays.

    The file is comma-separated text (UTF-8). Blank lines and lines starting
    with ``#`` are skipped. With a header row, the columns named ``time``
    and ``y`` are used (case-insensitive; a unit suffix such as
    ``time [s]`` or ``y (m)`` is allowed; other columns are ignored).
    Without a header, i.e. when the first row is all numbers, the file must
    have exactly two columns, time then y: a header-less file with more
    columns is ambiguous and refused.

    Parameters
    ----------
    path : str or path-like

    Returns
    -------
    times, y : ndarray
        At least 2 rows, finite, times strictly increasing.

    Raises
    ------
    InputError
        One line naming the file and the problem (missing file, missing
        column, non-numeric or non-finite entry with its line, non-increasing
        time, fewer than 2 rows).
    """
    p = pathlib.Path(path)
    if not p.is_file():
        what = "is not a file" if p.exists() else "does not exist"
        raise InputError(f"kick table {str(path)!r} {what}")
    st = p.stat()
    # Cached by content identity: validate() and run() both read the table.
    times, y = _read_kick_table(str(p.resolve()), str(path), st.st_mtime_ns, st.st_size)
    return times.copy(), y.copy()


@functools.lru_cache(maxsize=16)
def _read_kick_table(resolved, name, mtime_ns, size):
    import re

    def fail(problem):
        raise InputError(f"kick table {name!r}: {problem}")

    try:
        text = pathlib.Path(resolved).read_text(encoding="utf-8-sig")
    except UnicodeDecodeError:
        fail("is not a UTF-8 text file (expected CSV with columns time (s) and y (m))")
    except OSError as exc:
        fail(f"cannot be read: {exc.strerror or exc}")
    rows = [(k + 1, [f.strip() for f in line.split(",")]) for k, line in enumerate(text.splitlines())
            if line.strip() and not line.lstrip().startswith("#")]
    if not rows:
        fail("has no rows (expected CSV with columns time (s) and y (m))")

    def number(text):
        try:
            return float(text)
        except ValueError:
            return None

    first_line, first = rows[0]
    if all(number(f) is not None for f in first):
        if len(first) != 2:
            fail(f"line {first_line} has {len(first)} columns and no header; a file without header "
                 "must have exactly two columns, time (s) then y (m)")
        columns, data = {"time": 0, "y": 1}, rows
    else:
        names = [re.sub(r"\s*[\[(][^\])]*[\])]$", "", f).strip().lower() for f in first]
        columns = {}
        for want in ("time", "y"):
            hits = [i for i, n in enumerate(names) if n == want]
            if not hits:
                fail(f"has no column {want!r} (header: {', '.join(first)}); name the columns "
                     "time (s) and y (m)")
            if len(hits) > 1:
                fail(f"has {len(hits)} columns named {want!r}")
            columns[want] = hits[0]
        data = rows[1:]
    width = len(first)
    times, ys, lines = [], [], []
    for line, cells in data:
        if len(cells) != width:
            fail(f"line {line} has {len(cells)} column{'s' if len(cells) != 1 else ''}, expected {width}")
        values = []
        for col in ("time", "y"):
            cell = cells[columns[col]]
            v = number(cell)
            if v is None:
                fail(f"line {line}: {cell!r} in column {col} is not a number")
            if not math.isfinite(v):
                fail(f"line {line}: {col} = {cell} is not finite")
            values.append(v)
        times.append(values[0])
        ys.append(values[1])
        lines.append(line)
    if len(times) < 2:
        fail(f"has {len(times)} data row{'s' if len(times) != 1 else ''}; at least 2 are needed")
    t = np.array(times)
    bad = np.flatnonzero(np.diff(t) <= 0.0)
    if bad.size:
        k = bad[0] + 1
        fail(f"line {lines[k]}: time {times[k]!r} s is not after the previous row's {times[k - 1]!r} s "
             "(times must increase strictly)")
    t.flags.writeable = False
    y = np.array(ys)
    y.flags.writeable = False
    return t, y


@dataclass(frozen=True)
class KickTable:
    """A tabulated plate motion as the compiled model follows it.

    Attributes
    ----------
    name : str
        The table's file as given.
    times, y : ndarray
        Table rows [s], [m] (y signed: + to the right, after ``kick_direction``).
    segments : list of (t_start, t_end, (c0, c1, c2, c3))
        Clamped cubic spline, one cubic per table interval
        (:func:`whipple_kick.slip.cubic_segments`).
    """

    name: str
    times: np.ndarray
    y: np.ndarray
    segments: list

    @classmethod
    def from_points(cls, name, times, y):
        """Fit the spline through ``(times, y)``."""
        from . import slip
        return cls(name, np.asarray(times, float), np.asarray(y, float), slip.cubic_segments(times, y))

    @property
    def duration(self):
        """Time from the first to the last row [s]."""
        return float(self.times[-1] - self.times[0])

    @property
    def displacement(self):
        """Net plate travel y(last) - y(first) [m], signed."""
        return float(self.y[-1] - self.y[0])

    @property
    def peak_acceleration(self):
        """Peak |y''| of the spline [m/s^2].

        y'' = 2 c2 + 6 c3 tau is linear in each segment, so its extremes are
        at the segment ends.
        """
        return float(max(max(abs(2 * c[2]), abs(2 * c[2] + 6 * c[3] * (b - a))) for a, b, c in self.segments))

    @property
    def peak_velocity(self):
        """Peak |y'| of the spline [m/s] (from the roots of y'' in each segment)."""
        peak = 0.0
        for a, b, c in self.segments:
            taus = [0.0, b - a]
            if c[3] != 0.0 and 0.0 < -c[2] / (3 * c[3]) < b - a:
                taus.append(-c[2] / (3 * c[3]))
            peak = max(peak, *(abs(c[1] + 2 * c[2] * s + 3 * c[3] * s * s) for s in taus))
        return float(peak)

    def pieces(self, t_start, t_end):
        """Pieces covering [t_start, t_end]: list of (a, b, t0, (c0, c1, c2, c3)).

        Rest at the first row's y before the table, one spline segment per
        table interval, rest at the last row's y afterwards; clipped to the
        span (empty pieces dropped). ``t0`` is the cubic's origin.
        """
        t_first, t_last = float(self.times[0]), float(self.times[-1])
        raw = [(t_start, t_first, t_first, (float(self.y[0]), 0.0, 0.0, 0.0))]
        raw += [(float(a), float(b), float(a), c) for a, b, c in self.segments]
        raw.append((t_last, t_end, t_last, (float(self.y[-1]), 0.0, 0.0, 0.0)))
        out = []
        for a, b, t0, c in raw:
            a, b = max(a, t_start), min(b, t_end)
            if b > a:
                out.append((a, b, t0, c))
        return out


def sample_times(scenario):
    """The run's output times [s]: the multiples of 1/``output_rate`` on the kick's clock, plus -settle and duration.

    On the kick's clock (t = 0 at the nominal kick start), so the samples
    after the kick do not depend on ``settle``: k / rate for the integers k
    with -settle <= k / rate <= duration, and the run's ends if they fall
    between multiples.

    Example
    -------
    >>> sample_times(Scenario(settle=0.002, duration=0.003, output_rate=1000.0)).tolist()
    [-0.002, -0.001, 0.0, 0.001, 0.002, 0.003]
    """
    rate, t_start, t_end = scenario.output_rate, 0.0 - scenario.settle, scenario.duration   # no -0.0
    tiny = 1e-9   # of a sample spacing: a product like 0.5 * 1000 is an integer to round-off
    k = np.arange(math.ceil(t_start * rate - tiny), math.floor(t_end * rate + tiny) + 1)
    times = k / rate
    times = times[(times > t_start + tiny / rate) & (times < t_end - tiny / rate)]
    return np.concatenate([[t_start], times, [t_end]])


def end_limits(scenario):
    """The limits that end a run as lost (``integrate.integrate`` keywords): |roll| and |steer| [rad]."""
    return {"fall_angle": math.radians(scenario.fall_angle_deg),
            "steer_limit": None if scenario.steer_limit_deg is None else math.radians(scenario.steer_limit_deg)}


def _integrate_run(steady, scenario, kick_T, table, kick_start):
    """Integrate one run: the display-only settle, then the kick from the exact steady state.

    ``kick_heading="fixed"`` (piecewise): the post-kick run starts at the
    kick start from ``steady.x`` (heading N.x, rear contact at the origin),
    so nothing after the kick depends on ``settle``; the settle segment
    starts from the steady motion moved back by ``settle``
    (:func:`whipple_kick.slip.advance_steady`) and is integrated on its own.
    ``piecewise=False`` integrates from -settle (from that moved-back state,
    or from ``steady.x`` with ``kick_heading="settled"``) in one LSODA run.
    The constant-acceleration profile's plate stop is a velocity jump
    (:func:`whipple_kick.slip.velocity_jump`) in piecewise runs. The
    quadratures are shifted to be 0 at the kick start.

    Returns
    -------
    traj : integrate.Trajectory
    rhs : slip.CompiledRHS or list of them
    owner : ndarray of int or None
        With a list of ``rhs``: which one produced each sample.
    breakpoints : tuple of float
    jumps : list of dict
        One per velocity jump (:func:`whipple_kick.slip.velocity_jump`'s info).
    """
    from . import integrate, slip

    limits = end_limits(scenario)
    # piecewise=False is the comparison case: one LSODA run across the kick,
    # not even restarted at the integrator's chunk boundaries.
    chunk = integrate.DEFAULT_CHUNK if scenario.piecewise else math.inf
    samples = sample_times(scenario)
    t_start, t_end = float(samples[0]), scenario.duration
    rhs = slip.CompiledRHS(steady.params)   # the plate at rest at the kick start (a table's first row)
    # An upright start is no steady motion: nothing to move back along, it is where the run starts.
    fixed = scenario.kick_heading == "fixed" and scenario.start == "steady"
    x_start = slip.advance_steady(rhs, steady.x, t_start - kick_start, t=kick_start) if fixed else steady.x
    jumps, jump_map = [], {}
    stop = kick_start + kick_T
    kept = table is None and scenario.piecewise and scenario.kick_profile == "constant" \
        and scenario.plate_stop == "keep_speeds"
    if table is None:
        breakpoints = (kick_start, stop) if scenario.piecewise else ()
        if scenario.piecewise and scenario.kick_profile == "constant" and not kept:
            def plate_stop(t, x):
                x, info = slip.velocity_jump(rhs, t, x, impulse=scenario.plate_stop == "impulse")
                jumps.append(info)
                return x
            jump_map = {stop: plate_stop}
    else:
        breakpoints = tuple(float(t) for t in table.times if -scenario.settle < t < scenario.duration)

    def run_from(x, a, rows):
        if kept and a < stop:
            return _integrate_kept_speeds(rhs, steady.params, x, (a, kick_start), rows, stop, scenario, chunk,
                                          jumps)
        if table is None:
            return integrate.integrate(rhs, x, t_end, t_start=a, breakpoints=breakpoints, rtol=scenario.rtol,
                                       **limits, chunk=chunk, samples=rows, jumps=jump_map), rhs, None
        # The drive torque T6c found for the steady motion stays in every piece's parameters.
        return _integrate_table(steady.params, x, table, scenario, chunk, t_start=a)

    if not (fixed and scenario.piecewise) or kick_start <= t_start:
        traj, rhs_out, owner = run_from(steady.x if kick_start <= t_start else x_start, t_start, samples)
        return _from_kick_start(traj, kick_start), rhs_out, owner, breakpoints, jumps
    settle = integrate.integrate(rhs, x_start, kick_start, t_start=t_start, rtol=scenario.rtol, **limits,
                                 chunk=chunk, samples=samples[samples < kick_start])
    quad = [slip.X[n] for n in slip.QUADRATURE_STATES]
    settle_x = settle.x.copy()
    settle_x[:, quad] -= settle.end_state[quad]   # cumulative from the kick start
    if settle.fell or settle.failed:
        # The steady motion did not last through the settle (it fell or the integration failed before
        # the kick): that is the run's outcome, and there is no kick to integrate.
        return replace(settle, x=settle_x), rhs, None, breakpoints, jumps
    post, rhs_out, owner = run_from(steady.x, kick_start, samples[samples >= kick_start])
    traj = integrate.Trajectory(np.concatenate([settle.t, post.t]), np.concatenate([settle_x, post.x]),
                                post.fell, post.fall_time, settle.nfev + post.nfev, post.message,
                                end_state=post.end_state, failed=post.failed, njev=settle.njev + post.njev,
                                evaluations=settle.evaluations + post.evaluations, fall_reason=post.fall_reason)
    if owner is not None:
        # The settle's samples belong to the model of the plate at rest before the table.
        rhs_out = [rhs] + list(rhs_out)
        owner = np.concatenate([np.zeros(settle.t.size, dtype=int), np.asarray(owner) + 1])
    return traj, rhs_out, owner, breakpoints, jumps


def _integrate_kept_speeds(rhs, params, x, span, rows, stop, scenario, chunk, jumps):
    """Integrate across the plate stop keeping every speed (``plate_stop="keep_speeds"``).

    Up to the stop with ``rhs``; from it with the rear constraint imposing
    the slide that keeps the speeds continuous
    (:func:`whipple_kick.slip.kept_speeds_slide`), as the authors' code's
    acceleration-level constraint does. ``span`` is (start time, kick start)
    [s]; the kick start is a breakpoint. Appends the stop's info to ``jumps``.

    Returns
    -------
    traj : integrate.Trajectory
    rhs : list of slip.CompiledRHS
        Before and after the stop.
    owner : ndarray of int
        Which of them produced each sample.
    """
    from . import integrate, slip

    limits = end_limits(scenario)
    rows = np.asarray(rows, dtype=float)
    t_start, kick_start = span
    first = integrate.integrate(rhs, x, stop, t_start=t_start, breakpoints=(kick_start,), rtol=scenario.rtol,
                                **limits, chunk=chunk, samples=rows[rows < stop])
    if first.fell or first.failed:
        return first, [rhs], np.zeros(first.t.size, dtype=int)
    x_stop = first.end_state
    slide = slip.kept_speeds_slide(rhs, stop, x_stop)
    after = slip.CompiledRHS({**params, "vsx_r": slide})
    ke = [r.outputs(t, x_stop)[1][slip.OUT["kinetic_energy"]]
          for r, t in ((rhs, np.nextafter(stop, -np.inf)), (after, stop))]
    jumps.append({"time_s": float(stop), "kinetic_energy_change_j": float(ke[1] - ke[0]), "impulse_work_j": None,
                  "constraint_impulse_n_s": None, "rear_slide_m_s": slide})
    second = integrate.integrate(after, x_stop, scenario.duration, t_start=stop, rtol=scenario.rtol,
                                 **limits, chunk=chunk, samples=rows[rows >= stop])
    traj = integrate.Trajectory(np.concatenate([first.t, second.t]), np.concatenate([first.x, second.x]),
                                second.fell, second.fall_time, first.nfev + second.nfev, second.message,
                                end_state=second.end_state, failed=second.failed, fall_reason=second.fall_reason)
    return traj, [rhs, after], np.concatenate([np.zeros(first.t.size, dtype=int), np.ones(second.t.size, dtype=int)])


def _from_kick_start(traj, kick_start):
    """``traj`` with the quadratures shifted to be 0 at the kick start (interpolated between samples)."""
    from . import slip
    if traj.t.size == 0:
        return traj
    x = traj.x.copy()
    for name in slip.QUADRATURE_STATES:
        j = slip.X[name]
        x[:, j] -= np.interp(kick_start, traj.t, traj.x[:, j])
    return replace(traj, x=x)


def _segment_parameters(params, t0, coefficients):
    """``params`` with the plate following one cubic (everything else, e.g. T6c, kept)."""
    out = dict(params)
    out["kick_profile"] = float(_SEGMENT_PROFILE)
    out["kick_t0"] = float(t0)
    out.update({f"kick_c{i}": float(c) for i, c in enumerate(coefficients)})
    return out


def _integrate_table(params, x0, table, scenario, chunk, t_start=None):
    """Integrate a tabulated kick piece by piece on the run's global output grid.

    Each piece (rest before, one spline segment per table interval, rest
    after) has its own parameter set and compiled right-hand side; each is
    one :func:`whipple_kick.integrate.integrate` call on the samples not yet
    produced, starting from the previous piece's exact end state. The run
    starts at ``t_start`` (default -settle) from ``x0``.

    Returns
    -------
    trajectory : integrate.Trajectory
    rhs : list of slip.CompiledRHS
        One per piece.
    piece : ndarray of int
        Index into ``rhs`` of the piece that produced each sample.
    """
    from . import integrate, slip

    t_end = scenario.duration
    pending = sample_times(scenario)
    t_start = pending[0] if t_start is None else t_start
    pending = pending[pending >= t_start]
    limits = end_limits(scenario)
    ts, xs, owner, rhss = [], [], [], []
    nfev = njev = evaluations = 0
    x = np.asarray(x0, dtype=float)
    traj = None
    for k, (a, b, t0, coefficients) in enumerate(table.pieces(t_start, t_end)):
        rhs = slip.CompiledRHS(_segment_parameters(params, t0, coefficients))
        rhss.append(rhs)
        traj = integrate.integrate(rhs, x, b, t_start=a, rtol=scenario.rtol, **limits,
                                   chunk=chunk, samples=pending)
        nfev, njev, evaluations = nfev + traj.nfev, njev + traj.njev, evaluations + traj.evaluations
        ts.append(traj.t)
        xs.append(traj.x)
        owner.append(np.full(traj.t.size, k))
        if traj.t.size:
            pending = pending[pending > traj.t[-1]]
        x = traj.end_state
        if traj.fell or traj.failed:
            break
    trajectory = integrate.Trajectory(np.concatenate(ts), np.concatenate(xs), traj.fell, traj.fall_time,
                                      nfev, traj.message, end_state=x, failed=traj.failed, njev=njev,
                                      evaluations=evaluations, fall_reason=traj.fall_reason)
    return trajectory, rhss, np.concatenate(owner).astype(int)


@dataclass
class Result:
    """Outcome of :func:`run`.

    Attributes
    ----------
    scenario : Scenario
    trajectory : pandas.DataFrame
        Time histories, columns named as in :data:`UNITS` (time from the kick start).
    summary : dict
        JSON-ready summary (no NaN): outcome, model set-up, steady state,
        peaks, recovery metrics, numerics.
    """

    scenario: Scenario
    trajectory: "object"
    summary: dict = field(default_factory=dict)


# ------------------------------------------------------------------ model set-up

def build_bicycle(scenario):
    """Bicycle with rider for ``scenario``: (moore parameters, design parameters, info dict).

    The info holds the rider mass [kg] and the static loads [N] of the
    unmodified bicycle; ``moore`` has the low-inertia change applied if asked.
    ``design`` is the unmodified set the LQR is designed on. Cached per
    process on the fields it reads (a sweep over pressures, speeds or kicks
    seats the Yeadon rider once); callers get their own copies.
    """
    key = (scenario.bicycle, _file_stamp(scenario.bicycle), scenario.fz_n, scenario.rider_mass_kg,
           scenario.rider, scenario.low_inertia)
    return copy.deepcopy(_bicycle_setup(*key))


def _file_stamp(name):
    """Modification time of a parameter file given by path (so an edited file is re-read)."""
    path = pathlib.Path(str(name))
    return path.stat().st_mtime_ns if path.suffix == ".toml" and path.is_file() else None


@functools.lru_cache(maxsize=256)
def _bicycle_setup(bicycle, _stamp, fz_n, rider_mass_kg, rider_name, low_inertia):
    from . import benchmark, bicycles, riders

    bike = bicycles.load(bicycle)
    if bike.includes_rider:
        if fz_n is not None or rider_mass_kg is not None:
            raise InputError(f"bicycle {bike.name!r} already includes its rider; "
                             "do not give a rear-tyre load fz or a rider mass with it")
        combined, rider_mass = bike, None
    elif rider_mass_kg is not None:
        rider = riders.yeadon_rider(rider_name, mass_kg=rider_mass_kg)
        combined, rider_mass = riders.seat(bike, rider), float(rider_mass_kg)
    else:
        fz = 635.0 if fz_n is None else fz_n
        combined, rider_mass = riders.for_rear_load(bike, fz, rider=rider_name)
    rear_n, front_n = riders.static_loads(combined)
    design = dict(combined.moore)
    moore = dict(design)
    if low_inertia:
        bench = dict(combined.benchmark)
        for key in LOW_INERTIA_KEYS:
            bench[key] *= 0.5
        moore = benchmark.to_moore(bench)
    info = {"bicycle": bike.name, "includes_rider_preset": bike.includes_rider,
            "rider_mass_kg": rider_mass, "static_load_rear_n": rear_n, "static_load_front_n": front_n,
            "total_mass_kg": sum(float(combined.benchmark[k]) for k in ("mR", "mB", "mH", "mF"))}
    return moore, design, info


@functools.lru_cache(maxsize=256)
def _lqr(design_items, speed):
    # In front of the on-disk cache, which spares later processes python-control's import.
    from . import control
    K, poles = control.cached_lqr_gains(dict(design_items), speed)
    return tuple(np.ravel(K)), tuple(np.ravel(poles))


def controller_gains(scenario, design):
    """Steer-torque gains by name, and the LQR design's closed-loop poles at its design speed (or None).

    The LQR rider is designed at :attr:`Scenario.lqr_design_speed` (the run's
    speed unless ``design_speed`` is given).
    """
    from . import control

    if scenario.controller == "off":
        return {k: 0.0 for k in control.GAIN_ORDER}, None
    if scenario.controller == "thesis":
        gains = control.thesis_gains(thesis_load(scenario))
        return {k: scenario.gain_scale * v for k, v in gains.items()}, None
    K, poles = _lqr(tuple(sorted(design.items())), float(scenario.lqr_design_speed))
    return control.gains_dict(K, scenario.gain_scale), np.asarray(poles)


def thesis_load(scenario):
    """Rear load [N] whose Table 8.4 row ``controller="thesis"`` uses.

    ``thesis_load_n`` if given, else ``fz_n``, else the load a preset with
    rider is labelled with (``balanceassist_635N``: 635 N), else 635 N for a
    bicycle whose rider is seated for the default load.
    """
    from . import bicycles

    if scenario.thesis_load_n is not None:
        return scenario.thesis_load_n
    if scenario.fz_n is not None:
        return scenario.fz_n
    bike = bicycles.load(scenario.bicycle)
    if bike.includes_rider and bike.thesis_rear_load_n is not None:
        return bike.thesis_rear_load_n
    if scenario.rider_mass_kg is None and not bike.includes_rider:
        return 635.0
    raise InputError("controller thesis uses Table 8.4 gains for a rear load of 570, 635 or 701 N: give fz (N), "
                     "or thesis_load_n (--thesis-load N) for a rider given by mass or a preset with rider")


def build_tyres(scenario):
    """(rear, front) tyres and a list of notes about them."""
    from . import tyres

    notes = []
    rear_p, front_p = scenario.pressures
    loaded = []
    for p in (rear_p, front_p):
        tyre = tyres.load(scenario.tyre, p, coefficient_set=scenario.coefficient_set,
                          friction=scenario.friction, missing_moment="error")
        try:
            tyre.blend   # raises when the tyre has no M_z coefficients
            loaded.append(tyre)
        except InputError as exc:
            # Tyres without published M_z data: run with M_z = 0 and say so.
            if "aligning-moment" not in str(exc):
                raise
            loaded.append(tyres.load(scenario.tyre, p, coefficient_set=scenario.coefficient_set,
                                     friction=scenario.friction, missing_moment="zero"))
            note = f"{scenario.tyre} has no published aligning-moment data: M_z = 0"
            if note not in notes:
                notes.append(note)
    return loaded[0], loaded[1], notes


def preflight(scenario):
    """Cheap checks of everything a user can get wrong, before any long work.

    Field ranges, tyre name and pressure range, bicycle name and rider
    conflicts, the Table 8.4 row of ``controller="thesis"``. Raises
    :class:`InputError`; returns ``scenario``.
    """
    from . import bicycles, control

    scenario.validate()
    build_tyres(scenario)
    bike = bicycles.load(scenario.bicycle)
    if bike.includes_rider and (scenario.fz_n is not None or scenario.rider_mass_kg is not None):
        raise InputError(f"bicycle {bike.name!r} already includes its rider; "
                         "do not give a rear-tyre load fz or a rider mass with it")
    if scenario.controller == "thesis":
        control.thesis_gains(thesis_load(scenario))
    return scenario


# -------------------------------------------------------------------- running

def _trajectory_frame(rhs, traj, owner=None, tyre_transient="contact_patch"):
    """DataFrame of states and named outputs at every sample.

    ``rhs`` is one compiled right-hand side, or (tabulated kick) a list of
    them with ``owner[i]`` the one that produced sample ``i``. The patch
    states are columns in the contact-patch forms only; the energy columns
    and the balance residual (:mod:`whipple_kick.energy`) in every form.
    """
    import pandas as pd
    from . import slip

    n = traj.t.size
    if owner is None:
        outs = rhs.outputs_at(traj.t, traj.x)
    else:
        # Each segment's compiled model evaluates the samples it produced.
        owner = np.asarray(owner)
        outs = np.empty((n, len(slip.OUTPUT_NAMES)))
        for k in np.unique(owner):
            rows = owner == k
            outs[rows] = rhs[k].outputs_at(traj.t[rows], traj.x[rows])
    cols = {"time": traj.t}
    for q, (name, _) in _COORDINATE_COLUMNS.items():
        cols[name] = traj.x[:, slip.X[q]]
    for u, (name, _) in _SPEED_COLUMNS.items():
        cols[name] = outs[:, slip.OUT[u]]   # includes the dependent speeds u5 u6 u8
    applied = ("fy_r", "fy_f", "mz_r", "mz_f")
    for o in applied:
        cols[_OUTPUT_COLUMNS[o][0]] = outs[:, slip.OUT[o]]
    if tyre_transient != "force_lag":
        for state, (name, _) in _PATCH_STATE_COLUMNS.items():
            cols[name] = traj.x[:, slip.X[state]]
    for o, (name, _) in _OUTPUT_COLUMNS.items():
        if o not in applied:
            cols[name] = outs[:, slip.OUT[o]]
    for state, (name, _) in energy.COLUMNS.items():
        cols[name] = traj.x[:, slip.X[state]]
    frame = pd.DataFrame(cols)
    frame[BALANCE_COLUMN] = energy.balance_residual(frame)
    return frame


#: A closed-loop pole whose real part exceeds this [1/s] makes the rider linearly unstable
#: (slower growth, by less than 1 % over a 10 s run, is not reported).
UNSTABLE_REAL_PART = 1e-3


def _who_rides(scenario, controller_type):
    """How the summary and the messages name the rider in use."""
    if controller_type == "lqr":
        return f"the LQR rider designed at {scenario.lqr_design_speed:g} m/s"
    if controller_type == "thesis":
        return f"the thesis' Table 8.4 rider (designed at {THESIS_DESIGN_SPEED:g} m/s)"
    if controller_type == "off":
        return "the bicycle without steer control"
    return "the rider with the given gains"


def _steady_advice(scenario, controller_type):
    """What a user can change when there is no steady motion (for the one-line error)."""
    if controller_type == "lqr" and scenario.design_speed is not None:
        return (f"the rider is designed at {scenario.design_speed:g} m/s: choose another design speed "
                "(--design-speed; by default the run's speed) or another speed")
    if controller_type == "thesis":
        return (f"Table 8.4's rider was designed at {THESIS_DESIGN_SPEED:g} m/s: choose controller lqr "
                "(designed at the run's speed) or another speed")
    return "choose another speed, rider or tyre pressure, or symmetric tyres"


def steady_motion(params, scenario, controller_type):
    """The steady motion before the kick (:func:`whipple_kick.steady.find_steady_state`)."""
    from . import steady
    return steady.find_steady_state(params, scenario.speed, advice=_steady_advice(scenario, controller_type))


#: What an upright start's stability is judged about when the tyres' offsets allow no steady motion.
_SYMMETRIC_ABOUT = "upright running without the tyres' zero-slip offsets"
_SYMMETRIC_ROUTE = f"{_SYMMETRIC_ABOUT} (no steady motion with them)"


def start_state(params, scenario, controller_type):
    """The steady motion the rider's stability is judged about, and the state the run starts from.

    With ``start="steady"`` both are the steady motion. With
    ``start="upright"`` the run starts from :func:`whipple_kick.slip.upright_state`;
    stability is judged about the steady motion of the same model if there
    is one, else about upright running with the tyres' offsets removed (an
    exact equilibrium).

    Returns
    -------
    found : whipple_kick.steady.Found
    start : whipple_kick.slip.SteadyState
    """
    from . import slip, steady

    if scenario.start == "steady":
        found = steady_motion(params, scenario, controller_type)
        return found, found.steady
    try:
        start = slip.upright_state(params, scenario.speed)
    except FloatingPointError as exc:
        raise SimulationError(str(exc)) from None
    try:
        found = steady_motion(params, scenario, controller_type)
    except steady.NoSteadyMotion:
        symmetric = slip.steady_state(steady.offset_scaled(params, 0.0), scenario.speed)
        found = steady.Found(symmetric, _SYMMETRIC_ROUTE, 1)
    return found, start


def linear_stability(scenario, moore, gains, found, controller_type):
    """Is the rider in use linearly stable at the run's speed?

    Poles of the slip model linearised about the steady motion at constant
    speed (:func:`whipple_kick.steady.lateral_poles`; decisive) and of the
    no-slip classic model of the same bicycle with the same gains
    (:func:`whipple_kick.control.closed_loop_poles`). A yaw-angle gain breaks
    the slip linearisation's heading invariance: then the classic model decides.

    Returns
    -------
    dict
        ``stable``, ``message`` (one line, None when stable), ``slowest_pole_1_s``,
        ``model`` (which linearisation decided), ``poles_slip_model_1_s``,
        ``poles_no_slip_model_1_s`` (each as [real, imag] pairs), ``criterion``.
    """
    from . import control, steady

    classic = control.closed_loop_poles(moore, scenario.speed, gains)
    slip_poles = None
    if not gains.get("kq3", 0.0):
        try:
            slip_poles = steady.lateral_poles(found.steady.params, found.steady.x)
        except FloatingPointError:   # the linearisation's pitch solve failed: the classic model decides
            slip_poles = None
    about = _SYMMETRIC_ABOUT if found.route == _SYMMETRIC_ROUTE else "the steady motion"
    decisive, model = ((slip_poles, f"slip model about {about}, constant speed")
                       if slip_poles is not None else (classic, "no-slip classic model"))
    slowest = decisive[0]
    stable = bool(slowest.real <= UNSTABLE_REAL_PART)
    message = None
    if not stable:
        message = (f"{_who_rides(scenario, controller_type)} is linearly unstable at {scenario.speed:g} m/s: "
                   f"slowest closed-loop pole {_pole_text(slowest)} 1/s ({model}; no-slip model "
                   f"{_pole_text(classic[0])} 1/s)")
    pairs = lambda poles: None if poles is None else [[float(p.real), float(p.imag)] for p in poles]
    return {"stable": stable, "message": message, "slowest_pole_1_s": pairs([slowest])[0], "model": model,
            "poles_slip_model_1_s": pairs(slip_poles), "poles_no_slip_model_1_s": pairs(classic),
            "criterion": f"unstable when a closed-loop pole has real part > {UNSTABLE_REAL_PART:g} 1/s"}


def _pole_text(pole):
    text = f"{pole.real:+.3f}"
    return text + (f" +- {abs(pole.imag):.3f}j" if abs(pole.imag) > 1e-9 else "")


def _response_metrics(df, baseline, x0, scenario, traj):
    """Section 8.3 metrics (``metrics``, ``unavailable``) and the recovery of a (possibly partial) run."""
    from . import analysis, slip

    fall_roll = math.radians(scenario.fall_angle_deg)
    ended = None
    if traj.fell:
        ended = f"fell {traj.fall_time:.3f} s after the kick start"
    elif traj.failed:
        ended = "the integration failed before the end of the run"
    try:
        metrics = analysis.kick_metrics(df, t_kick=0.0, baseline=baseline, include_spectra=False,
                                        fall_roll=fall_roll)
        rec = analysis.recovery(df, 0.0, {name: float(x0[slip.X[state]]) for name, state in
                                          (("yaw_rate", "u3"), ("roll_rate", "u4"), ("steer_rate", "u7"))},
                                ended=ended)
    except InputError as exc:   # a failure so early that too little of the response exists
        metrics = {"unavailable": {"all": f"no response to analyse: {exc}"}}
        rec = {"time_s": None, "reason": ended or str(exc), "signals": {}}
    # The integrator's event is exact; kick_metrics sees |roll| only up to the limit.
    metrics["fell"] = bool(traj.fell)
    metrics["fall_time"] = traj.fall_time
    unavailable = metrics.setdefault("unavailable", {})
    if traj.fell:
        unavailable.pop("fall_time", None)
    if ended is not None and metrics.get("last_peak_time") is not None:
        # The last peak above 8 % before a fall or a failure is not the end of the response.
        metrics["last_peak_time"], unavailable["last_peak_time"] = None, ended
    return metrics, rec


def _custom_gains(gains):
    """Check user-given steer-torque gains (by name) and fill the missing ones with 0."""
    from . import control, slip, symbols

    unknown = sorted(set(gains) - set(slip.GAIN_NAMES))
    if unknown:
        raise InputError(f"unknown steer-torque gain(s) {unknown}; known: {list(slip.GAIN_NAMES)}")
    # The four of the thesis' law always; the yaw gains only when given.
    names = control.GAIN_ORDER + tuple(n for n in ("kq3", "ku3") if n in gains)
    return {name: check_range(f"gain {name}", gains.get(name, 0.0), None, None, symbols.info(name).unit)
            for name in names}


def _control_law(gains):
    """``T7 = -(kq4 q4 + ...)`` with the gains in use (gain k<x> multiplies state <x>), for the summary."""
    return "T7 = -(" + " + ".join(f"{name} {name[1:]}" for name in gains) + ")"


def _clean(value):
    """JSON-ready copy: numpy scalars/arrays to Python, NaN/inf refused."""
    if isinstance(value, dict):
        return {str(k): _clean(v) for k, v in value.items()}
    if isinstance(value, (list, tuple, np.ndarray)):
        return [_clean(v) for v in value]
    if isinstance(value, (np.bool_, bool)):
        return bool(value)
    if isinstance(value, (np.integer, int)):
        return int(value)
    if isinstance(value, (np.floating, float)):
        v = float(value)
        if not math.isfinite(v):
            raise SimulationError(f"non-finite value {v} in the summary")
        return v
    if isinstance(value, complex):
        return [_clean(value.real), _clean(value.imag)]
    return value


def model_hash():
    """Content hash of the compiled slip model in use (from its library file name)."""
    from . import slip
    return pathlib.Path(slip.library()._name).stem


def run(scenario, *, tyres=None, gains=None):
    """Run one kick-plate simulation.

    Parameters
    ----------
    scenario : Scenario
    tyres : (rear, front), optional
        Tyre objects to use instead of the scenario's tyre and pressures,
        e.g. :func:`whipple_kick.tyres.linear_tyre` or a :class:`~whipple_kick.tyres.Tyre`
        loaded with other options. The summary names them.
    gains : mapping, optional
        Steer-torque gains by name (``kq4 kq7 ku4 ku7``, and the yaw gains
        ``kq3 ku3``; N m/rad, N m s/rad; missing ones are 0) instead of the
        scenario's controller; the law is still ``T7 = -K x``.
        ``scenario.gain_scale`` does not apply to them. A yaw-angle gain
        (e.g. from :func:`whipple_kick.control.heading_lqr_gains`) needs a
        straight steady motion, so tyres without zero-slip offsets.

    Returns
    -------
    Result

    Raises
    ------
    InputError
        A field is out of range, unknown or conflicting;
        :class:`whipple_kick.steady.NoSteadyMotion` (an InputError) when
        there is no steady motion to start from, with the physical reason.
    SimulationError
        The integration failed numerically (never NaN in a result): e.g. it
        stalled beyond :data:`whipple_kick.integrate.DEFAULT_BUDGET`. Its
        ``partial`` holds the result up to the failure.

    Example
    -------
    >>> from whipple_kick.simulation import Scenario, run
    >>> result = run(Scenario(duration=1.0))                 # doctest: +SKIP
    >>> result.summary["outcome"], result.summary["linear_stability"]["stable"]   # doctest: +SKIP
    ('completed', True)
    """
    from . import integrate, slip, symbols

    wall0 = time.perf_counter()
    scenario.validate()
    custom_gains = None if gains is None else _custom_gains(gains)
    kick_T, kick_accel, kick_D = scenario.kick_timing()
    table = scenario.kick_table_spline() if scenario.kick_profile == TABLE_PROFILE else None
    # Tyres first: a pressure outside the measured range is the commonest mistake and cheap to find.
    if tyres is None:
        rear, front, notes = build_tyres(scenario)
    else:
        rear, front = tyres
        notes = [f"custom tyre objects (the scenario's tyre and pressures are not used): "
                 f"rear {rear!r}, front {front!r}"]
    moore, design, info = build_bicycle(scenario)
    if gains is None:
        gains, poles = controller_gains(scenario, design)
        controller_type = scenario.controller
    else:
        gains, poles, controller_type = custom_gains, None, "custom gains"
    if table is None:
        kick = dict(t0=0.0, duration=kick_T, displacement=kick_D, profile=KICK_PROFILES[scenario.kick_profile])
        kick_start = 0.0
    else:
        # Steady running with the plate at rest at the table's first y
        # (only the plate's velocity enters the tyre slip, so any y0 is steady).
        kick_start = float(table.times[0])
        kick = dict(profile=_SEGMENT_PROFILE, t0=kick_start, coefficients=(float(table.y[0]), 0.0, 0.0, 0.0))
    params = slip.model_parameters(moore, rear, front, gains=gains, symmetric=scenario.symmetric_tyres,
                                   kick=kick, tyre_transient=scenario.tyre_transient,
                                   reverse_camber=scenario.camber_sign == "reversed")
    found, steady = start_state(params, scenario, controller_type)
    stability = linear_stability(scenario, moore, gains, found, controller_type)
    steady_yaw_rate = float(steady.x[slip.X["u3"]])
    if gains.get("kq3", 0.0) and abs(steady_yaw_rate) > _STRAIGHT_YAW_RATE:
        # In a steady turn the yaw angle grows without bound, and so would kq3's torque.
        raise InputError(f"a yaw-angle gain kq3 needs straight steady running, but the steady yaw rate is "
                         f"{steady_yaw_rate:.3g} rad/s (allowed |yaw rate| <= {_STRAIGHT_YAW_RATE:g} rad/s): "
                         f"use tyres without zero-slip offsets (symmetric_tyres=True)")
    t_int = time.perf_counter()
    try:
        traj, rhs, owner, breakpoints, jumps = _integrate_run(steady, scenario, kick_T, table, kick_start)
    except FloatingPointError as exc:
        raise SimulationError(f"integration failed: {exc}") from None
    integration_s = time.perf_counter() - t_int
    df = _trajectory_frame(rhs, traj, owner, scenario.tyre_transient)
    if not np.all(np.isfinite(df.to_numpy())):
        raise SimulationError("non-finite values in the trajectory")

    x0 = steady.x
    # Recovery is back to the steady motion, also after an upright start (which is not one);
    # without a steady motion with these tyres, back to upright running.
    reference = steady if found.route == _SYMMETRIC_ROUTE else found.steady
    baseline = float(reference.x[slip.X["u3"]])
    metrics, recovery = _response_metrics(df, baseline, reference.x, scenario, traj)
    after = df["time"].to_numpy() >= 0.0

    summary = {
        "outcome": "failed" if traj.failed else "fell" if traj.fell else "completed",
        "fell": bool(traj.fell),
        "fall_time_s": traj.fall_time,
        "fall_reason": traj.fall_reason,
        "end_time_s": float(df["time"].iloc[-1]),
        "message": traj.message,
        "bicycle": info,
        "tyres": {
            "name": scenario.tyre if tyres is None else f"custom: rear {rear!r}, front {front!r}",
            "coefficient_set": scenario.coefficient_set,
            "friction": scenario.friction, "symmetric": scenario.symmetric_tyres,
            "transient": scenario.tyre_transient,
            "pressure_rear_kpa": scenario.pressures[0] if tyres is None else None,
            "pressure_front_kpa": scenario.pressures[1] if tyres is None else None,
            "notes": notes,
        },
        "controller": {
            "type": controller_type, "gain_scale": scenario.gain_scale if custom_gains is None else None,
            "design_speed_m_s": {"lqr": scenario.lqr_design_speed, "thesis": THESIS_DESIGN_SPEED}.get(
                controller_type),
            "rider": _who_rides(scenario, controller_type),
            "gains": gains,
            "gain_units": {name: symbols.info(name).unit for name in gains},
            "law": _control_law(gains),
            # At the run's speed, for the gains used (the LQR design's own poles are at its design speed).
            "linear_closed_loop_poles": stability["poles_no_slip_model_1_s"],
            "design_poles": None if poles is None else [[p.real, p.imag] for p in poles],
        },
        "linear_stability": stability,
        "kick": {"start_s": kick_start, "duration_s": kick_T, "displacement_m": kick_D,
                 "peak_acceleration_m_s2": kick_accel, "profile": scenario.kick_profile,
                 "direction": scenario.kick_direction,
                 **({} if table is None else {"table": {
                     "file": table.name, "rows": int(table.times.size),
                     "y_first_m": float(table.y[0]), "y_last_m": float(table.y[-1]),
                     "peak_abs_y_m": float(np.max(np.abs(table.y))),
                     "peak_velocity_m_s": table.peak_velocity,
                     "spline": "clamped cubic (plate at rest at both ends; y, y', y'' continuous)"}})},
        "steady_state": {
            "speed_m_s": scenario.speed,
            "roll_rad": float(x0[slip.X["q4"]]), "steer_rad": float(x0[slip.X["q7"]]),
            "pitch_rad": float(x0[slip.X["q5"]]), "yaw_rate_rad_s": float(x0[slip.X["u3"]]),
            "yaw_rate_baseline_rad_s": baseline,
            "lateral_drift_m_s": float(x0[slip.X["u2"]]),
            "compression_rear_m": float(x0[slip.X["q9"]]), "compression_front_m": float(x0[slip.X["q10"]]),
            **_rear_wheel_torque(steady),
            "residual": float(steady.residual),
            "found_by": found.route if scenario.start == "steady" else (
                f"upright start (start 'upright'): not a steady motion, the tyres' zero-slip forces act from "
                f"t = 0 (largest lateral acceleration there {steady.unknowns['largest_rate']:.3g} m/s^2 or "
                f"rad/s^2); yaw-rate peaks and recovery are measured from "
                + (f"the steady motion's yaw rate {baseline:.4g} rad/s" if reference is not steady
                   else "upright running (no steady motion with these tyres)")),
        },
        "peaks": {f"max_abs_{name}": float(np.max(np.abs(df[name].to_numpy()[after]), initial=0.0))
                  for name in ("yaw_rate", "roll_rate", "steer_rate", "roll", "steer", "slip_rear",
                               "fy_rear", "fy_front", "steer_torque")},
        "energy": _energy_summary(df, jumps, scenario),
        "recovery": recovery,
        "metrics": {k: v for k, v in metrics.items() if k != "unavailable"},
        "metrics_unavailable": metrics["unavailable"],
        "numerics": {
            "method": "LSODA", "rtol": scenario.rtol, "piecewise": scenario.piecewise,
            "plate_stop": scenario.plate_stop, "kick_heading": scenario.kick_heading,
            "breakpoints_s": list(breakpoints), "nfev": int(traj.nfev), "njev": int(traj.njev),
            # What the budget counts: LSODA's evaluations and those inside its Jacobians.
            "evaluations": int(traj.evaluations),
            "budget": {"allowance": integrate.DEFAULT_BUDGET.allowance,
                       "per_simulated_second": integrate.DEFAULT_BUDGET.per_second},
            "integration_wall_s": integration_s,
            "max_abs_holonomic_m": float(np.max(np.abs(df["holonomic_residual"]))),
            "model_hash": model_hash(),
        },
        "scenario": scenario.to_dict(),
        "units": {column: UNITS[column] for column in df.columns},
    }
    summary["numerics"]["wall_s"] = time.perf_counter() - wall0
    result = Result(scenario=scenario, trajectory=df, summary=_clean(summary))
    if traj.failed:
        raise SimulationError(traj.message, partial=result)
    return result


def _rear_wheel_torque(steady):
    """Summary entries of the steady rear-wheel torque T6c: value, sign convention, role, and what it balances."""
    from . import slip

    rhs = slip.CompiledRHS(steady.params)
    dx, out = rhs.outputs(0.0, steady.x)
    torque = float(steady.params["T6c"])
    power = {name: float(dx[slip.X[state]]) for name, state in (
        ("rear_wheel_torque", "W_wheel"), ("zero_slip_forces", "W_zero_slip"), ("aligning_moments", "W_moment"),
        ("sliding", "D_slide"))}
    power["sliding"] = -power["sliding"]   # dissipation enters the balance with a minus
    role = "none" if torque == 0.0 else ("brake" if torque * out[slip.OUT["u6"]] < 0.0 else "drive")
    return {
        "rear_wheel_torque_n_m": torque,
        "rear_wheel_torque_convention": ("on the rear wheel about the rear frame's C.y axis (pointing to the "
                                         "rider's right); + opposes forward rolling (the wheel spins about -C.y)"),
        "rear_wheel_torque_role": role,
        "steady_power_w": power,
    }


def _energy_summary(df, jumps, scenario):
    """Totals of the energy accounting after the kick, the balance residual and the velocity jumps."""
    after = df["time"].to_numpy() >= 0.0
    totals = {f"{column}_j": float(df[column].iloc[-1]) for column, _ in energy.COLUMNS.values()}
    stored = sum(df[c].to_numpy() for c in energy.STORED)
    dissipation = df["sliding_dissipation"].to_numpy() + df["damper_dissipation"].to_numpy()
    residual = np.abs(df[BALANCE_COLUMN].to_numpy())
    return {
        "convention": ("works done ON the bicycle and dissipations, cumulative from the kick start (J); "
                       "stored = kinetic + potential + tyre springs + carcasses; balance residual = "
                       "change of stored - (works - dissipations)"),
        **totals,
        "stored_change_after_kick_j": float(stored[-1] - stored[after][0]) if after.any() else 0.0,
        "balance_residual_max_abs_j": float(residual.max()),
        "dissipation_largest_decrease_j": float(max(0.0, -np.diff(dissipation).min())) if len(df) > 1 else 0.0,
        "plate_stop": scenario.plate_stop,
        "velocity_jumps": jumps,
    }


def with_changes(scenario, **changes):
    """Copy of ``scenario`` with fields changed (a convenience for sweeps)."""
    return replace(scenario, **changes)
