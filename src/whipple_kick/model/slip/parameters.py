"""The model's parameters by name: the tyres', the bicycle's, the rider's gains, the kick's, the options'."""
from dataclasses import dataclass

import numpy as np

from whipple_kick.errors import InputError
from whipple_kick.model import carcass, magic_formula, parts, transient
from whipple_kick.model import symbols as S
import whipple_kick.model.slip.layout as layouts  # the module by its full name, not through the package

from .description import Model, Parameters

# ------------------------------------------------------- parameters and steady state

#: Magic-Formula coefficients that shift the curves at zero slip and camber
#: (Sh and Sv terms not multiplied by camber). "Symmetric tyres" zero them.
FY_OFFSET_INDICES = magic_formula.FY_OFFSET_INDICES
MZ_OFFSET_INDICES = magic_formula.MZ_OFFSET_INDICES
#: The rider's reflex in the base model by parameter name, with the rigid rider's values: none. (The
#: upper body and the arms are parts: a model without them has none of their parameters.)
RIGID_BODY = {"rq4": 0.0, "rq7": 0.0, "ru4": 0.0, "ru7": 0.0, "reflex_delay": 0.0}


def gain_states():
    """The state each gain of the rider's voluntary law multiplies (``T7 = -sum(gain * state)``), every
    declared part's gains included (a model without the part refuses its gains).

    Read from :data:`whipple_kick.model.parts.REGISTRY` when called, so a part declared after the package
    was imported (a test's, a script's) has its gains here.
    """
    table = dict(layouts.GAIN_STATES)
    for part in parts.REGISTRY.values():
        table.update(part.gains)
    return table


def gain_names():
    """Names of the rider's gains (:func:`gain_states`' keys, the bicycle's first), read when called."""
    return tuple(gain_states())


def _part_body():
    """Each declared part's parameters that are not gains, by part name (read when called: a part declared
    later counts too)."""
    return {p.name: tuple(n for n in p.parameters if n not in p.gains) for p in parts.REGISTRY.values()}


def body_names():
    """The rider's body parameters by name: the reflex (:data:`RIGID_BODY`), then each declared part's that
    are not gains (the leaning upper body's placement, inertia and hip spring-damper, the arms'
    spring-damper), read when called: a part declared later counts too."""
    return tuple(RIGID_BODY) + tuple(n for names in _part_body().values() for n in names)


def tyre_parameters(tyre, wheel, symmetric=False, lateral=True, reverse_camber=False):
    """Slip-model parameters of one tyre, by name.

    Parameters
    ----------
    tyre : whipple_kick.library.tyres.Tyre
        A loaded tyre (its ``blend`` gives one or two coefficient sets).
    wheel : {"r", "f"}
        Rear or front.
    symmetric : bool
        Zero the zero-slip offsets (:data:`FY_OFFSET_INDICES`, :data:`MZ_OFFSET_INDICES`).
    lateral : bool
        False switches the tyre's lateral force and moment off.
    reverse_camber : bool
        Evaluate the curves at the opposite camber
        (:func:`whipple_kick.model.magic_formula.camber_reversed`): the thesis
        authors' published code, whose camber thrust pushes a leaning wheel
        away from the lean. Not physical; for comparisons only.
    """
    if wheel not in ("r", "f"):
        raise ValueError(f"wheel must be 'r' or 'f', got {wheel!r}")
    sets = list(tyre.blend)
    if len(sets) == 1:
        # The second slot gets weight 0; filling it with the same (finite)
        # coefficients keeps 0 * value finite.
        sets = [sets[0], (0.0, sets[0][1], sets[0][2])]
    out = {
        f"rt{wheel}": tyre.crown_radius, f"kz{wheel}": tyre.vertical_stiffness,
        f"cz{wheel}": tyre.vertical_damping, f"sig{wheel}": tyre.relaxation_length,
        f"w{wheel}": sets[1][0], f"mu{wheel}": tyre.friction_scale,
        f"lam{wheel}": tyre.curve_scale if lateral else 0.0,
    }
    for k, (_, fy, mz) in enumerate(sets, start=1):
        fy, mz = np.array(fy, dtype=float), np.array(mz, dtype=float)
        if symmetric:
            fy[list(FY_OFFSET_INDICES)] = 0.0
            mz[list(MZ_OFFSET_INDICES)] = 0.0
        if reverse_camber:
            fy, mz = magic_formula.camber_reversed(fy, "fy"), magic_formula.camber_reversed(mz, "mz")
        out.update({f"a{wheel}{k}_{i}": v for i, v in enumerate(fy)})
        out.update({f"c{wheel}{k}_{i}": v for i, v in enumerate(mz)})
    return out


#: Whose forward speed the tyres' slip angle and relaxation use (:func:`model_parameters`), by the
#: value of the parameter ``slip_speed_point``.
SLIP_SPEEDS = ("wheel_centre", "contact_point")


@dataclass(frozen=True)
class ModelOptions:
    """The model's options (the fields of the scenario's model view, ``scenario.model_spec``, by the same names).

    Attributes
    ----------
    tyre_transient : str
        One of :func:`whipple_kick.model.transient.transients` (default ``carcass``).
    symmetric_tyres : bool
        Zero the zero-slip offsets (:func:`tyre_parameters`).
    camber_sign : {"physical", "reversed"}
        "reversed": the curves at the opposite camber (:func:`tyre_parameters`' ``reverse_camber``).
    carcass_sliding : {"peak", "curve"}
        The carcass tyre's friction limit past the peak (:mod:`whipple_kick.model.carcass`).
    carcass_damping : float
        Lateral damping of both carcasses [N s/m], parallel to their stiffness.
    carcass_viscosity : float
        :data:`whipple_kick.model.carcass.SLIDING_VISCOSITY` [N s/m]: the regularisation of an undamped
        carcass' Coulomb plateau.
    slip_speed : {"wheel_centre", "contact_point"}
        Whose forward speed along the wheel's heading the slip angle ``atan(vsy / |vx|)`` and the
        relaxation ``sigma / |vx|`` use: the wheel centre's (default) or the geometric contact point's, as
        the thesis authors' published code takes it (parameter ``slip_speed_point``).
    carcass_stiffness_scale : float
        Factor on the carcass stiffnesses the steady state sets.
    """

    tyre_transient: str = transient.DEFAULT_TRANSIENT
    symmetric_tyres: bool = False
    camber_sign: str = "physical"
    carcass_sliding: str = carcass.DEFAULT_SLIDING
    carcass_damping: float = 0.0
    carcass_viscosity: float = carcass.SLIDING_VISCOSITY
    slip_speed: str = "wheel_centre"
    carcass_stiffness_scale: float = 1.0


def model_parameters(moore, rear_tyre, front_tyre, options=None, *, model=None, gains=None, kick=None, body=None,
                     drive_torque=0.0, lateral=True):
    """Assemble the slip model's parameters by name, with the model they are for.

    Parameters
    ----------
    moore : mapping
        Moore parameters of the bicycle (with rider).
    rear_tyre, front_tyre : whipple_kick.library.tyres.Tyre
        Loaded tyres.
    options : ModelOptions or the scenario's model view, optional
        The model's options (read by the names of :class:`ModelOptions`' fields; default its defaults).
    model : whipple_kick.model.slip.description.Model, optional
        The model: its parts, the reflex's delay filter and its tyre form, which must be ``options``'; default
        the rigid rider without the delay filter.
    gains : mapping, optional
        Steer-torque gains by name (:func:`gain_names`); missing ones are 0.
        ``T7 = -(kq4 q4 + kq7 q7 + ku4 u4 + ku7 u7 + kq3 q3 + ku3 u3)``.
    kick : mapping, optional
        ``t0`` [s], ``duration`` [s], ``displacement`` [m, + to the right],
        ``profile`` (0 constant acceleration, 1 minimum jerk, 2 one cubic
        segment ``c0 + c1 tau + c2 tau^2 + c3 tau^3`` with ``tau = t - t0``,
        given as ``coefficients`` = (c0, c1, c2, c3) in m, m/s, m/s^2, m/s^3;
        see :func:`whipple_kick.library.inputs.cubic_segments`). Default: no kick.
    body : mapping, optional
        The rider's body by parameter name: the reflex (:data:`RIGID_BODY`, missing ones 0; a nonzero
        ``reflex_delay`` needs the model's delay filter) and every parameter of each of the model's parts
        that is not a gain (:func:`body_names`; the leaning upper body's placement and inertia from the
        rider's segments, :func:`whipple_kick.library.riders.split_rider`), and no other part's.
    drive_torque : float
        Constant rear-wheel torque T6c [N m] about the rear frame's C.y axis
        (+ opposes forward rolling); the steady-state solver sets it.
    lateral : bool
        False switches the tyres' lateral forces and moments off (:func:`tyre_parameters`).

    Returns
    -------
    whipple_kick.model.slip.description.Parameters
    """
    options = ModelOptions() if options is None else options
    opt = {name: getattr(options, name, default.default)
           for name, default in ModelOptions.__dataclass_fields__.items()}
    model = Model(transient=opt["tyre_transient"]) if model is None else model
    if model.transient != opt["tyre_transient"]:
        raise ValueError(f"the model's tyre form {model.transient!r} is not the options' {opt['tyre_transient']!r}")
    slip_speed = opt["slip_speed"]
    if slip_speed not in SLIP_SPEEDS:
        raise InputError(f"slip speed {slip_speed!r} is unknown; choose one of {', '.join(SLIP_SPEEDS)}")
    params = {n: float(moore[n]) for n in S.CLASSIC_CONSTANTS}
    reverse = opt["camber_sign"] == "reversed"
    params.update(tyre_parameters(rear_tyre, "r", opt["symmetric_tyres"], lateral, reverse))
    params.update(tyre_parameters(front_tyre, "f", opt["symmetric_tyres"], lateral, reverse))
    body = dict(body or {})
    part_body = _part_body()
    chosen = model.parts
    known = tuple(RIGID_BODY) + tuple(n for name in chosen for n in part_body[name])
    unknown = set(body) - set(known)
    if unknown:
        owners = sorted({name for name, names in part_body.items() if set(names) & unknown})
        raise InputError(f"rider-body parameters {sorted(unknown)} are not the {model.layout.key} model's"
                         + (f" (they are the {', '.join(owners)} part's: a model with it takes them)" if owners else "")
                         + f"; known: {', '.join(known)}")
    for name in chosen:   # a part's parameters: all of them
        names = part_body[name]
        if any(n not in body for n in names):
            part = parts.REGISTRY[name]
            raise InputError(f"{part.title or part.name} needs all of {', '.join(names)}; missing "
                             f"{', '.join(n for n in names if n not in body)}")
    delay = float(body.get("reflex_delay", 0.0))
    if (delay != 0.0) != model.delayed_reflex:
        raise InputError(f"reflex delay = {delay:g} s: " + ("a delay needs the model with the delay filter"
                                                            if delay else "the delay filter needs a delay > 0 s"))
    layout = model.layout
    gains = dict(gains or {})
    # A zero gain on a state the model does not have changes nothing; a nonzero one is refused.
    declared = gain_states()
    unknown = {n for n in set(gains) - set(layout.GAIN_NAMES) if n not in declared or gains[n] != 0.0}
    if unknown:
        raise InputError(f"unknown controller gains {sorted(unknown)} for the {layout.key} model; known: "
                         f"{', '.join(layout.GAIN_NAMES)}")
    params.update({n: float(gains.get(n, 0.0)) for n in layout.GAIN_NAMES})
    kick = dict(kick or {})
    params.update({
        "kick_t0": float(kick.get("t0", 0.0)),
        "kick_T": float(kick.get("duration", 0.15)),
        "kick_D": float(kick.get("displacement", 0.0)),
        "kick_profile": float(kick.get("profile", 0)),
        **{f"kick_c{i}": float(c) for i, c in enumerate(kick.get("coefficients", (0.0, 0.0, 0.0, 0.0)))},
        "T6c": float(drive_torque),
        "tyre_transient": float(transient.check(model.transient)),
        "vsx_r": 0.0,
        "slip_speed_point": float(SLIP_SPEEDS.index(slip_speed)),
        "ccr": 0.0, "ccf": 0.0,   # set from the steady loads (_steady_tyre_states)
        "dcr": float(opt["carcass_damping"]), "dcf": float(opt["carcass_damping"]),
        "carcass_sliding": float(carcass.check_sliding(opt["carcass_sliding"])),
        "carcass_viscosity": float(opt["carcass_viscosity"]),
        "carcass_stiffness_scale": float(opt["carcass_stiffness_scale"]),
    })
    params.update({n: float(body.get(n, RIGID_BODY[n])) for n in RIGID_BODY})
    params.update({n: float(body[n]) for name in chosen for n in part_body[name]})
    return Parameters(model, params)
