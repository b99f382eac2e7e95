"""The kick plate's motion: the built-in profiles and tabulated plate motions, as the compiled model follows them.

A scenario's kick fields (:class:`whipple_kick.simulate.scenario.Scenario`) become one
:class:`Kick` (:func:`kick_of`): its duration, peak acceleration, signed
travel and start, and what the compiled model is given. The built-in
profiles are the thesis' constant acceleration (``constant``, 150 mm in
0.150 s, Dell'Orto 2025 Section 8.3) and a minimum-jerk quintic
(``smooth``); a table (``table``) is a CSV of the plate's displacement,
read through pandas (:func:`load_kick_table`) and followed as the clamped
cubic spline through its rows, one compiled-model segment per table
interval (:class:`KickTable`, :func:`cubic_segments`).
"""
from dataclasses import dataclass
import functools
import math
import pathlib
import re

import numpy as np
from scipy.interpolate import CubicSpline

from whipple_kick import fileio
from whipple_kick.errors import InputError, check_range

#: Kick-plate profiles the compiled model represents (its ``kick_profile`` parameter).
KICK_PROFILES = {"constant": 0, "smooth": 1}
#: Tabulated plate motion: a clamped cubic spline through ``kick_table``, one
#: compiled-model segment (``kick_profile`` 2) per table interval.
TABLE_PROFILE = "table"
#: Every ``Scenario.kick_profile`` value.
PROFILES = (*KICK_PROFILES, TABLE_PROFILE)
#: The compiled model's cubic-segment profile (y = c0 + c1 tau + c2 tau^2 + c3 tau^3).
SEGMENT_PROFILE = 2
#: Peak ``|acceleration|`` of each profile as a multiple of displacement/duration^2:
#: constant acceleration 2 D/T^2; minimum-jerk quintic 10/sqrt(3) D/T^2 (at s = 0.2113).
PEAK_ACCEL_FACTOR = {"constant": 2.0, "smooth": 10.0 / math.sqrt(3.0)}
DIRECTIONS = ("right", "left")
#: The thesis' plate travel [m] and travel time [s] (Section 8.3): the defaults.
DEFAULT_DISPLACEMENT = 0.150
DEFAULT_DURATION = 0.150
#: Plausibility caps of the kicks: plate travel [m] and peak ``|acceleration|`` [m/s^2] of the
#: built-in profiles (the measured plate peaks were 30-40 m/s^2, Dell'Orto 2025 Section 8.4);
#: peak ``|velocity|`` [m/s] is the most a built-in kick within both caps reaches (constant
#: profile: v = sqrt(a D)). A table is held to the travel and velocity caps, not to the
#: acceleration cap: the built-in constant profile itself stops the plate instantly, and a
#: table of it stops it within one row interval (6.9e3 m/s^2 at 1 kHz rows), so a plausible
#: table can exceed it. A table in mm read as metres exceeds the travel cap 1000-fold.
MAX_DISPLACEMENT = 1.0
MAX_ACCELERATION = 1000.0
MAX_VELOCITY = math.sqrt(MAX_ACCELERATION * MAX_DISPLACEMENT)
#: Units a kick table's header may give each column, as factors to s and m; no unit means s and m.
TABLE_UNITS = {"time": {"s": 1.0, "ms": 1e-3}, "y": {"m": 1.0, "mm": 1e-3}}


@dataclass(frozen=True)
class Kick:
    """The plate motion of one run.

    Attributes
    ----------
    profile : str
        One of :data:`PROFILES`.
    duration : float
        Time the plate moves [s] (a table: its time span).
    peak_acceleration : float
        Peak ``|plate acceleration|`` [m/s^2] (a table: the spline's).
    displacement : float
        Net plate travel [m], + to the right.
    start : float
        When the plate starts to move [s] on the run's clock (0, or a table's first time).
    table : KickTable or None
        The tabulated motion (``profile="table"`` only).
    """

    profile: str
    duration: float
    peak_acceleration: float
    displacement: float
    start: float = 0.0
    table: "KickTable | None" = None

    @property
    def stop(self) -> float:
        """When the plate stops [s]."""
        return self.start + self.duration

    def model_kick(self) -> dict:
        """The ``kick`` mapping of :func:`whipple_kick.model.slip.model_parameters` for the run's first piece.

        A table's first piece is the plate at rest at the table's first y
        (only the plate's velocity enters the tyre slip, so any y0 is steady).
        """
        if self.table is None:
            return {"t0": 0.0, "duration": self.duration, "displacement": self.displacement,
                    "profile": KICK_PROFILES[self.profile]}
        return {"profile": SEGMENT_PROFILE, "t0": self.start, "coefficients": (float(self.table.y[0]), 0.0, 0.0, 0.0)}

    def summary(self, direction: str) -> dict:
        """The ``kick`` section of a run's summary."""
        out = {"start_s": self.start, "duration_s": self.duration, "displacement_m": self.displacement,
               "peak_acceleration_m_s2": self.peak_acceleration, "profile": self.profile, "direction": direction}
        if self.table is not None:
            table = self.table
            out["table"] = {
                "file": table.name, "rows": int(table.times.size),
                "y_first_m": float(table.y[0]), "y_last_m": float(table.y[-1]),
                "peak_abs_y_m": float(np.max(np.abs(table.y))), "peak_velocity_m_s": table.peak_velocity,
                "spline": "clamped cubic (plate at rest at both ends; y, y', y'' continuous)"}
        return out


def kick_of(scenario) -> Kick:
    """The plate motion a scenario describes, checked.

    Parameters
    ----------
    scenario : whipple_kick.simulate.scenario.Scenario

    Returns
    -------
    Kick

    Raises
    ------
    InputError
        An unknown profile or direction, a value out of range, fields that
        conflict (duration and acceleration; a table and any other kick
        field), a bad table file, a kick longer than the run.

    Example
    -------
    >>> from whipple_kick.simulate.scenario import Scenario
    >>> kick = kick_of(Scenario())
    >>> kick.duration, round(kick.peak_acceleration, 3), kick.displacement
    (0.15, 13.333, 0.15)
    """
    if scenario.kick_direction not in DIRECTIONS:
        raise InputError(f"kick direction {scenario.kick_direction!r} is unknown; choose right or left")
    sign = 1.0 if scenario.kick_direction == "right" else -1.0
    if scenario.kick_profile == TABLE_PROFILE or scenario.kick_table is not None:
        table = _table_of(scenario, sign)
        return Kick(TABLE_PROFILE, table.duration, table.peak_acceleration, table.displacement,
                    start=float(table.times[0]), table=table)
    if scenario.kick_profile not in KICK_PROFILES:
        hint = ""
        if str(scenario.kick_profile).lower() in ("tabulated", "csv") or str(scenario.kick_profile).endswith(".csv"):
            hint = "; for a tabulated plate motion use kick_profile='table' with kick_table='FILE.csv'"
        raise InputError(f"kick profile {scenario.kick_profile!r} is unknown; choose one of "
                         f"{', '.join(PROFILES)}{hint}")
    disp = check_range("kick displacement", scenario.kick_displacement, 0.0, MAX_DISPLACEMENT, "m")
    factor = PEAK_ACCEL_FACTOR[scenario.kick_profile]
    if scenario.kick_duration is not None and scenario.kick_accel is not None:
        raise InputError("give the kick's duration (s) or its peak acceleration (m/s^2), not both")
    if scenario.kick_accel is not None:
        accel = check_range("kick peak acceleration", scenario.kick_accel, 0.0, MAX_ACCELERATION, "m/s^2",
                            low_open=True)
        if disp == 0.0:
            raise InputError("a kick acceleration needs a kick displacement > 0 m")
        dur = math.sqrt(factor * disp / accel)
    else:
        dur = DEFAULT_DURATION if scenario.kick_duration is None else scenario.kick_duration
        dur = check_range("kick duration", dur, 0.0, 10.0, "s", low_open=True)
        accel = factor * disp / dur**2
    if dur > scenario.duration:
        raise InputError(f"kick duration = {dur:g} s is longer than the run duration "
                         f"{scenario.duration:g} s; allowed (0, {scenario.duration:g}] s")
    return Kick(scenario.kick_profile, dur, accel, sign * disp)


def _table_of(scenario, sign):
    """The scenario's tabulated kick, checked against its other fields (see :func:`kick_of`)."""
    if scenario.kick_profile != TABLE_PROFILE:
        raise InputError(f"kick table {scenario.kick_table!r} needs kick_profile 'table', "
                         f"not {scenario.kick_profile!r}")
    if scenario.kick_table is None:
        raise InputError("kick profile 'table' needs a kick table: kick_table='FILE.csv' "
                         "with columns time (s) and y (m)")
    name = str(scenario.kick_table)
    # The table alone sets the plate motion; a second description of it is a mistake.
    for what, value, unit in (("kick duration", scenario.kick_duration, "s"),
                              ("kick peak acceleration", scenario.kick_accel, "m/s^2")):
        if value is not None:
            raise InputError(f"{what} = {value!r} {unit} conflicts with kick table {name!r} "
                             "(the table sets the plate motion)")
    if scenario.kick_displacement != DEFAULT_DISPLACEMENT:
        raise InputError(f"kick displacement = {scenario.kick_displacement!r} m conflicts with kick table "
                         f"{name!r} (the table sets the plate travel)")
    if not scenario.piecewise:
        raise InputError(f"piecewise = False is not possible with kick table {name!r}: "
                         "every table interval is integrated with its own parameters")
    times, y = load_kick_table(scenario.kick_table)
    if times[0] < -scenario.settle or times[-1] > scenario.duration:
        raise InputError(f"kick table {name!r} spans [{times[0]:g}, {times[-1]:g}] s, outside the run "
                         f"[-settle, duration] = [{-scenario.settle:g}, {scenario.duration:g}] s; times are "
                         "from the kick start: trim the table or change settle/duration")
    table = KickTable.from_points(name, times, sign * y)
    _check_table_caps(table)
    return table


def _check_table_caps(table):
    """Hold a tabulated kick to the built-in kicks' travel and velocity caps (a table in mm read as m fails here)."""
    travel = float(np.max(np.abs(table.y - table.y[0])))
    for what, value, cap, unit in (("plate travel from the first row", travel, MAX_DISPLACEMENT, "m"),
                                   ("peak plate velocity", table.peak_velocity, MAX_VELOCITY, "m/s")):
        if value > cap:
            raise InputError(f"kick table {table.name!r}: {what} = {value:.4g} {unit} is implausible; allowed "
                             f"[0, {cap:.4g}] {unit} (as the built-in kicks; give the units in the header, "
                             "e.g. 'time [ms]', 'y [mm]')")


# ------------------------------------------------------------ tabulated kick

def load_kick_table(path) -> tuple[np.ndarray, np.ndarray]:
    """Read a kick-plate table: (times [s], y [m]) as float arrays.

    The file is comma-separated text (UTF-8), read with ``pandas.read_csv``
    (:func:`whipple_kick.fileio.read_csv`); blank lines and ``#`` comments
    are skipped. With a header row, the columns named ``time`` and ``y``
    are used (case-insensitive; other columns are ignored), each with an
    optional unit in brackets or parentheses: ``time [s]`` or ``time [ms]``,
    ``y [m]`` or ``y [mm]`` (:data:`TABLE_UNITS`; no unit means s and m;
    any other unit is refused). Without a header, i.e. when the first row
    is all numbers, the file must have exactly two columns, time [s] then
    y [m]: a header-less file with more columns is ambiguous and refused.

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
        column, empty, non-numeric or non-finite entry with its line,
        non-increasing time, fewer than 2 rows, a unit other than s, ms,
        m, mm).
    """
    p = pathlib.Path(path)
    if not p.is_file():
        raise InputError(f"kick table {str(path)!r} {'is not a file' if p.exists() else 'does not exist'}")
    st = p.stat()
    # Cached by content identity: validating and running a scenario both read the table.
    times, y = _read_kick_table(str(p.resolve()), str(path), st.st_mtime_ns, st.st_size)
    return times.copy(), y.copy()


def _number(text):
    try:
        return float(text)
    except ValueError:
        return None


@functools.lru_cache(maxsize=16)
def _read_kick_table(resolved, name, mtime_ns, size):
    def fail(problem):
        raise InputError(f"kick table {name!r}: {problem}")

    frame = fileio.read_csv(resolved, "kick table", name=name, header=None, dtype=str, comment="#",
                            skip_blank_lines=True, keep_default_na=False, skipinitialspace=True)
    cells = [[str(c).strip() for c in row] for row in frame.to_numpy().tolist()]
    # The file line of each row pandas returns: the lines with something before a '#'.
    text = pathlib.Path(resolved).read_text(encoding="utf-8-sig")
    lines = [k + 1 for k, line in enumerate(text.splitlines()) if line.split("#", 1)[0].strip()]
    first = cells[0]
    if all(_number(c) is not None for c in first):
        if len(first) != 2:
            fail(f"line {lines[0]} has {len(first)} columns and no header; a file without header "
                 "must have exactly two columns, time (s) then y (m)")
        columns, rows, row_lines = {"time": 0, "y": 1}, cells, lines
        scale = {"time": 1.0, "y": 1.0}
    else:
        parsed = [re.fullmatch(r"(.*?)\s*(?:[\[(]([^\])]*)[\])])?", c) for c in first]
        names = [m.group(1).strip().lower() for m in parsed]
        columns, scale = {}, {}
        for want, allowed in TABLE_UNITS.items():
            hits = [i for i, n in enumerate(names) if n == want]
            if not hits:
                fail(f"has no column {want!r} (header: {', '.join(first)}); name the columns time (s) and y (m)")
            if len(hits) > 1:
                fail(f"has {len(hits)} columns named {want!r}")
            columns[want] = hits[0]
            unit = (parsed[hits[0]].group(2) or next(iter(allowed))).strip()
            if unit not in allowed:
                fail(f"column {first[hits[0]]!r} has unit {unit!r}; allowed: {', '.join(allowed)}")
            scale[want] = allowed[unit]
        rows, row_lines = cells[1:], lines[1:]
    values = np.empty((len(rows), 2))
    for k, (row, line) in enumerate(zip(rows, row_lines, strict=True)):
        for j, col in enumerate(("time", "y")):
            cell = row[columns[col]]
            v = _number(cell)
            if not cell:
                fail(f"line {line}: column {col} is empty")
            if v is None:
                fail(f"line {line}: {cell!r} in column {col} is not a number")
            if not math.isfinite(v):
                fail(f"line {line}: {col} = {cell} is not finite")
            values[k, j] = v
    if len(rows) < 2:
        fail(f"has {len(rows)} data row{'s' if len(rows) != 1 else ''}; at least 2 are needed")
    t, y = values[:, 0] * scale["time"], values[:, 1] * scale["y"]
    bad = np.flatnonzero(np.diff(t) <= 0.0)
    if bad.size:
        k = bad[0] + 1
        fail(f"line {row_lines[k]}: time {float(t[k])!r} s is not after the previous row's {float(t[k - 1])!r} s "
             "(times must increase strictly)")
    t.flags.writeable = False
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
        Clamped cubic spline, one cubic per table interval (:func:`cubic_segments`).
    """

    name: str
    times: np.ndarray
    y: np.ndarray
    segments: list

    @classmethod
    def from_points(cls, name, times, y):
        """Fit the spline through ``(times, y)``."""
        return cls(name, np.asarray(times, float), np.asarray(y, float), cubic_segments(times, y))

    @property
    def duration(self) -> float:
        """Time from the first to the last row [s]."""
        return float(self.times[-1] - self.times[0])

    @property
    def displacement(self) -> float:
        """Net plate travel y(last) - y(first) [m], signed."""
        return float(self.y[-1] - self.y[0])

    @property
    def peak_acceleration(self) -> float:
        """Peak ``|y''|`` of the spline [m/s^2].

        y'' = 2 c2 + 6 c3 tau is linear in each segment, so its extremes are
        at the segment ends.
        """
        return float(max(max(abs(2 * c[2]), abs(2 * c[2] + 6 * c[3] * (b - a))) for a, b, c in self.segments))

    @property
    def peak_velocity(self) -> float:
        """Peak ``|y'|`` of the spline [m/s] (from the roots of y'' in each segment)."""
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


def segment_parameters(params, t0, coefficients):
    """``params`` with the plate following one cubic from ``t0`` (everything else, e.g. T6c, kept)."""
    out = params.copy()   # the model's parameters keep their model (a plain mapping stays one)
    out["kick_profile"] = float(SEGMENT_PROFILE)
    out["kick_t0"] = float(t0)
    out.update({f"kick_c{i}": float(c) for i, c in enumerate(coefficients)})
    return out


def cubic_segments(times, displacements):
    """Cubic-spline segments through a tabulated plate displacement y(t).

    The spline is clamped (zero plate velocity at both ends, so the plate
    starts from rest and is held afterwards) and passes through every table
    point; y, y' and y'' are continuous.

    Parameters
    ----------
    times : array_like
        Strictly increasing times [s], at least 2.
    displacements : array_like
        Plate displacement [m] at those times (positive to the right).

    Returns
    -------
    list of (t_start, t_end, (c0, c1, c2, c3))
        One entry per table interval; ``kick=dict(profile=2, t0=t_start,
        coefficients=...)`` reproduces the segment.

    Example
    -------
    >>> [(a, b) for a, b, _ in cubic_segments([0.0, 0.1, 0.2], [0.0, 0.05, 0.15])]
    [(0.0, 0.1), (0.1, 0.2)]
    """
    t = np.asarray(times, dtype=float)
    y = np.asarray(displacements, dtype=float)
    if t.ndim != 1 or t.shape != y.shape or t.size < 2:
        raise InputError(f"a kick table needs matching time and displacement columns with at least 2 rows, "
                         f"got {t.size} times and {y.size} displacements")
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(y))):
        raise InputError("the kick table has non-finite entries")
    if np.any(np.diff(t) <= 0):
        raise InputError("kick table times must increase strictly (s)")
    spline = CubicSpline(t, y, bc_type="clamped")
    # CubicSpline stores c[m, k] for (x - t_k)^(3 - m).
    return [(float(t[k]), float(t[k + 1]), tuple(float(spline.c[3 - m, k]) for m in range(4)))
            for k in range(t.size - 1)]
