"""Animation of a kick-plate run: the bicycle, rider, plate, lane and tyre forces, frame by frame.

:func:`animate` turns a :class:`whipple_kick.simulate.results.Result` into a video
(``.mp4`` through ffmpeg, or ``.gif`` through Pillow when no video encoder
is installed):

* the bicycle's points and body orientations come from the model's own
  kinematics (:mod:`whipple_kick.model.geometry`, generated from
  :func:`whipple_kick.model.symbolic.derivation.kinematics`), evaluated at the run's
  coordinates; the wheels are discs in their planes with spokes turning
  with the wheel angles; the rider is drawn from the Yeadon segments in the
  posture the run seated it in (the summary's ``bicycle.rider_posture``), each
  segment on the body that carries it in the model (rear frame; the bar for
  forearms on it; the upper body leaning on the hip with ``rider_body =
  "leaning"``), or, for a preset whose rider is already lumped into the rear
  frame, as the rear frame's equivalent ellipsoid of inertia;
* the kick plate (500 x 500 mm, thesis Section 8.3) moves with the run's
  ``plate_y``; the lane follows the steady motion before the kick, so the
  distance between the bicycle and the lane's centre line is the kick's
  effect; a 2 m ground grid is fixed to the ground;
* arrows at the contacts: lateral tyre force (red) and normal load (grey)
  at one scale, 0.5 m per static rear load, so their ratio is the friction
  used; arcs for the self-aligning moments;
* the time, the playback speed, and roll, steer and yaw rate as numbers and
  as small traces with a cursor.

Rendering projects the 3D points in NumPy (perspective camera that follows
the bicycle) and draws 2D matplotlib artists updated in place over a saved
background (no artist is created per frame). docs/animation.md gives the
decisions and measured speed.
"""
import dataclasses
import functools
import itertools
import math
import pathlib
import subprocess
import time

import numpy as np
from scipy.ndimage import gaussian_filter1d

from whipple_kick.errors import InputError, check_range
from whipple_kick.library import bicycleparameters, riders
from whipple_kick.model import geometry, parts
from whipple_kick.simulate import assembly

from . import plotting

#: Trajectory columns the animation reads, by what they hold: the ONE place
#: to change when trajectory columns are renamed. q1..q10 are Moore's
#: coordinates (see :data:`whipple_kick.model.geometry.COORDINATES`).
COLUMNS = {
    "time": "time",
    "q1": "x_rear", "q2": "y_rear", "q3": "yaw", "q4": "roll", "q5": "frame_pitch",
    "q6": "rear_wheel_angle", "q7": "steer", "q8": "front_wheel_angle",
    "q9": "compression_rear", "q10": "compression_front",
    "velocity_x": "velocity_x_fixed", "velocity_y": "velocity_y_fixed",          # rear contact velocity along N.x, N.y [m/s]
    "yaw_rate": "yaw_rate", "roll_rate": "roll_rate", "steer_rate": "steer_rate",
    "fy_rear": "fy_rear", "fy_front": "fy_front",    # applied lateral tyre forces [N]
    "mz_rear": "mz_rear", "mz_front": "mz_front",    # applied self-aligning moments [N m]
    "fz_rear": "fz_rear", "fz_front": "fz_front",    # normal loads [N]
    "plate_y": "plate_y",                            # kick-plate displacement along N.y [m]
}

#: Kick plate as built: 500 mm x 500 mm (thesis Section 8.3, "Kickplate device").
PLATE_SIZE_M = (0.5, 0.5)
#: Drawn lane width [m] (a cycle lane; drawing only, not a model parameter).
LANE_WIDTH_M = 1.5
#: Arrow length [m] that stands for the static rear-tyre load.
FORCE_ARROW_M = 0.5
#: Sweep of a moment arc [rad] per N m of self-aligning moment (a quarter turn = 2 N m).
MOMENT_ARC_RAD_PER_NM = (math.pi / 2.0) / 2.0
#: Frame size [px] by format: a GIF (no video encoder) is kept smaller.
DEFAULT_SIZE = {"mp4": (1280, 720), "gif": (640, 360)}
#: Output arguments of every mp4 (H.264, playable everywhere); the speed benchmark uses the same.
FFMPEG_OUTPUT_ARGS = ("-pix_fmt", "yuv420p", "-preset", "superfast", "-crf", "23")

# Camera: behind and to the left of the bicycle, looking down a little.
_CAMERA_DISTANCE_M = 3.8
_CAMERA_AZIMUTH_RAD = math.radians(32.0)     # view heading turned right of the bicycle's
_CAMERA_ELEVATION_RAD = math.radians(17.0)
_CAMERA_FIELD_OF_VIEW_RAD = math.radians(42.0)   # vertical
_CAMERA_SMOOTHING_S = 0.4        # Gaussian smoothing of the followed position and heading
_NEAR_M = 0.3
_TARGET_AHEAD_M = 0.55           # the camera looks at the middle of the bicycle ...
_TARGET_HEIGHT_M = 0.75          # ... at about the rider's hip height

_WHEEL_VERTICES = 48
_GRID_SPACING_M = 2.0            # the ground grid: lines this far apart ...
_GRID_HALF_SIZE_M = 10.0         # ... in a square this far around a point ...
_GRID_AHEAD_M = 8.0              # ... this far ahead of the camera target (long thin lines are slow to draw)
# Directions whose support points outline a projected convex body (every 9 degrees).
_HULL_DIRECTIONS = np.c_[np.cos(np.linspace(0, 2 * np.pi, 40, endpoint=False)),
                         np.sin(np.linspace(0, 2 * np.pi, 40, endpoint=False))]


# ------------------------------------------------------------------- timeline

def frame_times(t_start, t_end, fps=30.0, slow_motion=1.0, slow_window=None):
    """Simulation times of the frames of a video played at ``fps``.

    Inside ``slow_window`` the video runs ``slow_motion`` times real time
    (0.2: five video seconds per simulated second); elsewhere it runs in
    real time. Frames are equally spaced in video time from ``t_start``; the
    last frame is at ``t_end`` exactly (the end of the run, or its fall).

    Parameters
    ----------
    t_start, t_end : float
        Span of the run to show [s].
    fps : float
        Frames per video second.
    slow_motion : float
        Playback speed inside the window (1 = real time).
    slow_window : (float, float), optional
        Simulated time span [s] played at ``slow_motion``; clipped to the run.

    Returns
    -------
    ndarray
        Increasing frame times [s].

    Example
    -------
    >>> len(frame_times(-0.5, 6.0, fps=30))     # 6.5 s in real time
    196
    >>> frame_times(0.0, 1.0, fps=10, slow_motion=0.5, slow_window=(0.0, 1.0))[:3]
    array([0.  , 0.05, 0.1 ])
    """
    if not t_end > t_start:
        raise InputError(f"the animation needs t_end > t_start, got [{t_start:g}, {t_end:g}] s")
    a, b = (t_start, t_start) if slow_window is None else (
        min(max(slow_window[0], t_start), t_end), min(max(slow_window[1], t_start), t_end))
    b = max(a, b)
    # Knots of the piecewise-linear map from video time to simulated time.
    sim = [t_start]
    video = [0.0]
    for end, rate in ((a, 1.0), (b, slow_motion), (t_end, 1.0)):
        if end > sim[-1]:
            video.append(video[-1] + (end - sim[-1]) / rate)
            sim.append(end)
    total = video[-1]
    count = int(math.floor(total * fps * (1.0 + 1e-12)))
    tau = np.arange(count + 1) / fps
    if total - tau[-1] > 1e-9 / fps:
        tau = np.append(tau, total)
    return np.interp(tau, video, sim)


# ---------------------------------------------------------------------- scene

def _stadium(radius, thickness, alignment, vertices_per_end=6):
    """Outline of a Yeadon stadium (two half circles joined by straight sides) in its plane."""
    half = np.linspace(-math.pi / 2, math.pi / 2, vertices_per_end)
    right = np.c_[thickness + radius * np.cos(half), radius * np.sin(half)]
    outline = np.r_[right, -right]
    return outline[:, ::-1] if alignment == "AP" else outline


# Yeadon segments split where one hull would hide the shape, by counts of
# stadium levels (two per stadium solid, four rings for the head's dome).
_SEGMENT_GROUPS = {
    "C": {"chest": 6, "head": 2 + 4},
    "A2": {"left forearm": 6, "left hand": 4},
    "B2": {"right forearm": 6, "right hand": 4},
    "J2": {"left shank": 6, "left foot": 6},
    "K2": {"right shank": 6, "right foot": 6},
}
#: Colour of each drawn part of the rider, by the part's name (Yeadon segment label or group).
_RIDER_COLOURS = {"P": "#3b3b48", "J1": "#3b3b48", "K1": "#3b3b48", "T": "#2f7fb8", "chest": "#2f7fb8",
                  "A1": "#2f7fb8", "B1": "#2f7fb8", "left forearm": "#e0b48c", "right forearm": "#e0b48c",
                  "head": "#e0b48c", "left hand": "#e0b48c", "right hand": "#e0b48c",
                  "left shank": "#e0b48c", "right shank": "#e0b48c", "left foot": "#222222",
                  "right foot": "#222222"}


def _yeadon_segments(human, seat, to_bike):
    """Mesh points of each Yeadon segment in the bicycle's benchmark frame: {segment label: {name: (m, 3)}}."""
    segments = {}
    for segment in human.segments:
        points = []
        rot = np.asarray(segment.rot_mat)      # a segment's solids share its orientation; z along the limb
        for solid in segment.solids:
            start = np.ravel(solid.pos)
            if hasattr(solid, "stads"):
                for level, stadium in zip((0.0, solid.height), solid.stads, strict=True):
                    flat = _stadium(stadium.radius, stadium.thickness, solid.alignment)
                    local = np.c_[flat, np.full(len(flat), level)]
                    points.append(start + local @ rot.T)
            else:   # the head's semi-ellipsoid: rings up to its apex
                for v in np.linspace(0.0, math.pi / 2, 4):
                    u = np.linspace(0.0, 2 * math.pi, 12, endpoint=False)
                    ring = np.c_[solid.radius * np.cos(v) * np.cos(u), solid.radius * np.cos(v) * np.sin(u),
                                 np.full(u.size, solid.height * np.sin(v))]
                    points.append(start + ring @ rot.T)
        label = segment.label.split(":")[0]
        groups = _SEGMENT_GROUPS.get(label, {label: len(points)})
        start = 0
        segments[label] = {}
        for name, count in groups.items():
            segments[label][name] = seat + np.vstack(points[start:start + count]) @ to_bike.T
            start += count
    return segments


def _model_parts(scenario):
    """The run's model's parts (:func:`whipple_kick.model.parts.selected`), in build order."""
    return parts.named([p.name for p in parts.selected(scenario)])


def _segment_frames(bicycle, scenario):
    """The frame that carries each Yeadon segment in the run's model: {segment label: "C", "E", "G" ...}.

    As :func:`whipple_kick.library.riders.split_rider` splits the rider for the model's parts (``bicycle`` the
    summary's section: its ``body`` is set when the rider was split): a segment a part of the model carries
    moves with the frame its split declares (``Split.moves_with``: the forearms and hands with the bar E when
    the arms are on it, the upper body in G, leaning on the hip, with the trunk part); the rest, and the
    segments of a part the model lacks that the rear frame holds, in the rear frame C. A rider not split is
    rigid in C.
    """
    if not bicycle.get("body"):
        return {}
    names = [p.name for p in _model_parts(scenario)]
    owner = riders.segment_carriers(names)
    return {label: part.split.moves_with if part is not None and part.name in names else "C"
            for label, part in owner.items()}


def _part_frames(scenario):
    """The model's parts that draw their segments in a frame of their own, by that frame (``"G"``: the trunk)."""
    return {p.split.moves_with: p for p in _model_parts(scenario) if p.pose is not None}


def _inertia_ellipsoid(mass, inertia, vertices=16):
    """Surface points of the uniform solid ellipsoid with this mass and inertia [m], about its centre.

    A uniform ellipsoid of semi-axes a, b, c has principal moments
    m (b^2 + c^2)/5 etc., so a^2 = 5 (I2 + I3 - I1) / (2 m).
    """
    moments, axes = np.linalg.eigh(inertia)
    sums = np.array([moments[1] + moments[2] - moments[0], moments[0] + moments[2] - moments[1],
                     moments[0] + moments[1] - moments[2]])
    semi = np.sqrt(np.maximum(sums, 0.0) * 5.0 / (2.0 * mass))
    u, v = np.meshgrid(np.linspace(0, 2 * math.pi, vertices, endpoint=False), np.linspace(-1.3, 1.3, 7))
    unit = np.c_[(np.cos(u) * np.cos(v)).ravel(), (np.sin(u) * np.cos(v)).ravel(), np.sin(v).ravel()]
    unit = np.r_[unit, [[0, 0, 1], [0, 0, -1]]]
    return (unit * semi) @ axes.T


@dataclasses.dataclass
class Body:
    """Points rigid in one body, given once: what the scene draws of the bicycle and rider.

    Attributes
    ----------
    frame : str
        Rear frame ``"C"`` (with the rider), front frame ``"E"``, or a part's own frame (``"G"``: the rider's
        upper body leaning on the hip, the trunk part's; :attr:`whipple_kick.model.parts.Part.pose`).
    lines : dict of str -> ndarray (m, 3)
        Polylines [m] in body axes from the body's wheel centre (a part's own frame: the rear frame's axes at
        the part's rest).
    solids : dict of str -> ndarray (m, 3)
        Point clouds [m] of convex bodies, drawn as the outline of their projection.
    """

    frame: str
    lines: dict
    solids: dict


def _bicycle_bodies(scenario, summary, params):
    """The rear body (frame lines and rider), the front body (fork, handlebar, the forearms on the bar) and the
    leaning upper body, in body axes.

    The rider is the one the run seated (``summary["bicycle"]["rider_posture"]``: the seating points, its
    fore-aft shift included, and the joint angles), not seated again here; the frame is the bicycle's own
    (the posture less the shift, which stands for a fit change: the saddle is drawn at the rider's seat).
    """
    bicycle = summary["bicycle"]
    posture = bicycle.get("rider_posture")
    to_c = functools.partial(geometry.benchmark_to_body, parameters=params, body="C")
    to_e = functools.partial(geometry.benchmark_to_body, parameters=params, body="E")
    d1, d2, d3 = params["d1"], params["d2"], params["d3"]
    axis_foot_e = np.array([-d3, 0.0, 0.0])          # on the steer axis, from the front wheel centre
    bodies = {frame: Body(frame, {}, {}) for frame in ("C", "E", *_part_frames(scenario))}
    rear_lines, front_lines = bodies["C"].lines, bodies["E"].lines
    if posture is not None:
        rider = riders.yeadon_rider(scenario.rider, mass_kg=bicycle["rider_mass_kg"])
        human = rider.human(dict(posture["configuration_rad"]))
        seat_pt, grip_left = np.array(posture["seat_m"]), np.array(posture["left_grip_m"])
        carriers = _segment_frames(bicycle, scenario)
        for label, named in _yeadon_segments(human, seat_pt, riders.YEADON_TO_BIKE).items():
            frame = carriers.get(label, "C")
            for name, pts in named.items():   # a part's own frame in the rear frame's axes at its rest
                bodies[frame].solids[name] = (to_e if frame == "E" else to_c)(pts)
        g = bicycleparameters.load_bicycle(scenario.bicycle, scenario.rider).geometry
        frame_shift = np.array([bicycle["rider_shift_m"], 0.0, 0.0])
        bb, seat = np.array(posture["bottom_bracket_m"]) - frame_shift, seat_pt - frame_shift
        grip_right = grip_left * np.array([1.0, -1.0, 1.0])
        bars = to_e(np.array([grip_left, 0.5 * (grip_left + grip_right), grip_right]))
        # Head-tube top: the point of the steer axis (E.z through the axis foot) nearest the bar centre.
        head_top_e = axis_foot_e + np.dot(bars[1] - axis_foot_e, [0, 0, 1.0]) * np.array([0, 0, 1.0])
        seat_tube_top = bb + g["lst"] * (seat - bb) / (g["lst"] + g["lsp"])
        bb, seat, top, saddle = (to_c(p) for p in (bb, seat, seat_tube_top, seat_pt))
        # The head tube is rigid in the rear frame: express its top in C (steer 0 at the nominal pose).
        # (The axis foot is d2 along C.z from the steer-axis point, which is d1 along C.x.)
        head_top_c = np.array([d1, 0.0, d2 + head_top_e[2]])
        rear_lines["frame"] = np.array([[0.0, 0.0, 0.0], bb, seat, saddle, seat, top, head_top_c, [d1, 0.0, 0.0],
                                        bb])
        rear_lines["seat stay"] = np.array([[0.0, 0.0, 0.0], top])
        front_lines["fork"] = np.array([[0.0, 0.0, 0.0], axis_foot_e, head_top_e, bars[1]])
        front_lines["handlebar"] = bars[[0, 2]]
    else:
        # Preset with the rider lumped into the rear frame: one body, its equivalent ellipsoid.
        inertia = np.array([[params["ic11"], 0.0, params["ic31"]], [0.0, params["ic22"], 0.0],
                            [params["ic31"], 0.0, params["ic33"]]])
        centre = np.array([params["l1"], 0.0, params["l2"]])
        bodies["C"].solids["rear frame and rider (lumped)"] = centre + _inertia_ellipsoid(params["mc"], inertia)
        head_top_e = axis_foot_e + np.array([0.0, 0.0, -(d2 + 0.25)])
        rear_lines["frame"] = np.array([[0.0, 0.0, 0.0], [d1, 0.0, 0.0], [d1, 0.0, -0.25]])
        front_lines["fork"] = np.array([[0.0, 0.0, 0.0], axis_foot_e, head_top_e])
    return [body for body in bodies.values() if body.lines or body.solids]


def _part_pose(result, times, part, rear_rotation, rear_origin):
    """Rotation (n, 3, 3) and origin (n, 3) of ``part``'s own frame at ``times`` (its declared ``pose``), from
    the run's body parameters and the part's states (its declared trajectory columns) at ``times``."""
    traj = result.trajectory
    t = traj["time"].to_numpy()
    states = {state: np.interp(times, t, traj[column].to_numpy()) for state, (column, _) in part.columns.items()}
    return part.pose(result.summary["bicycle"]["body"], states, rear_rotation, rear_origin)


def _model_parameters(result, tyres):
    """Moore's parameters of the run's bicycle with the tyres' crown radii, by name.

    With a seated rider the drawing takes only the bicycle's geometry from them (the rider is the summary's
    posture), so the bicycle's own set serves, without seating the rider again; a preset (rider lumped in)
    gives the rear frame's inertia the lumped drawing needs, low-inertia change included.
    """
    scenario = result.scenario
    if result.summary["bicycle"].get("rider_posture") is not None:
        moore = dict(bicycleparameters.load_bicycle(scenario.bicycle, scenario.rider).moore)
    else:
        moore, _, _ = assembly.build_bicycle(scenario.bicycle_spec)
    if tyres is None:
        if str(result.summary.get("tyres", {}).get("name", "")).startswith("custom"):
            raise InputError("this run used custom tyre objects: pass the same ones as tyres=(rear, front) "
                             "so the animation knows their crown radii (m)")
        rear, front, _ = assembly.build_tyres(scenario.tyre_spec)
    else:
        rear, front = tyres
    return dict(moore, rtr=rear.crown_radius, rtf=front.crown_radius)


def _sample(frame, times):
    """The :data:`COLUMNS` at ``times`` (linear interpolation of the 1 kHz trajectory)."""
    t = frame[COLUMNS["time"]].to_numpy()
    return {key: np.interp(times, t, frame[column].to_numpy()) for key, column in COLUMNS.items()}


def _steady_path(first, arc_lengths):
    """Rear-contact path [m] of the steady motion the run starts in, at arc lengths ``s`` [m].

    The steady motion turns at constant yaw rate with a constant velocity in
    the heading frame, so the contact runs on a circle (a line if the yaw
    rate is 0). Returns the points (n, 2) and the path's heading (n,) [rad].
    """
    vx, vy, yaw_rate = first["velocity_x"], first["velocity_y"], first["yaw_rate"]
    speed = math.hypot(vx, vy)
    heading0 = math.atan2(vy, vx)
    curvature = yaw_rate / speed
    s = np.asarray(arc_lengths, dtype=float)
    half = 0.5 * curvature * s
    chord = s * np.sinc(half / math.pi)      # 2 sin(k s / 2) / k, finite at k = 0
    mid = heading0 + half
    points = np.c_[first["q1"] + chord * np.cos(mid), first["q2"] + chord * np.sin(mid)]
    return points, heading0 + curvature * s


def _smooth(values, times, sigma_s):
    step = float(np.median(np.diff(times))) if times.size > 1 else 1.0
    return gaussian_filter1d(values, sigma_s / step, mode="nearest")


@dataclasses.dataclass
class Item:
    """One thing drawn, with its points at every frame (N frame, metres).

    Attributes
    ----------
    name : str
    kind : {"disc", "hull", "tube", "arrow", "arc", "axis"}
        disc: polygon in the given vertex order; hull: the convex hull of
        the projected points (a solid); tube: polyline drawn as quads of a
        perspective width; arrow: from point 0 to point 1; arc: polyline;
        axis: dashed line. Discs, hulls and tubes are depth-sorted together
        (painter's algorithm); arrows, arcs and the axis are drawn on top.
    points : ndarray, shape (n_frames, m, 3)
    color, edge : str or tuple
        Face (or line) colour and edge colour.
    width : float
        Tube radius [m]; arrow shaft width [image units]; disc edge and arc
        line width [px].
    follows : str, optional
        Name of the item this one is drawn right after (spokes after their disc).
    """

    name: str
    kind: str
    points: np.ndarray
    color: object
    edge: object = "none"
    width: float = 0.0
    follows: str = None


@dataclasses.dataclass
class Scene:
    """World-space content of every frame (N frame, metres), before projection."""

    times: np.ndarray
    samples: dict
    items: list                    # of Item
    camera_target: np.ndarray      # (n, 3)
    camera_heading: np.ndarray     # (n,) [rad]
    lane: dict                     # name -> (m, 3) polylines on the ground (NaN breaks the dashes)
    plate: np.ndarray              # (n, 4, 3) the kick plate's corners
    plate_pit: np.ndarray          # (4, 3) the area the plate moves in
    force_scale: float             # arrow length per force [m/N]


def grid_segments(centre, half_size=_GRID_HALF_SIZE_M, spacing=_GRID_SPACING_M):
    """Lines of the ground grid (fixed to the ground, every ``spacing`` [m]) within a square around ``centre``.

    Returns
    -------
    ndarray, shape (k, 2, 3)
        Straight segments [m] on the ground (z = 0).
    """
    cx, cy = float(centre[0]), float(centre[1])
    xs = np.arange(math.ceil((cx - half_size) / spacing), math.floor((cx + half_size) / spacing) + 1) * spacing
    ys = np.arange(math.ceil((cy - half_size) / spacing), math.floor((cy + half_size) / spacing) + 1) * spacing
    out = np.zeros((xs.size + ys.size, 2, 3))
    out[:xs.size, :, 0] = xs[:, None]
    out[:xs.size, :, 1] = [cy - half_size, cy + half_size]
    out[xs.size:, :, 1] = ys[:, None]
    out[xs.size:, :, 0] = [cx - half_size, cx + half_size]
    return out


def _rider_colour(name):
    part = name[2:]
    if part in ("frame", "seat stay"):
        return _STYLE["rear frame"]
    return _RIDER_COLOURS.get(part, _STYLE["lumped"])


def build_scene(result, times, tyres=None, moments=True):
    """Everything drawn at ``times`` [s], in the ground frame.

    Parameters
    ----------
    result : whipple_kick.simulate.results.Result
    times : array_like
        Frame times [s] within the run.
    tyres : (rear, front), optional
        The tyre objects of a run made with custom tyres.
    moments : bool
        Include the self-aligning moment arcs.

    Returns
    -------
    Scene
    """
    frame = result.trajectory
    times = np.asarray(times, dtype=float)
    samples = _sample(frame, times)
    params = _model_parameters(result, tyres)
    pose = geometry.evaluate({q: samples[q] for q in geometry.COORDINATES}, params)
    n = times.size
    items = []

    # Wheels: discs of the tyre's outer radius in the wheel plane, one
    # vertex at the lowest point; spokes turn with the wheel angle.
    angles = np.linspace(0.0, 2 * math.pi, _WHEEL_VERTICES, endpoint=False)
    cos, sin = np.cos(angles), np.sin(angles)
    for wheel, centre, radius, down, ahead, spin in (
            ("rear", "rear_wheel_centre", params["rr"], pose.frames["B"][:, :, 2], pose.frames["B"][:, :, 0], "D"),
            ("front", "front_wheel_centre", params["rf"], pose.directions["front_down"],
             pose.directions["front_heading"], "F")):
        c = pose.points[centre]
        rim = c[:, None, :] + radius * (cos[None, :, None] * down[:, None, :] + sin[None, :, None] * ahead[:, None, :])
        items.append(Item(f"{wheel} wheel", "disc", rim, _STYLE["disc"], _STYLE["tyre"], 2.6))
        spoke = pose.frames[spin]
        ends = []
        for k in range(3):
            a = k * math.pi / 3
            d = math.cos(a) * spoke[:, :, 0] + math.sin(a) * spoke[:, :, 2]
            ends += [c + 0.93 * radius * d, c - 0.93 * radius * d, np.full_like(c, np.nan)]
        items.append(Item(f"{wheel} spokes", "tube", np.stack(ends, axis=1), _STYLE["spokes"], width=0.0025,
                          follows=f"{wheel} wheel"))

    placed = {"C": (pose.frames["C"], pose.points["rear_wheel_centre"]),
              "E": (pose.frames["E"], pose.points["front_wheel_centre"])}
    own = _part_frames(result.scenario)
    for body in _bicycle_bodies(result.scenario, result.summary, params):
        if body.frame not in placed:   # a part's own frame ("G": the leaning upper body), as it declares
            placed[body.frame] = _part_pose(result, times, own[body.frame], *placed["C"])
        rot, origin = placed[body.frame]
        for name, pts in body.lines.items():
            world = origin[:, None, :] + np.einsum("nij,mj->nmi", rot, pts)
            colour = _STYLE["front frame"] if body.frame == "E" else _STYLE["rear frame"]
            items.append(Item(f"{body.frame} {name}", "tube", world, colour, width=0.014))
        for name, pts in body.solids.items():
            world = origin[:, None, :] + np.einsum("nij,mj->nmi", rot, pts)
            items.append(Item(f"{body.frame} {name}", "hull", world, _rider_colour(f"C {name}"), "#5a4a3c", 0.5))
    # Steer axis: through the steer-axis point along C.z, from near the ground to above the head tube.
    axis = pose.frames["C"][:, :, 2]
    point = pose.points["steer_axis_point"]
    items.append(Item("steer axis", "axis", np.stack([point - 0.45 * axis, point + 0.5 * axis], axis=1),
                      _STYLE["axis"]))

    # Forces at the contacts: lateral force along the wheel's lateral
    # direction and normal load up, at one scale (FORCE_ARROW_M per static rear load).
    static_rear = float(result.summary["bicycle"]["static_load_rear_n"])
    scale = FORCE_ARROW_M / static_rear
    up = -pose.frames["A"][:, :, 2]
    for wheel, contact, lateral, heading in (
            ("rear", "rear_contact", pose.frames["A"][:, :, 1], pose.frames["A"][:, :, 0]),
            ("front", "front_contact", pose.directions["front_lateral"], pose.directions["front_heading"])):
        p = pose.points[contact]
        items.append(Item(f"{wheel} load", "arrow", np.stack([p, p + scale * samples[f"fz_{wheel}"][:, None] * up],
                                                             axis=1), _STYLE["load"], width=0.009))
        items.append(Item(f"{wheel} lateral force", "arrow",
                          np.stack([p, p + scale * samples[f"fy_{wheel}"][:, None] * lateral], axis=1),
                          _STYLE["force"], width=0.014))
        if moments:
            # z is down, so a positive moment about the downward normal turns the heading toward the right.
            phi = np.linspace(0.0, 1.0, 16)[None, :] * (MOMENT_ARC_RAD_PER_NM * samples[f"mz_{wheel}"])[:, None]
            arc = p[:, None, :] + 0.16 * (np.cos(phi)[:, :, None] * heading[:, None, :]
                                          + np.sin(phi)[:, :, None] * lateral[:, None, :])
            items.append(Item(f"{wheel} aligning moment", "arc", arc, _STYLE["moment"], width=2.0))

    # Ground: the plate (moving along N.y), the pit it moves in, the lane and a grid.
    t_all = frame[COLUMNS["time"]].to_numpy()
    kick = result.summary["kick"]
    k0, k1 = kick["start_s"], kick["start_s"] + kick["duration_s"]
    x_kick = np.interp([k0, k1], t_all, frame[COLUMNS["q1"]].to_numpy())
    y_kick = float(np.interp(k0, t_all, frame[COLUMNS["q2"]].to_numpy()))
    plate_y = frame[COLUMNS["plate_y"]].to_numpy()
    plate_rest = float(np.interp(k0, t_all, plate_y))
    travel = float(x_kick[1] - x_kick[0])
    length = max(PLATE_SIZE_M[0], abs(travel) + 0.1)  # the model keeps the wheel on the plate for the whole kick
    x0 = 0.5 * (x_kick[0] + x_kick[1]) - 0.5 * length
    width = PLATE_SIZE_M[1]
    corners = np.array([[0, -0.5], [1, -0.5], [1, 0.5], [0, 0.5]]) * [length, width] + [x0, y_kick]
    plate = np.zeros((n, 4, 3))
    plate[:, :, :2] = corners
    plate[:, :, 1] += (samples["plate_y"] - plate_rest)[:, None]
    low, high = float(np.min(plate_y - plate_rest)), float(np.max(plate_y - plate_rest))
    pit = np.zeros((4, 3))
    pit[:, :2] = np.array([[x0, y_kick - 0.5 * width + low], [x0 + length, y_kick - 0.5 * width + low],
                           [x0 + length, y_kick + 0.5 * width + high], [x0, y_kick + 0.5 * width + high]])

    first = {key: values[0] for key, values in _sample(frame, t_all[:1]).items()}
    span = math.hypot(first["velocity_x"], first["velocity_y"]) * (t_all[-1] - t_all[0])
    s = np.arange(-8.0, span + 30.0, 0.25)
    centre, heading = _steady_path(first, s)
    normal = np.c_[-np.sin(heading), np.cos(heading)]
    lane = {}
    for name, shift in (("left edge", -0.5 * LANE_WIDTH_M), ("right edge", 0.5 * LANE_WIDTH_M)):
        lane[name] = np.c_[centre + shift * normal, np.zeros(s.size)]
    centre_line = np.c_[centre, np.zeros(s.size)]
    centre_line[np.floor(s / 0.5) % 2 == 1] = np.nan      # 0.5 m dashes, 0.5 m gaps
    lane["centre"] = centre_line

    xy = np.c_[frame[COLUMNS["q1"]].to_numpy(), frame[COLUMNS["q2"]].to_numpy()]

    # The camera follows the rear contact and the heading, smoothed so that
    # the kick's quick motions show against the frame.
    yaw_sm = np.interp(times, t_all, _smooth(frame[COLUMNS["q3"]].to_numpy(), t_all, _CAMERA_SMOOTHING_S))
    x_sm = np.interp(times, t_all, _smooth(xy[:, 0], t_all, _CAMERA_SMOOTHING_S))
    y_sm = np.interp(times, t_all, _smooth(xy[:, 1], t_all, _CAMERA_SMOOTHING_S))
    target = np.c_[x_sm + _TARGET_AHEAD_M * np.cos(yaw_sm), y_sm + _TARGET_AHEAD_M * np.sin(yaw_sm),
                   np.full(n, -_TARGET_HEIGHT_M)]
    return Scene(times=times, samples=samples, items=items, camera_target=target, camera_heading=yaw_sm,
                 lane=lane, plate=plate, plate_pit=pit,
                 force_scale=scale)


# --------------------------------------------------------------------- camera

class Camera:
    """Perspective camera per frame: image x to the right, y up, in units of the focal length.

    Parameters
    ----------
    target : ndarray (n, 3)
        Point looked at [m] (N frame, z down).
    heading : ndarray (n,)
        Heading [rad] the view is turned from (the bicycle's, smoothed).
    """

    def __init__(self, target, heading, distance=_CAMERA_DISTANCE_M, azimuth=_CAMERA_AZIMUTH_RAD,
                 elevation=_CAMERA_ELEVATION_RAD, field_of_view=_CAMERA_FIELD_OF_VIEW_RAD):
        view = np.asarray(heading) + azimuth
        ce, se = math.cos(elevation), math.sin(elevation)
        horizontal = np.c_[np.cos(view), np.sin(view), np.zeros(view.size)]
        down = np.array([0.0, 0.0, 1.0])
        forward = ce * horizontal + se * down
        right = np.c_[-np.sin(view), np.cos(view), np.zeros(view.size)]
        upward = se * horizontal - ce * down
        self.rows = np.stack([right, upward, forward], axis=1)     # (n, 3, 3): camera axes in N
        self.eye = np.asarray(target) - distance * forward
        self.focal = 1.0 / math.tan(0.5 * field_of_view)
        #: Image height of the horizon (every horizontal direction projects to it).
        self.horizon = self.focal * math.tan(elevation)

    def to_camera(self, k, points):
        """Camera-axis components (right, up, depth) of ``points`` (..., 3) at frame ``k``."""
        return (np.asarray(points) - self.eye[k]) @ self.rows[k].T

    def project(self, k, points):
        """Image points (..., 2) and depths (...) of ``points`` at frame ``k``; NaN behind the near plane."""
        c = self.to_camera(k, points)
        depth = c[..., 2]
        with np.errstate(invalid="ignore", divide="ignore"):
            xy = self.focal * c[..., :2] / np.where(depth > _NEAR_M, depth, np.nan)[..., None]
        return xy, depth

    def project_segments(self, k, segments):
        """Image segments (s, 2, 2) of straight 3D segments (s, 2, 3), clipped at the near plane."""
        c = self.to_camera(k, segments)
        a, b = c[:, 0], c[:, 1]
        za, zb = a[:, 2:3], b[:, 2:3]
        keep = (za[:, 0] > _NEAR_M) | (zb[:, 0] > _NEAR_M)
        with np.errstate(invalid="ignore", divide="ignore"):
            f = np.clip((_NEAR_M - za) / (zb - za), 0.0, 1.0)
        cut = a + f * (b - a)
        a = np.where(za > _NEAR_M, a, cut)[keep]
        b = np.where(zb > _NEAR_M, b, cut)[keep]
        return self.focal * np.stack([a[:, :2] / a[:, 2:3], b[:, :2] / b[:, 2:3]], axis=1)


def _arrow(xy, width):
    """Outline of a 2D arrow from xy[0] to xy[1] (image units), head proportional, capped."""
    p0, p1 = xy
    d = p1 - p0
    length = float(np.hypot(*d))
    if not np.isfinite(length) or length < 1e-6:
        return np.full((1, 2), np.nan)
    u = d / length
    n = np.array([-u[1], u[0]])
    head = min(0.35 * length, 6.0 * width)
    neck = p1 - head * u
    w = 0.5 * width
    return np.array([p0 + w * n, neck + w * n, neck + 2.2 * w * n, p1, neck - 2.2 * w * n, neck - w * n, p0 - w * n])


# ------------------------------------------------------------------ rendering

_STYLE = {
    "sky": "#dfe9f1", "ground": "#cfd6c4", "grid": "#b9c1ad", "asphalt": "#8c8f93", "lane": "white",
    "pit": "#555555", "plate": "#c9a66b", "tyre": "#1b1b1b", "disc": (0.85, 0.85, 0.85, 0.75),
    "spokes": "#7a7a7a", "rear frame": "#1f4e99", "front frame": "#d9822b", "axis": "#444444",
    "lumped": (0.56, 0.66, 0.78, 0.6), "force": "#d62728", "load": "#5f5f5f", "moment": "#9467bd",
}


class _PixelText:
    """A line or two of text written straight into the canvas pixels with Pillow.

    Matplotlib lays out every string afresh (about 3 ms per string and
    frame here); Pillow draws the same few characters in about 0.1 ms. Used
    only where the figure's background is plain white (the right column), so
    the text is drawn on a white box of the size of ``template``.
    """

    def __init__(self, canvas_size, anchor, template, size_pt, dpi, color, bold=True, align="left"):
        from matplotlib import font_manager
        from matplotlib.colors import to_rgba
        from PIL import Image, ImageDraw, ImageFont

        path = font_manager.findfont(font_manager.FontProperties(family="DejaVu Sans",
                                                                 weight="bold" if bold else "normal"))
        self.font = ImageFont.truetype(path, max(6, round(size_pt * dpi / 72.0)))
        self.Image, self.ImageDraw = Image, ImageDraw
        box = ImageDraw.Draw(Image.new("RGBA", (4, 4))).multiline_textbbox((0, 0), template, font=self.font)
        self.size = (box[2] + 4, box[3] + 4)
        width, height = canvas_size
        x, y = anchor[0] * width, (1.0 - anchor[1]) * height     # figure fraction, from the bottom left
        self.x0 = int(round(x - self.size[0])) if align == "right" else int(round(x))
        self.y0 = int(round(y))
        self.x0 = min(max(self.x0, 0), width - self.size[0])
        self.y0 = min(max(self.y0, 0), height - self.size[1])
        self.align = align
        self.color = tuple(int(round(255 * c)) for c in to_rgba(color))

    def draw(self, pixels, text):
        """Write ``text`` into ``pixels`` (the canvas' RGBA array, rows from the top)."""
        image = self.Image.new("RGBA", self.size, (255, 255, 255, 255))
        x = self.size[0] - 2 if self.align == "right" else 0
        self.ImageDraw.Draw(image).multiline_text((x, 0), text, font=self.font, fill=self.color,
                                                  anchor="ra" if self.align == "right" else "la",
                                                  align=self.align)
        pixels[self.y0:self.y0 + self.size[1], self.x0:self.x0 + self.size[0]] = np.asarray(image)


class _PixelCursor:
    """A vertical line at the current time and a dot at the current value, written into a trace's pixels."""

    def __init__(self, axes, height, color=(214, 39, 40, 255), radius=2.5):
        box = axes.bbox                                    # display pixels, from the bottom left
        self.to_pixels = axes.transData
        self.columns = (int(math.ceil(box.x0)), int(math.floor(box.x1)))
        self.rows = (int(math.ceil(height - box.y1)), int(math.floor(height - box.y0)))
        self.height, self.color = height, np.array(color, dtype=np.uint8)
        r = int(math.ceil(radius))
        dy, dx = np.mgrid[-r:r + 1, -r:r + 1]
        inside = dx * dx + dy * dy <= radius * radius
        self.dot = (dy[inside], dx[inside])

    def draw(self, pixels, t, y):
        x_px, y_px = self.to_pixels.transform((t, y))
        col = int(round(x_px))
        (c0, c1), (r0, r1) = self.columns, self.rows
        if c0 <= col < c1:
            pixels[r0:r1, col] = self.color
        rows, cols = int(round(self.height - y_px)) + self.dot[0], col + self.dot[1]
        keep = (rows >= r0) & (rows < r1) & (cols >= c0) & (cols < c1)
        pixels[rows[keep], cols[keep]] = self.color


class _Frames:
    """The figure and its artists, drawn frame by frame over a saved background.

    Per frame: the ground grid, the ground polygons (lane, pit, plate), the
    lane lines, every disc, hull and tube depth-sorted in ONE polygon
    collection, the overlays (arrows, arcs, steer axis), the clock and the
    trace cursors. Nothing is created per frame.
    """

    def __init__(self, result, scene, camera, size, dpi, playback_label, fall_time):
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.collections import LineCollection, PolyCollection
        from matplotlib.colors import to_rgba
        from matplotlib.figure import Figure
        from matplotlib.patches import Polygon


        width, height = size
        self.fig = Figure(figsize=(width / dpi, height / dpi), dpi=dpi, facecolor="white")
        self.canvas = FigureCanvasAgg(self.fig)
        self.scene, self.camera = scene, camera
        self.playback_label, self.fall_time = playback_label, fall_time
        aspect = 0.70 * width / height
        ax = self.fig.add_axes((0.0, 0.0, 0.70, 1.0))
        ax.set_xlim(-aspect, aspect)
        ax.set_ylim(-1.0, 1.0)
        ax.set_axis_off()
        ax.add_patch(Polygon([[-aspect, -1], [aspect, -1], [aspect, 1], [-aspect, 1]], color=_STYLE["sky"], zorder=0))
        ax.add_patch(Polygon([[-aspect, -1], [aspect, -1], [aspect, camera.horizon], [-aspect, camera.horizon]],
                             color=_STYLE["ground"], zorder=0))
        self.ax = ax

        def add(artist):
            artist.set_animated(True)
            return artist

        self.grid = add(ax.add_collection(LineCollection([], colors=_STYLE["grid"], linewidths=0.6)))
        self.ground = add(ax.add_collection(PolyCollection(
            [], facecolors=[_STYLE["asphalt"], _STYLE["pit"], _STYLE["plate"]],
            edgecolors=["none", "none", "#6b5a3a"], linewidths=[0, 0, 0.8])))
        self.lane = add(ax.add_collection(LineCollection([], colors=_STYLE["lane"], linewidths=[1.6, 1.6, 1.2])))
        self.solids = add(ax.add_collection(PolyCollection([])))
        self.axis = add(ax.plot([], [], color=_STYLE["axis"], lw=0.9, ls="--")[0])
        arrows = [item for item in scene.items if item.kind == "arrow"]
        self.arrows = add(ax.add_collection(PolyCollection([], facecolors=[item.color for item in arrows],
                                                           alpha=0.9, linewidths=0)))
        arcs = [item for item in scene.items if item.kind == "arc"]
        self.arcs = add(ax.add_collection(LineCollection([], colors=[item.color for item in arcs],
                                                         linewidths=[item.width for item in arcs])))
        self.status = add(ax.text(0.5, 0.05, "", fontsize=17, weight="bold", color="#b00000",
                                  transform=ax.transAxes, ha="center", va="bottom"))
        self._index_solids(to_rgba)

        self.fig.text(0.005, 0.995, plotting.result_title(result).replace("$^2$", "²"), fontsize=7, va="top",
                      color="#333333")
        legend = (f"Arrows at the tyre contacts, {FORCE_ARROW_M:g} m = "
                  f"{result.summary['bicycle']['static_load_rear_n']:.0f} N\n(the static rear load): "
                  "red lateral force,\ngrey normal load")
        if arcs:
            legend += f"; purple arcs: aligning\nmoment, a quarter turn = {(math.pi / 2) / MOMENT_ARC_RAD_PER_NM:g} N m"
        legend += f"\nLane: the steady path before the kick\n({LANE_WIDTH_M:g} m wide); ground grid {_GRID_SPACING_M:g} m"
        if any("lumped" in item.name for item in scene.items):
            legend += "\nEllipsoid: rear frame and rider lumped\n(uniform, same mass and inertia)"
        self.fig.text(0.765, 0.015, legend, fontsize=7, color="#222222", va="bottom", linespacing=1.25)
        self.clock = _PixelText(size, (0.765, 0.965), "t = -00.000 s\nslow motion 0.25x\nplate moving", 11, dpi,
                                "black")

        # Small traces on the right with a cursor and the current value.
        frame = result.trajectory
        t = frame[COLUMNS["time"]].to_numpy()
        kick = result.summary["kick"]
        fall_roll = math.radians(result.scenario.fall_angle_deg)
        steer_deg = getattr(result.scenario, "steer_limit_deg", None)
        steer_limit = None if steer_deg is None else math.radians(steer_deg)
        self.traces = []
        panels = (("roll_rate", "roll rate [rad/s]"), ("steer_rate", "steer rate [rad/s]"),
                  ("yaw_rate", "yaw rate [rad/s]"))
        for k, (key, label) in enumerate(panels):
            bounds = (0.765, 0.66 - 0.2 * k, 0.225, 0.14)
            tax = self.fig.add_axes(bounds)
            y = frame[COLUMNS[key]].to_numpy()
            tax.plot(t, y, color="#1f77b4", lw=0.9)
            tax.axvspan(kick["start_s"], kick["start_s"] + kick["duration_s"], color="0.85", zorder=0)
            # The part of the run animated (a still shows the whole run).
            shown = (float(scene.times[0]), float(scene.times[-1])) if scene.times.size > 1 else (t[0], t[-1])
            tax.set_ylim(*plotting.motion_limits(t, y, frame[COLUMNS["q4"]].to_numpy(), fall_roll, shown,
                                                 frame[COLUMNS["q7"]].to_numpy(), steer_limit))
            tax.set_xlim(*shown)
            tax.set_title(label, fontsize=8, loc="left")
            tax.tick_params(labelsize=7)
            tax.grid(True, lw=0.3, alpha=0.6)
            if k == len(panels) - 1:
                tax.set_xlabel("time from kick start [s]", fontsize=7)
            value = _PixelText(size, (bounds[0] + bounds[2], bounds[1] + bounds[3] + 0.035), "-00.000", 8, dpi,
                               "#d62728", align="right")
            self.traces.append((key, tax, value))
        self.canvas.draw()
        self.background = self.canvas.copy_from_bbox(self.fig.bbox)
        # The cursors are written into the pixels (a line artist costs 0.5 ms to draw, this 20 us).
        self.cursors = [(key, _PixelCursor(tax, height), value) for key, tax, value in self.traces]

    def _index_solids(self, to_rgba):
        """Stack the points of every disc, hull and tube so one projection per frame serves them all."""
        solids = [item for item in self.scene.items if item.kind in ("disc", "hull", "tube")]
        sizes = [item.points.shape[1] for item in solids]
        starts = np.cumsum([0] + sizes)
        self.solid_points = np.concatenate([item.points for item in solids], axis=1)
        self.solid_items = solids
        self.solid_slices = [slice(a, b) for a, b in itertools.pairwise(starts)]
        # Hulls: point indices padded to one length (the padding repeats a point of the same item).
        hulls = [i for i, item in enumerate(solids) if item.kind == "hull"]
        width = max([sizes[i] for i in hulls], default=1)
        self.hull_items = np.array(hulls, dtype=int)
        self.hull_index = np.array([np.resize(np.arange(starts[i], starts[i + 1]), width) for i in hulls],
                                   dtype=int).reshape(len(hulls), width)
        self.discs = [i for i, item in enumerate(solids) if item.kind == "disc"]
        segments = [(starts[i] + j, i) for i, item in enumerate(solids) if item.kind == "tube"
                    for j in range(item.points.shape[1] - 1)]
        self.tube_start = np.array([a for a, _ in segments], dtype=int)
        self.tube_item = np.array([i for _, i in segments], dtype=int)
        self.tube_radius = np.array([solids[i].width for i in self.tube_item])
        self.face = np.array([to_rgba(item.color) for item in solids])
        self.edge = np.array([to_rgba(item.edge) for item in solids])
        self.edge_width = np.array([0.0 if item.kind == "tube" else item.width for item in solids])
        names = [item.name for item in solids]
        self.follows = np.array([names.index(item.follows) if item.follows else -1 for item in solids])

    def _ground(self, k):
        scene, cam = self.scene, self.camera
        edges = [cam.project(k, scene.lane[name])[0] for name in ("left edge", "right edge")]
        both = np.all(np.isfinite(edges[0]), axis=1) & np.all(np.isfinite(edges[1]), axis=1)
        asphalt = np.r_[edges[0][both], edges[1][both][::-1]] if both.any() else np.zeros((1, 2))
        self.ground.set_verts([asphalt, cam.project(k, scene.plate_pit)[0], cam.project(k, scene.plate[k])[0]])
        heading = scene.camera_heading[k] + _CAMERA_AZIMUTH_RAD
        centre = scene.camera_target[k, :2] + _GRID_AHEAD_M * np.array([math.cos(heading), math.sin(heading)])
        self.grid.set_segments(cam.project_segments(k, grid_segments(centre)))
        self.lane.set_segments([cam.project(k, scene.lane[name])[0] for name in ("left edge", "right edge", "centre")])

    def _solids(self, k):
        """Every disc, hull and tube of frame ``k`` in one collection, far to near (painter's algorithm)."""
        cam = self.camera
        xy, depth = cam.project(k, self.solid_points[k])
        # Solids: outlines of the convex bodies from their support points in _HULL_DIRECTIONS.
        pts = xy[self.hull_index]                                          # (hulls, m, 2)
        support = np.argmax(np.nan_to_num(pts @ _HULL_DIRECTIONS.T, nan=-np.inf), axis=1)   # (hulls, K)
        hulls = np.take_along_axis(pts, support[:, :, None], axis=1)
        verts = list(hulls) + [xy[self.solid_slices[i]] for i in self.discs]
        owner = list(self.hull_items) + self.discs
        depths = [np.nanmean(depth[self.hull_index], axis=1), [np.nanmean(depth[self.solid_slices[i]])
                                                               for i in self.discs]]
        item_depth = np.full(len(self.solid_items), np.nan)
        item_depth[owner] = np.concatenate(depths)
        # Tubes: one quad per segment with a perspective width.
        a, b = xy[self.tube_start], xy[self.tube_start + 1]
        za, zb = depth[self.tube_start], depth[self.tube_start + 1]
        ok = np.all(np.isfinite(a), axis=1) & np.all(np.isfinite(b), axis=1)
        d = b - a
        normal = np.c_[-d[:, 1], d[:, 0]] / np.maximum(np.hypot(d[:, 0], d[:, 1]), 1e-12)[:, None]
        with np.errstate(invalid="ignore", divide="ignore"):
            wa = (cam.focal * self.tube_radius / za)[:, None] * normal
            wb = (cam.focal * self.tube_radius / zb)[:, None] * normal
        quads = np.stack([a + wa, b + wb, b - wb, a - wa], axis=1)[ok]
        tube_owner = self.tube_item[ok]
        followed = self.follows[tube_owner]
        # Spokes are drawn right after their wheel's disc.
        tube_depth = np.where(followed >= 0, item_depth[followed] - 1e-6, 0.5 * (za + zb)[ok])
        verts += list(quads)
        owner = np.r_[np.asarray(owner, dtype=int), tube_owner]
        order = np.argsort(-np.r_[item_depth[owner[:len(owner) - len(quads)]], tube_depth], kind="stable")
        owner = owner[order]
        self.solids.set_verts([verts[i] for i in order])
        self.solids.set_facecolor(self.face[owner])
        self.solids.set_edgecolor(self.edge[owner])
        self.solids.set_linewidth(self.edge_width[owner])

    def _overlays(self, k):
        cam = self.camera
        arrows, arcs = [], []
        for item in self.scene.items:
            if item.kind == "arrow":
                arrows.append(_arrow(cam.project(k, item.points[k])[0], item.width))
            elif item.kind == "arc":
                arcs.append(cam.project(k, item.points[k])[0])
            elif item.kind == "axis":
                self.axis.set_data(*cam.project(k, item.points[k])[0].T)
        self.arrows.set_verts(arrows)
        self.arcs.set_segments(arcs)

    def render(self, k):
        """Draw frame ``k``; returns the figure's RGBA pixels (height, width, 4), a view of the canvas."""
        self.canvas.restore_region(self.background)
        self._ground(k)
        self._solids(k)
        self._overlays(k)
        for artist in (self.grid, self.ground, self.lane, self.solids, self.axis, self.arrows, self.arcs):
            self.ax.draw_artist(artist)
        t = self.scene.times[k]
        if self.fall_time is not None and k == self.scene.times.size - 1:
            self.status.set_text(f"fell at {self.fall_time:.3f} s")
            self.ax.draw_artist(self.status)
        pixels = np.asarray(self.canvas.buffer_rgba())
        self.clock.draw(pixels, f"t = {t:.3f} s\n{self.playback_label(t)}")
        for key, cursor, value in self.cursors:
            y = self.scene.samples[key][k]
            cursor.draw(pixels, t, y)
            value.draw(pixels, f"{y:+.3f}")
        return pixels


# -------------------------------------------------------------------- writers

@functools.cache
def video_encoder():
    """Path of the ffmpeg executable the ``video`` extra's imageio-ffmpeg uses, or None without it.

    imageio-ffmpeg ships an ffmpeg (``IMAGEIO_FFMPEG_EXE`` points it at
    another, e.g. the system's) and writes the frames through it
    (:func:`imageio_ffmpeg.write_frames`), so an ``ffmpeg`` on PATH alone is
    not enough: without the extra, animations are GIFs.
    """
    try:
        import imageio_ffmpeg
        return imageio_ffmpeg.get_ffmpeg_exe()
    except (ImportError, RuntimeError):
        return None


@functools.cache
def _h264_codec(exe):
    """libx264 when this ffmpeg has it, else its built-in MPEG-4 part 2 encoder."""
    listing = subprocess.run([exe, "-hide_banner", "-encoders"], capture_output=True, text=True).stdout
    return "libx264" if " libx264 " in listing else "mpeg4"


class _FfmpegWriter:
    """RGBA frames encoded as H.264 mp4 by ffmpeg, through :func:`imageio_ffmpeg.write_frames`."""

    def __init__(self, path, size, fps):
        exe = video_encoder()
        if exe is None:
            raise InputError(f"cannot write {path}: no video encoder; install the 'video' extra "
                             "(pip install 'whipple_kick[video]') or write a .gif")
        import imageio_ffmpeg
        codec = _h264_codec(exe)
        # write_frames sets the input format, the codec and -pix_fmt; the rest of the output options are ours.
        options = list(FFMPEG_OUTPUT_ARGS[2:]) if codec == "libx264" else ["-q:v", "4"]
        self._frames = imageio_ffmpeg.write_frames(
            str(path), tuple(size), pix_fmt_in="rgba", pix_fmt_out="yuv420p", fps=float(fps), codec=codec,
            quality=None, macro_block_size=1, ffmpeg_log_level="error", output_params=options)
        self._frames.send(None)   # starts ffmpeg

    def write(self, rgba):
        self._frames.send(np.ascontiguousarray(rgba))

    def close(self):
        self._frames.close()   # ends the input, waits for ffmpeg; raises with its message if it failed


class _GifWriter:
    """Frames quantised to 256 colours as they come; written by Pillow at the end."""

    def __init__(self, path, size, fps):
        self.path, self.size, self.fps = path, size, fps
        self.frames = []

    def write(self, rgba):
        from PIL import Image

        image = Image.fromarray(rgba[..., :3])
        # Fast octree: about 2 ms a frame at 640 x 360 against 21 ms for median cut, for a similar picture.
        self.frames.append(image.quantize(colors=128, method=Image.Quantize.FASTOCTREE, dither=Image.Dither.NONE))

    def close(self):
        # GIF delays are whole centiseconds: round the frame times, not each delay, so the mean rate is kept.
        k = np.arange(len(self.frames) + 1)
        delays = np.diff(np.round(100.0 * k / self.fps)).astype(int) * 10
        self.frames[0].save(self.path, save_all=True, append_images=self.frames[1:], duration=delays.tolist(),
                            loop=0, optimize=False)
        self.frames = []


# ---------------------------------------------------------------------- public

@dataclasses.dataclass
class Animation:
    """What :func:`animate` wrote.

    Attributes
    ----------
    path : pathlib.Path
    format : {"mp4", "gif"}
    frames : int
    size : (int, int)
        Width and height [px].
    fps : float
    times : ndarray
        Simulation time of every frame [s].
    video_duration_s : float
        Playing time [s] (frames / fps).
    wall_s : float
        Time taken to write it [s].
    """

    path: pathlib.Path
    format: str
    frames: int
    size: tuple
    fps: float
    times: np.ndarray
    video_duration_s: float
    wall_s: float


def _playback_label(kick, window, factor):
    """Second line of the clock: playback speed (None for a still) and whether the plate moves."""
    def label(t):
        speed = "" if factor is None else (
            f"slow motion {factor:g}x" if factor != 1.0 and window[0] <= t <= window[1] else "real time")
        moving = "plate moving" if kick[0] <= t <= kick[1] else ""
        return "\n".join(part for part in (speed, moving) if part)
    return label


def check_options(fps, slow_motion, slow_after):
    """Check the playback options (before a long run): returns them as floats.

    Raises
    ------
    InputError
        Naming the value, the allowed range and the unit.
    """
    return (check_range("frame rate", fps, 1.0, 120.0, "frames/s"),
            check_range("slow-motion factor", slow_motion, 0.0, 1.0, "(playback speed)", low_open=True),
            check_range("slow-motion time after the kick", slow_after, 0.0, 60.0, "s"))


def _options(fmt, fps, slow_motion, slow_after, size):
    """Checked options: (fps, slow_motion, slow_after, (width, height))."""
    fps, slow_motion, slow_after = check_options(fps, slow_motion, slow_after)
    width, height = DEFAULT_SIZE[fmt] if size is None else size
    for name, value in (("width", width), ("height", height)):
        check_range(f"animation {name}", value, 64, 3840, "px")
        if int(value) != value or int(value) % 2:
            raise InputError(f"animation {name} = {value!r} px must be an even whole number in [64, 3840] px")
    return fps, slow_motion, slow_after, (int(width), int(height))


def _frames(result, times, size, dpi, tyres, moments, window, slow_motion):
    """The scene at ``times`` and the figure that draws it."""
    t_last = float(result.trajectory[COLUMNS["time"]].iloc[-1])
    scene = build_scene(result, times, tyres=tyres, moments=moments)
    camera = Camera(scene.camera_target, scene.camera_heading)
    fell = result.summary.get("fell") and times[-1] == t_last
    kick = _kick_window(result, 0.0)
    return _Frames(result, scene, camera, size, dpi, _playback_label(kick, window, slow_motion),
                   result.summary["fall_time_s"] if fell else None)


def _kick_window(result, after):
    """(start, end + after) of the kick [s]."""
    kick = result.summary["kick"]
    return kick["start_s"], kick["start_s"] + kick["duration_s"] + after


def animate(result, path, *, fps=30.0, slow_motion=0.2, slow_after=1.0, time_range=None, size=None, dpi=100,
            tyres=None, moments=True):
    """Write an animation of a run: mp4 (ffmpeg) or gif (Pillow), by the file's suffix.

    Parameters
    ----------
    result : whipple_kick.simulate.results.Result
    path : str or pathlib.Path
        ``*.mp4`` (needs a video encoder: the ``video`` extra or ffmpeg on
        PATH) or ``*.gif``.
    fps : float
        Frames per second of the video, in [1, 120].
    slow_motion : float
        Playback speed during the kick and the ``slow_after`` seconds after
        it, in (0, 1] (1 = real time throughout; default 0.2).
    slow_after : float
        Seconds after the kick's end still shown slowed [s], in [0, 60].
    time_range : (float, float), optional
        Part of the run to show [s] (default all of it: from the steady
        running before the kick to the end or the fall).
    size : (int, int), optional
        Width and height [px], even numbers in [64, 3840]; default
        :data:`DEFAULT_SIZE` of the format.
    dpi : float
        Resolution the text sizes refer to.
    tyres : (rear, front), optional
        The tyre objects of a run made with ``run(..., tyres=...)``.
    moments : bool
        Draw the self-aligning moments as arcs.

    Returns
    -------
    Animation

    Example
    -------
    >>> import whipple_kick as wk
    >>> result = wk.run(wk.Scenario(duration=1.0))
    >>> wk.animation.animate(result, "kick.gif", fps=10, size=(320, 180)).frames
    56
    """
    wall = time.perf_counter()
    path = pathlib.Path(path)
    fmt = path.suffix.lower().lstrip(".")
    if fmt not in DEFAULT_SIZE:
        raise InputError(f"animation file {str(path)!r} must end in .mp4 or .gif")
    fps, slow_motion, slow_after, size = _options(fmt, fps, slow_motion, slow_after, size)
    t = result.trajectory[COLUMNS["time"]].to_numpy()
    t0, t1 = float(t[0]), float(t[-1])
    if time_range is not None:
        lo, hi = (float(v) for v in time_range)
        check_range("animation start", lo, t0, t1, "s")
        check_range("animation end", hi, lo, t1, "s", low_open=True)
        t0, t1 = lo, hi
    window = _kick_window(result, slow_after)
    times = frame_times(t0, t1, fps, slow_motion, window)
    frames = _frames(result, times, size, dpi, tyres, moments, window, slow_motion)
    writer = (_FfmpegWriter if fmt == "mp4" else _GifWriter)(path, size, fps)
    try:
        for k in range(times.size):
            writer.write(frames.render(k))
    finally:
        writer.close()
    return Animation(path=path, format=fmt, frames=int(times.size), size=size, fps=fps, times=times,
                     video_duration_s=times.size / fps, wall_s=time.perf_counter() - wall)


def still(result, path, at, *, size=(1280, 720), dpi=100, tyres=None, moments=True):
    """Write one frame of the animation as a PNG: the run at time ``at`` [s].

    Example
    -------
    >>> import whipple_kick as wk
    >>> result = wk.run(wk.Scenario(duration=1.0))
    >>> wk.animation.still(result, "kick.png", 0.2)
    """
    from PIL import Image

    _, _, _, size = _options("mp4", 30.0, 1.0, 0.0, size)
    t = result.trajectory[COLUMNS["time"]].to_numpy()
    at = check_range("frame time", at, float(t[0]), float(t[-1]), "s")
    frames = _frames(result, np.array([at]), size, dpi, tyres, moments, (at, at), None)
    Image.fromarray(frames.render(0)).save(path)
