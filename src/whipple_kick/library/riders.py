"""Yeadon riders: build, scale, seat on a bicycle, and size to a rear-tyre load.

The rider is a Yeadon (1990) human-body model (the ``yeadon`` package) built
from the 95 measurements in ``parameters/riders/<name>.toml``, scaled to the
requested mass (and optionally height), seated on the bicycle the way Moore's
BicycleParameters seats a rider, and lumped rigidly into the rear frame.

Seating (the method of BicycleParameters' ``rider_on_bike``, re-derived and
written here from yeadon's segment kinematics):

* the Yeadon origin (centre of the bottom of the pelvis) sits at the top of
  the seat post, ``lst + lsp`` up the seat tube from the bottom bracket;
* the trunk keeps the rider file's configuration (somersault = forward lean);
* each leg (hip flexion, knee flexion) is bent so that the point of the
  shank-foot segment at Yeadon level 6 (``Lj6L`` beyond the ankle; Yeadon's
  foot is in line with the shank) lies on the bottom bracket (crank axle);
* each arm (shoulder extension, adduction, rotation and elbow extension) puts
  the hand point at Yeadon level 5 (``La5L`` beyond the wrist) on its grip,
  ``whb/2`` beside the mid-plane, ``LhbR`` from the rear and ``LhbF`` from the
  front wheel centre, with the elbow's hinge axis horizontal (the fourth
  condition that makes the arm posture unique);
* left and right limbs mirror each other (the model is left-right averaged,
  yeadon's ``symmetric=True``).

Frames: yeadon's global frame has x to the rider's left, y backward, z up;
the bicycle's benchmark frame has x forward, y right, z down. So
``v_bike = YEADON_TO_BIKE @ v_yeadon``.
"""
from collections.abc import Mapping
import copy
import dataclasses
import functools
import math
import types
from typing import NamedTuple

import numpy as np
from scipy.optimize import fsolve

from whipple_kick.errors import InputError, check_range
from whipple_kick.model import benchmark as _benchmark
from whipple_kick.model import parts

from . import parameters
from .bicycles import Bicycle

#: Folder of the shipped rider files.
RIDER_DIR = parameters.shipped("riders")

FORMAT = "whipple_kick rider, version 1"

#: The human range of a rider's mass [kg], refused outside (one line naming the value, the range and the unit).
#: Derived from the WHO's body-mass-index classification (WHO Technical Report Series 854, 1995, and 894, 2000:
#: BMI < 16 kg/m^2 "severe thinness", its lowest class; BMI >= 40 kg/m^2 obese class III, its highest) at the
#: standing heights a Yeadon rider can be scaled to here, 1.2-2.3 m (:func:`yeadon_rider`): 16 x 1.2^2 = 23.0 kg
#: is the lightest person of the shortest height outside severe thinness; above, 200 kg (the project's bound
#: before this one) lies below 40 x 2.3^2 = 211.6 kg. A rider outside is no person (a 3.35 kg Yeadon "rider",
#: which a bicycle that already holds its rider would get to reach the default 635 N: give it rider "none").
MIN_RIDER_MASS_KG = 23.0
#: Largest rider mass accepted anywhere [kg] (see :data:`MIN_RIDER_MASS_KG`).
MAX_RIDER_MASS_KG = 200.0
#: The rider name of a bicycle whose parameters include its rider (:attr:`whipple_kick.Scenario.rider`): no Yeadon
#: rider is seated and the bicycle runs with its own load share.
NO_RIDER = "none"
#: Largest fore-aft shift of the whole seated rider [m] a rear load share may ask for (:func:`for_load_share`).
#: A judgement, not a measurement: a saddle's rails and setback posts move it some 0.05-0.08 m, a stem's length
#: the bar some 0.06-0.10 m, and a rider slides about 0.05 m along the saddle; 0.15 m spans these together.
#: Beyond it the posture kept would be a different bicycle's fit. Thesis Table 8.3's totals (rear share
#: 0.683-0.694) need 0.09-0.11 m rearward on balanceassist_v1 (tests/library/test_riders.py).
MAX_RIDER_SHIFT_M = 0.15

#: Rotation taking yeadon-frame components to benchmark-frame components.
YEADON_TO_BIKE = np.array([[0.0, -1.0, 0.0],
                           [-1.0, 0.0, 0.0],
                           [0.0, 0.0, -1.0]])

#: Ankle-joint height as a fraction of standing height: Drillis & Contini
#: (1966) segment proportions (as reproduced in Winter, "Biomechanics and
#: Motor Control of Human Movement", Fig. 4.1). Yeadon measures no foot
#: height, so this is how a standing height is estimated from the model.
ANKLE_HEIGHT_FRACTION = 0.039

# Trunk angles the seating solution assumes to be zero: with them the pelvis
# turns about its x axis only, so the legs move in a sagittal plane.
_MUST_BE_ZERO = ("tilt", "twist", "PTbending", "TCspinalTorsion", "PJ1adduction", "PK1abduction")


@dataclasses.dataclass(frozen=True)
class YeadonRider:
    """A Yeadon rider, scaled, not yet seated.

    Attributes
    ----------
    name : str
        Rider file name.
    mass_kg : float
        Mass the body is scaled to [kg].
    height_m : float
        Standing height [m], estimated from the (scaled) measurements by
        :func:`standing_height`.
    length_scale : float
        Factor applied to all 95 measurements of the file (1 unless a height
        was requested).
    measurements : Mapping
        The 95 Yeadon measurements after length scaling [m].
    configuration : Mapping
        The file's seated configuration [rad] (limb angles are solved when
        seating).
    source : str
        The rider file's sources.
    """

    name: str
    mass_kg: float
    height_m: float
    length_scale: float
    measurements: Mapping
    configuration: Mapping
    source: str

    def human(self, configuration=None):
        """Return a new ``yeadon.Human`` of this rider, scaled to :attr:`mass_kg`.

        Parameters
        ----------
        configuration : mapping, optional
            Joint angles [rad] (all 21 yeadon names); default the file's.
        """
        import yeadon

        # yeadon keeps a reference to the dict and averages limbs in place.
        human = yeadon.Human(dict(self.measurements), symmetric=True)
        # scale_human_by_mass() rescales yeadon's class-level density table in
        # place, which would leak into every later Human; give this instance
        # its own copy first. Only the density ratios (Dempster's) matter.
        human.segmental_densities = copy.deepcopy(type(human).segmental_densities)
        for _ in range(3):  # one pass is exact to round-off; repeat if not
            human.scale_human_by_mass(self.mass_kg)
            if abs(human.mass - self.mass_kg) <= 1e-12 * self.mass_kg:
                break
        human.set_CFG_dict(dict(configuration or self.configuration))
        return human


def available():
    """Names of the shipped rider files, sorted."""
    return list(parameters.toml_files(RIDER_DIR))


def standing_height(measurements):
    """Standing height [m] estimated from Yeadon measurements.

    Top of head to hip centre (``Ls5L + Ls8L``) plus hip centre to ankle (mean
    of ``Lj5L`` and ``Lk5L``) is the stature less the ankle height, taken as
    :data:`ANKLE_HEIGHT_FRACTION` of the stature.
    """
    m = measurements
    head_to_ankle = m["Ls5L"] + m["Ls8L"] + 0.5 * (m["Lj5L"] + m["Lk5L"])
    return head_to_ankle / (1.0 - ANKLE_HEIGHT_FRACTION)


def _read_rider_file(name):
    """Parse and validate ``parameters/riders/<name>.toml``, once per process and content (shared: read only)."""
    names = available()
    if name not in names:
        raise InputError(f"unknown rider {name!r}; available: {', '.join(names)}")
    path = RIDER_DIR / f"{name}.toml"
    return _parse_rider_file(path, parameters.file_bytes(path))


@functools.lru_cache(maxsize=64)
def _parse_rider_file(path, content):
    import yeadon

    data = parameters.parse_toml(path, content)
    if data.get("format") != FORMAT:
        parameters.fail(path, "format", f"must be {FORMAT!r}, got {data.get('format')!r}")
    if data.get("model") != "yeadon":
        parameters.fail(path, "model", f"must be 'yeadon', got {data.get('model')!r}")
    sources = data.get("sources")
    if not isinstance(sources, dict) or not sources:
        parameters.fail(path, "sources", "must map keys to citation strings")
    out = {}
    for table, unit, names_wanted in (("measurements", "m", yeadon.Human.measnames),
                                      ("configuration", "rad", yeadon.Human.CFGnames)):
        tab = parameters.table(path, table, data.get(table))
        values = parameters.table(path, f"{table}.values", tab.get("values"))
        if tab.get("unit") != unit:
            parameters.fail(path, f"{table}.unit", f"must be {unit!r}, got {tab.get('unit')!r}")
        if tab.get("source") not in sources:
            parameters.fail(path, f"{table}.source", f"{tab.get('source')!r} is not a key of [sources]")
        unknown = sorted(set(values) - set(names_wanted))
        missing = [k for k in names_wanted if k not in values]
        if unknown or missing:
            parameters.fail(path, f"{table}.values", f"unknown keys {unknown}, missing keys {missing}")
        out[table] = {k: parameters.number(path, f"{table}.values.{k}", values[k]) for k in names_wanted}
    for key, value in out["measurements"].items():
        parameters.at_least(path, f"measurements.values.{key}", value, "m", 0.0, low_open=True)
    for key, (low, high) in zip(yeadon.Human.CFGnames, yeadon.Human.CFGbounds, strict=True):
        value = out["configuration"][key]
        if not low <= value <= high:
            parameters.fail(path, f"configuration.values.{key}", f"value {value!r} rad is outside "
                                                                 f"[{low:g}, {high:g}] rad")
    for key in _MUST_BE_ZERO:
        if out["configuration"][key] != 0.0:
            parameters.fail(path, f"configuration.values.{key}", "must be 0 rad for seating on a bicycle (the "
                            f"legs must move in the mid-plane), got {out['configuration'][key]!r}")
    out["mass"] = parameters.quantity(path, "mass", data.get("mass"), "kg", sources=sources,
                                      low=0.0, low_open=True)[0]
    out["source"] = "\n".join(f"{k}: {v}" for k, v in sources.items())
    return out


def yeadon_rider(name="jason", mass_kg=None, height_m=None):
    """Build a Yeadon rider from a rider file, scaled to a mass (and height).

    Parameters
    ----------
    name : str
        Rider file in ``parameters/riders/`` (see :func:`available`).
    mass_kg : float, optional
        Rider mass [kg], in [23, 200] (:data:`MIN_RIDER_MASS_KG`); default the file's measured mass.
        The body's densities are scaled uniformly, so the mass is met to
        round-off and, at fixed geometry, inertia is proportional to mass.
    height_m : float, optional
        Standing height [m], in [1.2, 2.3]. All 95 lengths are scaled by
        ``height_m / standing_height(file measurements)`` first, then the
        mass is imposed. Default: the file's body unchanged.

    Returns
    -------
    YeadonRider
    """
    data = _read_rider_file(name)
    return rider_from_measurements(name, data["measurements"], data["configuration"], data["source"],
                                   mass_kg=data["mass"] if mass_kg is None else mass_kg, height_m=height_m)


def rider_from_measurements(name, measurements, configuration, source, mass_kg, height_m=None):
    """A :class:`YeadonRider` from its 95 measurements [m] and configuration [rad] (:func:`yeadon_rider`'s core).

    Parameters
    ----------
    name, source : str
        The rider's name and where the measurements come from.
    measurements, configuration : Mapping
        Yeadon's 95 measurements [m] and 21 joint angles [rad], by yeadon's names.
    mass_kg : float
        Rider mass [kg], in [23, 200] (:data:`MIN_RIDER_MASS_KG`).
    height_m : float, optional
        Standing height [m], in [1.2, 2.3] (see :func:`yeadon_rider`).
    """
    mass = check_range("rider mass", mass_kg, MIN_RIDER_MASS_KG, MAX_RIDER_MASS_KG, "kg")
    meas = dict(measurements)
    scale = 1.0
    if height_m is not None:
        scale = check_range("rider height", height_m, 1.2, 2.3, "m") / standing_height(meas)
        meas = {k: v * scale for k, v in meas.items()}
    for key in _MUST_BE_ZERO:
        if configuration.get(key, 0.0) != 0.0:
            raise InputError(f"rider {name!r}: configuration {key} = {configuration[key]!r} rad must be 0 rad "
                             "for seating on a bicycle (the legs must move in the mid-plane)")
    return YeadonRider(
        name=name, mass_kg=mass, height_m=standing_height(meas), length_scale=scale,
        measurements=types.MappingProxyType(meas),
        configuration=types.MappingProxyType(dict(configuration)),
        source=source,
    )


@dataclasses.dataclass(frozen=True)
class SeatedRider:
    """A rider placed on a bicycle, in the bicycle's benchmark frame.

    Attributes
    ----------
    mass : float
        [kg]
    com : numpy.ndarray, shape (3,)
        Mass centre [m] from the rear contact point, x forward, y right, z down.
    inertia : numpy.ndarray, shape (3, 3)
        Inertia tensor [kg m^2] about the mass centre in benchmark axes.
    configuration : Mapping
        The full seated yeadon configuration [rad].
    seat, bottom_bracket, left_grip : numpy.ndarray, shape (3,)
        The seating points used [m], benchmark frame.
    """

    mass: float
    com: np.ndarray
    inertia: np.ndarray
    configuration: Mapping
    seat: np.ndarray
    bottom_bracket: np.ndarray
    left_grip: np.ndarray

    def benchmark(self):
        """The rider alone as benchmark rear-frame entries (mB, xB, yB, zB, IB..)."""
        i = self.inertia
        return {"mB": self.mass, "xB": float(self.com[0]), "yB": float(self.com[1]),
                "zB": float(self.com[2]), "IBxx": float(i[0, 0]), "IByy": float(i[1, 1]),
                "IBzz": float(i[2, 2]), "IBxz": float(i[0, 2])}

    def posture(self):
        """The seated posture as plain data (what a drawing of the rider needs besides the rider's file and mass).

        The seating points [m] in the benchmark frame (from the rear contact, x forward, y right, z down) and
        the Yeadon configuration [rad] the seating solved: ``seat_m``, ``bottom_bracket_m``, ``left_grip_m``
        (the right grip is its mirror in the mid-plane), ``configuration_rad`` ([name, angle] pairs: a list, so
        that a sweep's table, which takes a summary's scalars, does not get 21 columns of a drawing's input).
        """
        return {"seat_m": [float(v) for v in self.seat], "bottom_bracket_m": [float(v) for v in self.bottom_bracket],
                "left_grip_m": [float(v) for v in self.left_grip],
                "configuration_rad": [[k, float(v)] for k, v in self.configuration.items()]}


def _seating_points(bench, geometry, bike_name):
    """Seat, bottom bracket and left grip in the benchmark frame (x fwd, y right, z down)."""
    g = geometry
    rR, rF, w = bench["rR"], bench["rF"], bench["w"]
    # Bottom bracket: hbb above the ground, lcs from the rear wheel centre.
    dz = rR - g["hbb"]
    if g["lcs"] <= abs(dz):
        raise InputError(f"bicycle {bike_name!r}: chain stay lcs = {g['lcs']} m must exceed "
                         f"|rR - hbb| = {abs(dz):g} m")
    bottom_bracket = np.array([math.sqrt(g["lcs"] ** 2 - dz ** 2), 0.0, -g["hbb"]])
    seat_tube = g["lst"] + g["lsp"]
    seat = bottom_bracket + seat_tube * np.array([-math.cos(g["lamst"]), 0.0, -math.sin(g["lamst"])])
    # Grip: in-plane distances from the wheel centres, then the upper
    # intersection of the two circles in the x-z plane.
    half = 0.5 * g["whb"]
    if g["LhbR"] <= half or g["LhbF"] <= half:
        raise InputError(f"bicycle {bike_name!r}: LhbR and LhbF must exceed whb/2 = {half:g} m")
    a_r = math.sqrt(g["LhbR"] ** 2 - half ** 2)
    a_f = math.sqrt(g["LhbF"] ** 2 - half ** 2)
    rear_c, front_c = np.array([0.0, -rR]), np.array([w, -rF])
    span = float(np.linalg.norm(front_c - rear_c))
    along = (a_r ** 2 - a_f ** 2 + span ** 2) / (2.0 * span)
    if a_r ** 2 - along ** 2 <= 0:
        raise InputError(f"bicycle {bike_name!r}: LhbR = {g['LhbR']} m and LhbF = {g['LhbF']} m "
                         f"do not locate a grip above the wheel centres (wheel-centre span {span:g} m)")
    up = math.sqrt(a_r ** 2 - along ** 2)
    unit = (front_c - rear_c) / span
    normal = np.array([unit[1], -unit[0]])  # unit rotated toward -z (up) for a level bicycle
    grip = rear_c + along * unit + up * normal
    left_grip = np.array([grip[0], -half, grip[1]])
    return seat, bottom_bracket, left_grip


def _rx(angle):
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def _body123(a, b, c):
    """yeadon's body-fixed 1-2-3 rotation (x, then new y, then new z)."""
    cb, sb, cc, sc = math.cos(b), math.sin(b), math.cos(c), math.sin(c)
    ry = np.array([[cb, 0.0, sb], [0.0, 1.0, 0.0], [-sb, 0.0, cb]])
    rz = np.array([[cc, -sc, 0.0], [sc, cc, 0.0], [0.0, 0.0, 1.0]])
    return _rx(a) @ ry @ rz


def place(bike, rider):
    """Seat a rider on a bicycle (hands on the grips, feet at the bottom bracket).

    Parameters
    ----------
    bike : Bicycle
        A bicycle without rider and with seating geometry (``bike.geometry``).
    rider : YeadonRider

    Returns
    -------
    SeatedRider
        The rider's mass, mass centre and inertia in the bicycle's benchmark frame.

    Raises
    ------
    InputError
        The bicycle has no seating geometry or already includes a rider, or
        the rider cannot reach the bottom bracket or the grips.
    """
    if not isinstance(bike, Bicycle):
        raise InputError(f"bike must be a whipple_kick.library.bicycles.Bicycle, got {type(bike).__name__}")
    if not isinstance(rider, YeadonRider):
        raise InputError(f"rider must be a YeadonRider (see yeadon_rider()), got {type(rider).__name__}")
    if bike.includes_rider:
        raise InputError(f"bicycle {bike.name!r} already includes a rider; seat riders on a "
                         f"bicycle-only set such as 'balanceassist_v1'")
    if bike.geometry is None:
        raise InputError(f"bicycle {bike.name!r} has no [seating] geometry to seat a rider on")
    seat_pt, bb_pt, grip_pt = _seating_points(bike.benchmark, bike.geometry, bike.name)
    to_yeadon = YEADON_TO_BIKE.T
    human = rider.human()  # file configuration: trunk posed, limbs straight
    # Limb lengths as yeadon uses them: left and right averaged (symmetric=True).
    m = human.meas

    # Legs: planar two-link chain from the hip to the foot point, in yeadon's
    # y-z plane. A link at absolute angle t about x points along (0, sin t, -cos t).
    thigh = m["Lj3L"]
    shank_foot = m["Lj5L"] - m["Lj3L"] + m["Lj6L"]
    foot = to_yeadon @ (bb_pt - seat_pt)
    reach = math.hypot(foot[1], foot[2])
    if not abs(thigh - shank_foot) < reach < thigh + shank_foot:
        raise InputError(f"rider {rider.name!r} (height {rider.height_m:.3f} m) cannot reach the "
                         f"bottom bracket: seat-to-crank distance {reach:.3f} m, leg reach "
                         f"{thigh + shank_foot:.3f} m")
    knee = math.acos((reach ** 2 - thigh ** 2 - shank_foot ** 2) / (2.0 * thigh * shank_foot))
    pelvis = human.CFG["somersault"]
    hip = (math.atan2(foot[1], -foot[2])
           - math.atan2(shank_foot * math.sin(knee), thigh + shank_foot * math.cos(knee)) - pelvis)

    # Left arm: shoulder position and chest orientation do not depend on the arm angles.
    chest = np.asarray(human.C.rot_mat)
    shoulder = np.asarray(human.A1.pos).ravel()
    upper = m["La2L"]
    fore = m["La4L"] + m["La5L"] - m["La2L"]
    hand = to_yeadon @ (grip_pt - seat_pt)
    if np.linalg.norm(hand - shoulder) >= upper + fore:
        raise InputError(f"rider {rider.name!r} (height {rider.height_m:.3f} m) cannot reach the "
                         f"grips: shoulder-to-grip {np.linalg.norm(hand - shoulder):.3f} m, arm "
                         f"reach {upper + fore:.3f} m")

    def arm_residual(q):
        upper_rot = chest @ _body123(q[0], q[1], q[2])
        fore_rot = upper_rot @ _rx(q[3])
        # yeadon builds limb segments toward their local -z.
        tip = shoulder - upper * upper_rot[:, 2] - fore * fore_rot[:, 2]
        # Fourth condition: elbow hinge (upper arm's x axis) horizontal.
        return np.r_[tip - hand, upper_rot[2, 0]]

    # Start from a bent-elbow, arm-forward posture (the branch a rider uses).
    guess = np.radians([-15.0, 2.0, 2.0, -40.0])
    arm, _, ok, _ = fsolve(arm_residual, guess, full_output=True, xtol=1e-13)
    arm = (np.asarray(arm) + math.pi) % (2.0 * math.pi) - math.pi
    if ok != 1 or np.max(np.abs(arm_residual(arm))) > 1e-9:
        raise RuntimeError(f"arm posture for rider {rider.name!r} on {bike.name!r} did not converge")

    cfg = dict(rider.configuration)
    cfg.update(PJ1extension=hip, PK1extension=hip, J1J2flexion=knee, K1K2flexion=knee,
               CA1extension=arm[0], CA1adduction=arm[1], CA1rotation=arm[2], A1A2extension=arm[3],
               CB1extension=arm[0], CB1abduction=-arm[1], CB1rotation=-arm[2],
               B1B2extension=arm[3])
    import yeadon

    for key, (low, high) in zip(yeadon.Human.CFGnames, yeadon.Human.CFGbounds, strict=True):
        if not low <= cfg[key] <= high:
            raise InputError(f"rider {rider.name!r} (height {rider.height_m:.3f} m) does not fit "
                             f"bicycle {bike.name!r}: seated {key} = {cfg[key]:.3f} rad is outside "
                             f"yeadon's joint range [{low:g}, {high:g}] rad")
    human.set_CFG_dict(cfg)

    # Check the posture with yeadon's own segment geometry (not our kinematics).
    yeadon_foot = np.asarray(human.J2.solids[3].end_pos).ravel()   # level j6 (proximal end of j6-j7)
    yeadon_hand = np.asarray(human.A2.solids[2].pos).ravel()       # level a5 (distal end of a4-a5)
    yeadon_rhand = np.asarray(human.B2.solids[2].pos).ravel()
    mirror = np.array([-1.0, 1.0, 1.0])
    errors = (abs(yeadon_foot[1] - foot[1]), abs(yeadon_foot[2] - foot[2]),
              *np.abs(yeadon_hand - hand), *np.abs(yeadon_rhand - mirror * hand))
    if max(errors) > 1e-8:
        raise RuntimeError(f"seated posture misses its targets by {max(errors):.3g} m")

    com = seat_pt + YEADON_TO_BIKE @ np.asarray(human.center_of_mass).ravel()
    inertia = YEADON_TO_BIKE @ np.asarray(human.inertia) @ YEADON_TO_BIKE.T
    # Mid-plane symmetry: no lateral offset, no xy/yz products of inertia.
    scale = max(1.0, float(np.max(np.abs(inertia))))
    if abs(com[1]) > 1e-9 or max(abs(inertia[0, 1]), abs(inertia[1, 2])) > 1e-9 * scale:
        raise RuntimeError("seated rider is not symmetric about the bicycle's mid-plane")
    com[1] = 0.0
    inertia[0, 1] = inertia[1, 0] = inertia[1, 2] = inertia[2, 1] = 0.0
    return SeatedRider(mass=float(human.mass), com=com, inertia=inertia,
                       configuration=types.MappingProxyType(cfg), seat=seat_pt,
                       bottom_bracket=bb_pt, left_grip=grip_pt)


def lump_into_rear_frame(bench, mass, com, inertia):
    """Add a rigid body to the rear frame B of a benchmark-form set (:func:`lump_into_frame` with ``"B"``)."""
    return lump_into_frame(bench, "B", mass, com, inertia)


def lump_into_frame(bench, frame, mass, com, inertia):
    """Add a rigid body to the benchmark body ``frame`` ("B" rear frame, "H" front frame) of a benchmark set.

    Parameters
    ----------
    bench : mapping
        Benchmark parameters.
    frame : {"B", "H"}
        The body it is added to.
    mass : float
        Added mass [kg].
    com : sequence of 3 floats
        Its mass centre [m] (benchmark frame; y must be 0).
    inertia : array_like, shape (3, 3)
        Its inertia tensor [kg m^2] about its own mass centre, benchmark axes.

    Returns
    -------
    dict
        Benchmark parameters with the combined body (m<frame>, x<frame>, z<frame>, I<frame>..).
    """
    f = frame
    out = dict(bench)
    m_b, m_r = bench[f"m{f}"], float(mass)
    m = m_b + m_r
    x = (m_b * bench[f"x{f}"] + m_r * com[0]) / m
    z = (m_b * bench[f"z{f}"] + m_r * com[2]) / m

    def shifted(m_i, ixx, iyy, izz, ixz, xi, zi):
        # Parallel-axis theorem to the combined mass centre; a tensor's xz entry is -sum(m x z).
        dx, dz = xi - x, zi - z
        return (ixx + m_i * dz * dz, iyy + m_i * (dx * dx + dz * dz),
                izz + m_i * dx * dx, ixz - m_i * dx * dz)

    a = shifted(m_b, bench[f"I{f}xx"], bench[f"I{f}yy"], bench[f"I{f}zz"], bench[f"I{f}xz"], bench[f"x{f}"],
                bench[f"z{f}"])
    i = np.asarray(inertia, dtype=float)
    b = shifted(m_r, i[0, 0], i[1, 1], i[2, 2], i[0, 2], com[0], com[2])
    out.update({f"m{f}": m, f"x{f}": x, f"z{f}": z, f"I{f}xx": a[0] + b[0], f"I{f}yy": a[1] + b[1],
                f"I{f}zz": a[2] + b[2], f"I{f}xz": a[3] + b[3]})
    return out


def _with_rider(bike, rider, seated, bench, name, how):
    """The :class:`Bicycle` of ``bike`` with ``rider`` seated (``seated``, :func:`place`'s) as ``bench`` has it.

    ``name`` is added to the set's name, ``how`` says in the description where the rider went.
    """
    return Bicycle(
        name=f"{bike.name}+{rider.name}({rider.mass_kg:g} kg{name})",
        benchmark=bench, parameterisation="benchmark", includes_rider=True,
        source=f"{bike.source}\nrider {rider.name}:\n{rider.source}",
        description=f"{bike.description} With Yeadon rider {rider.name!r} "
                    f"({rider.mass_kg:g} kg, {rider.height_m:.3f} m){how}",
        uncertainties={}, geometry=bike.geometry, tyre_placeholders=bike.tyre_placeholders, defaults=bike.defaults,
        rider={"name": rider.name, "mass_kg": rider.mass_kg, "height_m": rider.height_m,
               **{f"rider_{k}": v for k, v in seated.benchmark().items()}, "posture": seated.posture()},
    )


def seat(bike, rider, shift_m=0.0):
    """Bicycle with the rider rigidly lumped into its rear frame.

    Parameters
    ----------
    bike : Bicycle
        Bicycle-only set with seating geometry (e.g. ``"balanceassist_v1"``).
    rider : YeadonRider
    shift_m : float
        Fore-aft shift of the whole seated rider [m], forward positive (:func:`shifted`).

    Returns
    -------
    Bicycle
        Moore-parameter mapping of bicycle + rider (``includes_rider`` True,
        ``rider`` metadata: name, mass_kg, height_m and the rider's own
        benchmark-form entries).
    """
    seated = shifted(place(bike, rider), shift_m)
    bench = lump_into_rear_frame(bike.benchmark, seated.mass, seated.com, seated.inertia)
    return _with_rider(bike, rider, seated, bench, _shift_label(shift_m), " lumped into the rear frame.")


def shifted(seated, shift_m):
    """``seated`` moved ``shift_m`` [m] along the bicycle's x axis (forward positive), posture unchanged.

    The whole rider moves as one: mass centre, seat point (the leaning body's hinge), the feet's and the
    hands' points; the inertia about the mass centre is unchanged. It stands for a fit change (saddle
    setback, stem length) that keeps the rider's posture, not a rider re-posed on a fixed saddle, bar and
    cranks (that would change the inertia as well, and tie the share to the joint limits).
    """
    if shift_m == 0.0:
        return seated
    dx = np.array([float(shift_m), 0.0, 0.0])
    return dataclasses.replace(seated, com=seated.com + dx, seat=seated.seat + dx,
                               bottom_bracket=seated.bottom_bracket + dx, left_grip=seated.left_grip + dx)


def _shift_label(shift_m):
    return "" if shift_m == 0.0 else f", shifted {shift_m:+.4f} m"


def static_loads(params):
    """Static normal forces on the tyres of the upright bicycle [N].

    Exact rigid-contact statics with knife-edge wheels on level ground: the
    vertical forces balance the weight and its moment about the rear contact,
    ``rear = m g (w - x) / w``, ``front = m g x / w``, with ``m`` the total
    mass, ``x`` the total mass centre ahead of the rear contact and ``g`` the
    parameter set's own gravity.

    Parameters
    ----------
    params : mapping
        Moore parameters (a :class:`Bicycle` or a dict with Moore names).

    Returns
    -------
    (float, float)
        (rear, front) normal forces [N].
    """
    bench = _benchmark.from_moore(params)
    w = bench["w"]
    masses = (bench["mR"], bench["mB"], bench["mH"], bench["mF"])
    xs = (0.0, bench["xB"], bench["xH"], w)
    m = sum(masses)
    x = sum(mi * xi for mi, xi in zip(masses, xs, strict=True)) / m
    weight = m * bench["g"]
    return weight * (w - x) / w, weight * x / w


class RearLoadSolution(NamedTuple):
    """Result of :func:`for_rear_load`; unpacks as ``(combined, rider_mass_kg)``.

    ``rear_n`` and ``front_n`` are the static tyre loads of ``combined`` [N].
    """

    combined: Bicycle
    rider_mass_kg: float

    @property
    def rear_n(self):
        return static_loads(self.combined)[0]

    @property
    def front_n(self):
        return static_loads(self.combined)[1]


def rear_load_range(bike, rider="jason", height_m=None):
    """Static rear-tyre loads a rider can produce on ``bike``: (low, high, per_kg).

    ``low`` is the bicycle's own rear load [N] (a rider of no mass),
    ``high`` that with a :data:`MAX_RIDER_MASS_KG` rider [N], ``per_kg`` the
    rear load one kilogram of rider adds [N/kg] (the seated posture, hence
    the rider's mass centre, does not depend on the mass). The loads allowed
    run from ``low + MIN_RIDER_MASS_KG * per_kg`` to ``high``
    (:func:`within_rear_load_range`).
    """
    probe = yeadon_rider(rider, height_m=height_m)
    x_rider = place(bike, probe).com[0]
    bench = bike.benchmark
    rear_bike, _ = static_loads(bike)
    per_kg = bench["g"] * (bench["w"] - x_rider) / bench["w"]
    return rear_bike, rear_bike + MAX_RIDER_MASS_KG * per_kg, per_kg


def within_rear_load_range(bike, fz_n, low, high, per_kg):
    """``float(fz_n)`` if a rider of a human mass (:data:`MIN_RIDER_MASS_KG` to :data:`MAX_RIDER_MASS_KG`) gives it,
    else one-line InputError; ``low, high, per_kg`` are the :func:`rear_load_range` of ``bike``."""
    fz = check_range("rear-tyre load fz", fz_n, None, None, "N")  # a finite number
    lightest = low + MIN_RIDER_MASS_KG * per_kg
    if not lightest <= fz <= high:
        # A bicycle that holds its rider already needs only a few kilograms more (the benchmark bicycle: 3.35 kg).
        hint = (f"; the bicycle alone puts {low:.2f} N on it: if its parameters include the rider, give rider "
                f"{NO_RIDER!r} (--rider {NO_RIDER})" if low < fz < lightest else "")
        raise InputError(f"rear-tyre load fz = {fz_n!r} N is outside the allowed range "
                         f"[{lightest:.2f}, {high:.2f}] N for {bike.name!r}: a {MIN_RIDER_MASS_KG:g} kg rider puts "
                         f"{lightest:.2f} N on its rear tyre and a {MAX_RIDER_MASS_KG:g} kg rider {high:.2f} N"
                         + hint)
    return fz


def for_rear_load(bike, fz_n, rider="jason", height_m=None, load_range=None):
    """Seat the rider whose mass gives the bicycle a static rear-tyre load ``fz_n``.

    The seated posture does not depend on the rider's mass (only on the
    lengths), so the rider's mass centre is fixed and the rear load is affine
    in the rider mass: ``rear(m) = rear_bike + m g (w - x_rider) / w``. The
    mass follows in closed form and is checked on the seated result.

    Parameters
    ----------
    bike : Bicycle
        Bicycle-only set with seating geometry; its ``g`` is used (9.80665
        m/s^2 for ``balanceassist_v1``, the value of its source).
    fz_n : float
        Required static rear-tyre normal force [N]; between the loads with a
        23 kg and a 200 kg rider (:data:`MIN_RIDER_MASS_KG`, :func:`rear_load_range`).
    rider : str
        Rider file name.
    height_m : float, optional
        Rider height [m] (see :func:`yeadon_rider`).
    load_range : tuple, optional
        :func:`rear_load_range` of this bicycle and rider if already known
        (it seats a probe rider, ~10 ms, and does not depend on the load).

    Returns
    -------
    RearLoadSolution
        ``combined, rider_mass = for_rear_load(...)``; ``.front_n`` and
        ``.rear_n`` give the static loads [N].
    """
    rear_bike, high, per_kg = rear_load_range(bike, rider, height_m) if load_range is None else load_range
    fz = within_rear_load_range(bike, fz_n, rear_bike, high, per_kg)
    mass = (fz - rear_bike) / per_kg
    combined = seat(bike, yeadon_rider(rider, mass_kg=mass, height_m=height_m))
    achieved = static_loads(combined)[0]
    if abs(achieved - fz) > 1e-6:
        raise RuntimeError(f"rear load {achieved} N misses the requested {fz} N")
    return RearLoadSolution(combined=combined, rider_mass_kg=mass)


class LoadShareSolution(NamedTuple):
    """Result of :func:`for_load_share`: the bicycle with its rider seated and shifted, the rider's mass [kg]
    and the shift [m, forward positive]; ``rear_n``/``front_n`` as :class:`RearLoadSolution`'s."""

    combined: Bicycle
    rider_mass_kg: float
    shift_m: float

    rear_n = RearLoadSolution.rear_n
    front_n = RearLoadSolution.front_n


def for_load_share(bike, share, fz_n=None, rider_mass_kg=None, rider="jason", height_m=None):
    """Seat the rider and shift it fore-aft so that a fraction ``share`` of the static weight is on the rear tyre.

    With ``fz_n`` the total weight is ``fz_n / share``, which fixes the rider's mass; with ``rider_mass_kg``
    the rear load is ``share`` times the weight. Either way the rider's mass centre ``x_r`` (from the rear
    contact) must give the bicycle that rear load: ``rear = rear_bike + m g (1 - x_r / w)``, solved in closed
    form for ``x_r``; the seated rider is then moved by ``x_r - x_seated`` as a whole (:func:`shifted`).

    Parameters
    ----------
    bike : Bicycle
        Bicycle-only set with seating geometry.
    share : float
        Rear tyre's share of the static weight [1].
    fz_n, rider_mass_kg : float, optional
        The static rear load [N] or the rider's mass [kg]; exactly one.
    rider : str
    height_m : float, optional

    Returns
    -------
    LoadShareSolution

    Raises
    ------
    InputError
        One line naming the share, the range this bicycle and load allow, and why: a rider mass in
        [:data:`MIN_RIDER_MASS_KG`, :data:`MAX_RIDER_MASS_KG`] kg, a shift within +-:data:`MAX_RIDER_SHIFT_M` m, the rider's mass
        centre inside the wheelbase.
    """
    share_in = share
    share = check_range("rear load share", share, 0.0, 1.0, "1", low_open=True, high_open=True)
    if (fz_n is None) == (rider_mass_kg is None):
        raise ValueError("give exactly one of fz_n and rider_mass_kg")
    bench = bike.benchmark
    g, w = bench["g"], bench["w"]
    m_bike = sum(float(bench[k]) for k in ("mR", "mB", "mH", "mF"))
    rear_bike, _ = static_loads(bike)
    if fz_n is not None:
        # Above the bicycle's own rear load; the upper end (the heaviest rider) is the share's check below.
        fz = check_range("rear-tyre load fz", fz_n, rear_bike, None, "N", low_open=True)
        mass = fz / (share * g) - m_bike
        what = f"rear load fz = {fz:g} N"
    else:
        mass = check_range("rider mass", rider_mass_kg, MIN_RIDER_MASS_KG, MAX_RIDER_MASS_KG, "kg")
        fz = share * g * (m_bike + mass)
        what = f"rider mass {mass:g} kg"
    human = MIN_RIDER_MASS_KG <= mass <= MAX_RIDER_MASS_KG
    x_seated = place(bike, yeadon_rider(rider, mass_kg=mass if human else 70.0,
                                        height_m=height_m)).com[0]
    # The shifts allowed: within +-MAX_RIDER_SHIFT_M and the rider's mass centre inside the wheelbase.
    lo_dx, hi_dx = max(-MAX_RIDER_SHIFT_M, -x_seated), min(MAX_RIDER_SHIFT_M, w - x_seated)

    def share_at(dx, m):   # the rear share of a rider of mass m shifted dx (rear load over weight)
        return (rear_bike + m * g * (1.0 - (x_seated + dx) / w)) / (g * (m_bike + m))

    if fz_n is not None:
        # At a given rear load a rider further forward must be heavier: m(dx) = (fz - rear_bike) / (g (1 - x/w)).
        def mass_at(dx):
            return (fz - rear_bike) / (g * (1.0 - (x_seated + dx) / w))
        low, high = share_at(hi_dx, mass_at(hi_dx)), share_at(lo_dx, mass_at(lo_dx))
        low = max(low, fz / (g * (m_bike + MAX_RIDER_MASS_KG)))
        high = min(high, fz / (g * (m_bike + MIN_RIDER_MASS_KG)))
        seated_share = share_at(0.0, mass_at(0.0))
    else:
        low, high = share_at(hi_dx, mass), share_at(lo_dx, mass)
        seated_share = share_at(0.0, mass)
    x_rider = w * (1.0 - (fz - rear_bike) / (g * mass)) if mass > 0.0 else math.nan
    shift = x_rider - x_seated
    if not (human and lo_dx <= shift <= hi_dx):
        raise InputError(f"rear load share = {share_in!r} (unit 1) is outside the allowed range "
                         f"[{low:.4f}, {high:.4f}] for {what} on {bike.name!r}: the rider ({MIN_RIDER_MASS_KG:g}-"
                         f"{MAX_RIDER_MASS_KG:g} kg) moves at most {MAX_RIDER_SHIFT_M:g} m fore or aft of the "
                         f"seated posture, its mass centre inside the wheelbase; the seated share is "
                         f"{seated_share:.4f}")
    combined = seat(bike, yeadon_rider(rider, mass_kg=mass, height_m=height_m), shift_m=shift)
    achieved = static_loads(combined)[0]
    if abs(achieved - fz) > 1e-6:
        raise RuntimeError(f"rear load {achieved} N misses the requested {fz} N")
    return LoadShareSolution(combined=combined, rider_mass_kg=mass, shift_m=shift)


#: The rider's eleven Yeadon segments: pelvis, thorax, chest-head, the arms (upper, forearm-hand) and the legs
#: (thigh, shank-foot). Those no part of the model carries (:attr:`whipple_kick.model.parts.Split.segments`) stay
#: in the rear frame.
RIDER_SEGMENTS = ("P", "T", "C", "A1", "A2", "B1", "B2", "J1", "J2", "K1", "K2")


def _segments(human, seat_pt, names):
    """Mass [kg], mass centre [m] and inertia [kg m^2] of yeadon segments ``names`` in the benchmark frame."""
    mass, com, inertia = human.combine_inertia(tuple(names))
    com = seat_pt + YEADON_TO_BIKE @ np.asarray(com).ravel()
    inertia = YEADON_TO_BIKE @ np.asarray(inertia) @ YEADON_TO_BIKE.T
    com[1] = 0.0   # mid-plane symmetry (checked for the whole rider by place())
    inertia[0, 1] = inertia[1, 0] = inertia[1, 2] = inertia[2, 1] = 0.0
    return float(mass), com, inertia


def carriers(part_names):
    """The declared parts that split the rider for a model with parts ``part_names``, in build order.

    The model's parts that declare a :class:`~whipple_kick.model.parts.Split`, and every declared part the
    model lacks that holds its body rigidly (``Split.rigid``) and names segments one of them carries: its
    body is the rest of its segments, held as it declares (the upper body of the rigid rider whose arms take
    the forearms to the bar). Empty: the rider is not split.
    """
    chosen = [p for p in parts.named(part_names) if p.split is not None]
    taken = {s for p in chosen for s in p.split.segments}
    held = [n for n, p in parts.REGISTRY.items() if p.split is not None and p.split.rigid
            and p not in chosen and taken & set(p.split.segments)]
    return parts.named([p.name for p in chosen] + held) if chosen else ()


def segment_carriers(part_names):
    """The part that carries each of :data:`RIDER_SEGMENTS` in a model with ``part_names`` (None: the rear frame).

    Parts in build order each take the segments they name, a later one from an earlier one.
    """
    owner = dict.fromkeys(RIDER_SEGMENTS)
    for part in carriers(part_names):
        owner.update(dict.fromkeys(part.split.segments, part))
    return owner


class SplitRider(NamedTuple):
    """A rider split among the rear frame, the bicycle's frames and the parts' own bodies (:func:`split_rider`)."""

    combined: object   # Bicycle: the rear frame with the segments no part carries, the lumped parts' in theirs
    body: dict         # the own-body parts' parameters by name (a held part's too)
    body_mass: float   # [kg] of the own bodies, which ``combined`` lacks
    held: tuple        # (rigid, body) of each part the model lacks whose body the rear frame holds


def split_rider(bike, rider, part_names, shift_m=0.0):
    """Seat ``rider`` on ``bike`` split as the parts ``part_names`` of a model declare (:func:`carriers`).

    The rider is seated as by :func:`place`. Each part's :class:`~whipple_kick.model.parts.Split` says which
    Yeadon segments it carries and how: lumped into a frame of the bicycle (the forearms into the front
    frame) or as a body of its own (the upper body, its parameters by its ``body``). The segments no part
    carries are lumped into the rear frame. A part the model lacks whose split holds its body rigidly
    (``rigid``) is split off all the same and listed in ``held``: apply each to the Moore parameters.

    Parameters
    ----------
    bike : Bicycle
        Bicycle-only set with seating geometry.
    rider : YeadonRider
    part_names : tuple of str
        The model's parts.
    shift_m : float
        Fore-aft shift of the whole seated rider [m], forward positive (:func:`shifted`): a hinge at the seat
        point moves with it, the legs and the lumped segments with the rider.

    Returns
    -------
    SplitRider
    """
    seated = shifted(place(bike, rider), shift_m)
    human = rider.human(seated.configuration)
    seat_pt = seated.seat
    owner = segment_carriers(part_names)
    rest, bench, total = [s for s in RIDER_SEGMENTS if owner[s] is None], bike.benchmark, 0.0
    if rest:   # the segments no part carries, in the rear frame
        rest = _segments(human, seat_pt, rest)
        bench, total = lump_into_frame(bench, "B", *rest), rest[0]
    body, body_mass, held, titles = {}, 0.0, [], []
    for part in carriers(part_names):
        names = [s for s in part.split.segments if owner[s] is part]
        if not names:
            continue
        mass, com, inertia = _segments(human, seat_pt, names)
        total += mass
        titles.append(part.title or part.name)
        if part.split.frame:
            bench = lump_into_frame(bench, part.split.frame, mass, com, inertia)
            continue
        own = part.split.body(bike.benchmark, seat_pt, mass, com, inertia)
        body.update(own)
        body_mass += mass
        if part.name not in part_names:
            held.append((part.split.rigid, own))
    if abs(total - seated.mass) > 1e-9 * seated.mass:
        raise RuntimeError(f"the rider's segments sum to {total} kg, not {seated.mass} kg")
    combined = _with_rider(bike, rider, seated, bench, ", body" + _shift_label(shift_m),
                           f": split as the model's parts declare ({', '.join(titles)} carrying their segments), "
                           "the rest in the rear frame.")
    return SplitRider(combined, body, body_mass, tuple(held))


def seat_with_body(bike, rider, arms_on_bar=True, shift_m=0.0):
    """Seat a rider whose upper body leans on the saddle (the trunk part) and, with ``arms_on_bar``, whose
    forearms move with the bar (the arms part): :func:`split_rider` for those parts.

    Returns
    -------
    combined : Bicycle
        The bicycle with the legs (and forearms) lumped in; its ``rider`` metadata as :func:`seat`'s.
    body : dict
        The upper body's parameters by name (the trunk part's :data:`whipple_kick.model.parts.TRUNK`
        ``from_rider``), in Moore's rear frame C from the rear wheel centre.
    """
    split = split_rider(bike, rider, ("trunk", "arms") if arms_on_bar else ("trunk",), shift_m)
    return split.combined, split.body
