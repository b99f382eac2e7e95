"""The slip model at run time: the compiled C right-hand side, its parameters, steady motion and linearisation.

The C library is built from the symbolic equations by :mod:`whipple_kick.slip_build`
on a cache miss (once per version); this module only loads it (ctypes) with
the plain-data metadata written beside it, so a warm run imports neither
SymPy nor the derivation. One C call evaluates the right-hand side: the
kick-plate profile, the dependent speeds, slip and camber, normal forces,
the tyre block of the active transient form (:mod:`whipple_kick.transient`,
the ``tyre_transient`` parameter), the steer controller, Kane's equations
and the rates of the energy quadratures (:mod:`whipple_kick.energy`); the
named outputs (:data:`OUTPUTS`) only when asked for.

State vector layout (by name, see :data:`STATE_NAMES`): q1..q10, the
independent speeds u1 u2 u3 u4 u7 u9 u10, four tyre states in fixed slots
(:func:`tyre_state_names`: the contact patch's slip and camber angles, or
the thesis' relaxed forces fyr fyf mzr mzf, which :data:`X` also names),
and the quadratures of :data:`whipple_kick.energy.QUADRATURE_STATES`.
"""
import ctypes
import functools
import json
import math
import os
import shutil

import numpy as np

from . import cache, carcass, energy, kane, magic_formula, rhs_call, transient
from . import symbols as S
from .errors import InputError

COORDINATES = tuple(f"q{i}" for i in range(1, 11))
SPEEDS = tuple(f"u{i}" for i in range(1, 11))
DEPENDENT = ("u5", "u6", "u8")
INDEPENDENT = tuple(n for n in SPEEDS if n not in DEPENDENT)
#: Tyre-state slot names of the thesis' form (kept as aliases in :data:`X`).
TYRE_STATES = transient.STATES["force_lag"]
#: Tyre-state slot names of the default form.
PATCH_STATES = transient.STATES["contact_patch"]
QUADRATURE_STATES = energy.QUADRATURE_STATES
#: States integrated for the dynamics; the quadratures follow them.
DYNAMIC_STATES = COORDINATES + INDEPENDENT + PATCH_STATES
#: Coordinates nothing depends on (Moore's ignorable coordinates: the rear contact's position, the plate
#: being prescribed in time; the axisymmetric wheels' angles): their Jacobian columns are exactly zero
#: (a test), so the compiled Jacobian does not evaluate them.
IGNORABLE = ("q1", "q2", "q6", "q8")
#: Right-hand-side evaluations one compiled Jacobian costs (the budget counts them).
JACOBIAN_EVALUATIONS = len(DYNAMIC_STATES) + 1 - len(IGNORABLE)
STATE_NAMES = DYNAMIC_STATES + QUADRATURE_STATES
#: Named outputs the C function writes when asked, after all ten speeds: name -> (unit, what it is).
OUTPUTS = {
    "yp": ("m", "kick-plate lateral displacement along N.y"),
    "vp": ("m/s", "kick-plate lateral velocity"),
    "ap": ("m/s^2", "kick-plate lateral acceleration"),
    "slip_r": ("rad", "rear kinematic slip angle atan(vsy/|vx|), + = contact sliding right"),
    "slip_f": ("rad", "front kinematic slip angle atan(vsy/|vx|), + = contact sliding right"),
    "camber_r": ("rad", "rear wheel camber, + = top leaning right"),
    "camber_f": ("rad", "front wheel camber, + = top leaning right"),
    "vx_r": ("m/s", "rear wheel rolling speed relative to the plate, along its heading"),
    "vx_f": ("m/s", "front wheel rolling speed along its heading"),
    "fz_r": ("N", "rear tyre normal force"),
    "fz_f": ("N", "front tyre normal force"),
    "fy_ss_r": ("N", "rear steady lateral force at the kinematic slip and camber"),
    "fy_ss_f": ("N", "front steady lateral force at the kinematic slip and camber"),
    "mz_ss_r": ("N m", "rear steady aligning moment at the kinematic slip and camber"),
    "mz_ss_f": ("N m", "front steady aligning moment at the kinematic slip and camber"),
    "T7": ("N m", "steer torque of the rider's control law"),
    "kinetic_energy": ("J", "kinetic energy of the bicycle and rider"),
    "potential_energy": ("J", "gravitational potential energy"),
    "spring_energy": ("J", "energy stored in the vertical tyre springs"),
    "holonomic": ("m", "front contact height above the ground (the holonomic constraint's residual)"),
    "sliding_power": ("W", "power of the tyres' lateral forces on the contacts' sliding, F vsy"),
    "fy_r": ("N", "lateral force the rear tyre applies to the bicycle"),
    "fy_f": ("N", "lateral force the front tyre applies to the bicycle"),
    "mz_r": ("N m", "aligning moment the rear tyre applies to the bicycle"),
    "mz_f": ("N m", "aligning moment the front tyre applies to the bicycle"),
    "sigma_r": ("m", "rear relaxation length in use"),
    "sigma_f": ("m", "front relaxation length in use"),
    "patch_slip_r": ("rad", "slip angle the rear steady curve is evaluated at: the contact patch's (the kinematic "
                            "slip in force_lag)"),
    "patch_slip_f": ("rad", "slip angle the front steady curve is evaluated at: the contact patch's (the kinematic "
                            "slip in force_lag)"),
    "fy_limit_r": ("N", "rear friction limit on the side of its force: the steady curve's extreme at the current "
                        "load and camber (patch slip within the carcass tyre's cap)"),
    "fy_limit_f": ("N", "front friction limit on the side of its force: the steady curve's extreme at the current "
                        "load and camber (patch slip within the carcass tyre's cap)"),
}
#: Every output by position: the ten speeds (dependent ones included), then :data:`OUTPUTS`.
OUTPUT_NAMES = SPEEDS + tuple(OUTPUTS)
PARAMETER_NAMES = S.SLIP_CONSTANTS
X = {n: i for i, n in enumerate(STATE_NAMES)}
X.update({n: X[m] for n, m in zip(TYRE_STATES, PATCH_STATES, strict=True)})
X.update({n: X[m] for n, m in zip(transient.STATES["carcass"], PATCH_STATES, strict=True)})
OUT = {n: i for i, n in enumerate(OUTPUT_NAMES)}
P = {n: i for i, n in enumerate(PARAMETER_NAMES)}

#: Package modules the compiled library is generated from (its cache key hashes them).
_SOURCES = ("symbols", "derivation", "codegen", "magic_formula", "transient", "carcass", "energy", "slip",
            "slip_build")
_PARTITION = kane.ConstraintPartition(SPEEDS, DEPENDENT)


def tyre_state_names(name=transient.DEFAULT_TRANSIENT):
    """Names of the four tyre-state slots under the transient form ``name``."""
    transient.check(name)
    return transient.STATES[name]


def _compiler():
    """Path of the C compiler: $CC if set (must exist), else cc, gcc or clang on PATH."""
    requested = os.environ.get("CC")
    if requested:
        cc = shutil.which(requested)
        if not cc:
            raise InputError(f"CC={requested!r} is not an executable C compiler; install gcc or fix CC")
        return cc
    cc = shutil.which("cc") or shutil.which("gcc") or shutil.which("clang")
    if not cc:
        raise InputError("no C compiler found (looked for cc, gcc, clang on PATH): install gcc or set CC")
    return cc


_CFLAGS = ("-O2", "-fPIC", "-shared", "-std=c99")


@functools.cache
def _native_call():
    """The compiled call extension (:func:`whipple_kick.rhs_call.module`), or None; looked up once per process."""
    return rhs_call.module(_compiler())


def layout():
    """The layouts the running code expects of the compiled library (as its metadata records them)."""
    return {"states": list(STATE_NAMES), "parameters": list(PARAMETER_NAMES), "outputs": list(OUTPUT_NAMES),
            "dynamic_states": len(DYNAMIC_STATES)}


def _metadata_matches(path):
    """Whether the metadata file at ``path`` exists, is private and records the running code's layouts."""
    try:
        cache.check_private_file(path)
        return json.loads(path.read_text()).get("layout") == layout()
    except (OSError, ValueError, AttributeError):
        return False


def library_path():
    """Path of the compiled slip model in the cache, built first on a cache miss.

    The cache entry is ``slip_<key>.so`` with its C source and plain-data
    metadata (``slip_<key>.json``) beside it, the key hashing the package
    sources it is generated from, the SymPy version, the compiler and its
    flags. A miss runs :func:`whipple_kick.slip_build.build_library` (SymPy,
    20-30 s, one line on stderr). An entry whose metadata is missing or
    records other layouts (states, parameters, outputs) is built again.
    """
    cc = _compiler()
    key = cache.source_hash(_SOURCES, extra=f"{os.path.basename(cc)} {' '.join(_CFLAGS)}")
    name = f"slip_{key}.so"

    def build(tmp):
        from . import slip_build  # SymPy and the derivation: only on a cache miss
        slip_build.build_library(tmp, key, cc, _CFLAGS)

    lib_path = cache.build_once(name, build)
    if not _metadata_matches(lib_path.with_suffix(".json")):
        with cache.locked(lib_path):
            lib_path.unlink(missing_ok=True)
        lib_path = cache.build_once(name, build)
        if not _metadata_matches(lib_path.with_suffix(".json")):
            raise RuntimeError(f"the compiled slip model {lib_path} has no matching metadata; remove the cache folder")
    return lib_path


def model_hash():
    """Name of the compiled slip model in use (``slip_<key>``, its cache entry): what a sweep folder records."""
    return os.path.splitext(os.path.basename(library()._name))[0]


@functools.cache
def library():
    """The compiled slip model (ctypes library of :func:`library_path`), loaded once per process."""
    lib = ctypes.CDLL(str(library_path()))
    pointer = ctypes.c_void_p
    lib.wk_slip_rhs.restype = ctypes.c_int
    lib.wk_slip_rhs.argtypes = [ctypes.c_double, pointer, pointer, pointer, pointer]
    lib.wk_slip_outputs.restype = ctypes.c_int
    lib.wk_slip_outputs.argtypes = [ctypes.c_int, pointer, pointer, pointer, pointer]
    lib.wk_slip_jacobian.restype = ctypes.c_int
    lib.wk_slip_jacobian.argtypes = [ctypes.c_double, pointer, pointer, pointer, pointer]
    lib.wk_slip_impulse_terms.restype = ctypes.c_int
    lib.wk_slip_impulse_terms.argtypes = [ctypes.c_double, pointer, pointer, pointer, pointer, pointer]
    lib.wk_slip_cornering_stiffness.restype = ctypes.c_int
    lib.wk_slip_cornering_stiffness.argtypes = [ctypes.c_double, ctypes.c_double, pointer, pointer]
    sizes = (ctypes.c_int * 4)()
    lib.wk_slip_sizes(sizes)
    if tuple(sizes) != (len(STATE_NAMES), len(PARAMETER_NAMES), len(OUTPUT_NAMES), len(DYNAMIC_STATES)):
        raise RuntimeError(f"compiled slip model has sizes {tuple(sizes)}; rebuild the cache")
    return lib


# ------------------------------------------------------------------- interface

def parameter_vector(params):
    """Parameter array for the compiled model, looked up by name.

    Raises
    ------
    InputError
        If a name is missing or unknown.
    """
    missing = [n for n in PARAMETER_NAMES if n not in params]
    if missing:
        raise InputError(f"slip-model parameters are missing: {', '.join(missing[:8])}"
                         + (" ..." if len(missing) > 8 else ""))
    unknown = [n for n in params if n not in P]
    if unknown:
        raise InputError(f"unknown slip-model parameters: {', '.join(sorted(unknown)[:8])}")
    return np.array([float(params[n]) for n in PARAMETER_NAMES])


class CompiledRHS:
    """Callable ``f(t, x) -> dx/dt`` backed by the C library, for one parameter set.

    Parameters
    ----------
    params : mapping
        Every name in :data:`PARAMETER_NAMES`.

    Example
    -------
    >>> rhs = CompiledRHS(steady.params)           # doctest: +SKIP
    >>> dx = rhs(0.0, steady.x)                    # doctest: +SKIP
    """

    def __init__(self, params):
        self.lib = library()
        self.p = np.ascontiguousarray(parameter_vector(params))
        self._p_ptr = self.p.ctypes.data
        self._dx = np.empty(len(STATE_NAMES))
        self._dx_ptr = self._dx.ctypes.data
        self._out = np.empty(len(OUTPUT_NAMES))
        self._out_ptr = self._out.ctypes.data
        self.fast = self.guarded()   # f(t, x): one foreign call (what the integrators call)

    @property
    def transient(self):
        """Name of the tyre transient form of these parameters."""
        return transient.TRANSIENTS[int(self.p[P["tyre_transient"]])]

    def __call__(self, t, x):
        return self.fast(t, x)

    def guarded(self, index=0, limit=math.inf, exception=None, index2=0, limit2=math.inf):
        """A fast ``f(t, x)`` that raises ``exception`` once ``|x[index]| > limit`` or ``|x[index2]| > limit2``.

        Where the Python headers are available this is an object of the
        compiled :mod:`whipple_kick.rhs_call` extension: one foreign call,
        no Python code, per evaluation (the integrator's hot path, about 1e4
        calls per run). Otherwise one Python frame with everything bound
        locally around the ctypes call. Without ``exception`` nothing is checked.
        """
        native = _native_call()
        if native is not None:
            address = ctypes.cast(self.lib.wk_slip_rhs, ctypes.c_void_p).value
            return native.Rhs(address, self.p, len(STATE_NAMES), _raise_status, exception, index, limit, index2,
                              limit2)
        fn, p_ptr, dx_ptr, dx = self.lib.wk_slip_rhs, self._p_ptr, self._dx_ptr, self._dx
        if exception is None:
            limit = limit2 = math.inf

        def f(t, x):
            if abs(x[index]) > limit or abs(x[index2]) > limit2:
                raise exception
            x = np.ascontiguousarray(x, dtype=float)
            status = fn(t, x.ctypes.data, p_ptr, dx_ptr, None)
            if status:
                _raise_status(status, t)
            return dx.copy()
        return f

    def jacobian_function(self, scale):
        """``J(t, x)``: Jacobian d(dx/dt)/dx by forward differences in C (quadrature columns exactly 0).

        Parameters
        ----------
        scale : array_like
            Typical size of each state; the step is ``1.5e-8 max(|x_j|, scale_j)``.

        Returns
        -------
        callable
            ``jac(t, x)``; its ``evaluations`` attribute is the number of
            right-hand-side evaluations one call makes (:data:`JACOBIAN_EVALUATIONS`:
            dynamic states + 1, less the :data:`IGNORABLE` columns).
        """
        scale = np.ascontiguousarray(scale, dtype=float)
        n = len(STATE_NAMES)
        fn, p_ptr, s_ptr = self.lib.wk_slip_jacobian, self._p_ptr, scale.ctypes.data

        def jac(t, x):
            x = np.ascontiguousarray(x, dtype=float)
            J = np.empty((n, n))
            status = fn(t, x.ctypes.data, p_ptr, s_ptr, J.ctypes.data)
            if status:
                _raise_status(status, t)
            return J
        jac.scale = scale   # keeps the array alive with the closure
        jac.evaluations = JACOBIAN_EVALUATIONS   # right-hand-side evaluations per call (the budget counts them)
        return jac

    def impulse_terms(self, t, x):
        """Mass matrix M (10, 10), constraint matrix A (3, 10) and offset a0 (3,) at ``(t, x)``."""
        x = np.ascontiguousarray(x, dtype=float)
        n, m = len(SPEEDS), len(DEPENDENT)
        M, A, a0 = np.empty((n, n)), np.empty((m, n)), np.empty(m)
        self.lib.wk_slip_impulse_terms(t, x.ctypes.data, self._p_ptr, M.ctypes.data, A.ctypes.data,
                                       a0.ctypes.data)
        return M, A, a0

    def outputs_at(self, t, X):
        """Named outputs (:data:`OUTPUT_NAMES`) at many samples, in one C call.

        Parameters
        ----------
        t : array_like, shape (n,)
            Times [s].
        X : array_like, shape (n, len(STATE_NAMES))
            States.

        Returns
        -------
        ndarray, shape (n, len(OUTPUT_NAMES))
        """
        t = np.ascontiguousarray(t, dtype=float)
        X = np.ascontiguousarray(X, dtype=float)
        if X.shape != (t.size, len(STATE_NAMES)):
            raise ValueError(f"states must have shape ({t.size}, {len(STATE_NAMES)}), got {X.shape}")
        out = np.empty((t.size, len(OUTPUT_NAMES)))
        status = self.lib.wk_slip_outputs(t.size, t.ctypes.data, X.ctypes.data, self._p_ptr, out.ctypes.data)
        if status:
            raise FloatingPointError(_STATUS.get(status, f"status {status}") + " while evaluating outputs")
        return out

    def outputs(self, t, x):
        """Derivatives and named outputs (:data:`OUTPUT_NAMES`) at one state."""
        x = np.ascontiguousarray(x, dtype=float)
        status = self.lib.wk_slip_rhs(t, x.ctypes.data, self._p_ptr, self._dx_ptr, self._out_ptr)
        if status:
            _raise_status(status, t)
        return self._dx.copy(), self._out.copy()


_STATUS = {
    1: "singular constraint or mass matrix in the slip model",
    2: "non-finite derivative in the slip model",
}


def _raise_status(status, t):
    """Raise the model's error for a nonzero status of its C function at time ``t`` [s]."""
    raise FloatingPointError(_STATUS.get(status, f"status {status}") + f" at t = {t:.6g} s")


# ------------------------------------------------------- parameters and steady state

#: Magic-Formula coefficients that shift the curves at zero slip and camber
#: (Sh and Sv terms not multiplied by camber). "Symmetric tyres" zero them.
FY_OFFSET_INDICES = magic_formula.FY_OFFSET_INDICES
MZ_OFFSET_INDICES = magic_formula.MZ_OFFSET_INDICES
GAIN_NAMES = ("kq3", "kq4", "kq7", "ku3", "ku4", "ku7")


def tyre_parameters(tyre, wheel, symmetric=False, lateral=True, reverse_camber=False):
    """Slip-model parameters of one tyre, by name.

    Parameters
    ----------
    tyre : whipple_kick.tyres.Tyre
        A loaded tyre (its ``blend`` gives one or two coefficient sets).
    wheel : {"r", "f"}
        Rear or front.
    symmetric : bool
        Zero the zero-slip offsets (:data:`FY_OFFSET_INDICES`, :data:`MZ_OFFSET_INDICES`).
    lateral : bool
        False switches the tyre's lateral force and moment off.
    reverse_camber : bool
        Evaluate the curves at the opposite camber
        (:func:`whipple_kick.magic_formula.camber_reversed`): the thesis
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


def model_parameters(moore, rear_tyre, front_tyre, gains=None, kick=None,
                     symmetric=False, lateral=True, drive_torque=0.0,
                     tyre_transient=transient.DEFAULT_TRANSIENT, reverse_camber=False,
                     carcass_sliding=carcass.DEFAULT_SLIDING, carcass_damping=0.0,
                     carcass_viscosity=carcass.SLIDING_VISCOSITY, slip_speed="wheel_centre"):
    """Assemble the slip model's parameters by name.

    Parameters
    ----------
    moore : mapping
        Moore parameters of the bicycle (with rider).
    rear_tyre, front_tyre : whipple_kick.tyres.Tyre
        Loaded tyres.
    gains : mapping, optional
        Steer-torque gains by name (:data:`GAIN_NAMES`); missing ones are 0.
        ``T7 = -(kq4 q4 + kq7 q7 + ku4 u4 + ku7 u7 + kq3 q3 + ku3 u3)``.
    kick : mapping, optional
        ``t0`` [s], ``duration`` [s], ``displacement`` [m, + to the right],
        ``profile`` (0 constant acceleration, 1 minimum jerk, 2 one cubic
        segment ``c0 + c1 tau + c2 tau^2 + c3 tau^3`` with ``tau = t - t0``,
        given as ``coefficients`` = (c0, c1, c2, c3) in m, m/s, m/s^2, m/s^3;
        see :func:`whipple_kick.inputs.cubic_segments`). Default: no kick.
    symmetric, lateral, reverse_camber : bool
        See :func:`tyre_parameters`.
    drive_torque : float
        Constant rear-wheel torque T6c [N m] about the rear frame's C.y axis
        (+ opposes forward rolling); the steady-state solver sets it.
    tyre_transient : str
        One of :data:`whipple_kick.transient.TRANSIENTS` (default ``carcass``).
    carcass_sliding : {"peak", "curve"}
        The carcass tyre's friction limit past the peak (:mod:`whipple_kick.carcass`).
    carcass_damping : float
        Lateral damping of both carcasses [N s/m], parallel to their stiffness
        (default 0).
    carcass_viscosity : float
        :data:`whipple_kick.carcass.SLIDING_VISCOSITY` [N s/m]: the
        regularisation of an undamped carcass' Coulomb plateau. The stiffnesses ``ccr``/``ccf`` are set by
        :func:`steady_state` (or :func:`upright_state`) from the loads of the
        state found: ``C_Fa(F_z0) / sigma0``.
    slip_speed : {"wheel_centre", "contact_point"}
        Whose forward speed along the wheel's heading the slip angle
        ``atan(vsy / |vx|)`` and the relaxation ``sigma / |vx|`` use: the
        wheel centre's (default) or the geometric contact point's, as the
        thesis authors' published code takes it (parameter ``slip_speed_point``).
    """
    if slip_speed not in SLIP_SPEEDS:
        raise InputError(f"slip speed {slip_speed!r} is unknown; choose one of {', '.join(SLIP_SPEEDS)}")
    params = {n: float(moore[n]) for n in S.CLASSIC_CONSTANTS}
    params.update(tyre_parameters(rear_tyre, "r", symmetric, lateral, reverse_camber))
    params.update(tyre_parameters(front_tyre, "f", symmetric, lateral, reverse_camber))
    gains = dict(gains or {})
    unknown = set(gains) - set(GAIN_NAMES)
    if unknown:
        raise InputError(f"unknown controller gains {sorted(unknown)}; known: {', '.join(GAIN_NAMES)}")
    params.update({n: float(gains.get(n, 0.0)) for n in GAIN_NAMES})
    kick = dict(kick or {})
    params.update({
        "kick_t0": float(kick.get("t0", 0.0)),
        "kick_T": float(kick.get("duration", 0.15)),
        "kick_D": float(kick.get("displacement", 0.0)),
        "kick_profile": float(kick.get("profile", 0)),
        **{f"kick_c{i}": float(c) for i, c in enumerate(kick.get("coefficients", (0.0, 0.0, 0.0, 0.0)))},
        "T6c": float(drive_torque),
        "tyre_transient": float(transient.check(tyre_transient)),
        "vsx_r": 0.0,
        "slip_speed_point": float(SLIP_SPEEDS.index(slip_speed)),
        "ccr": 0.0, "ccf": 0.0,   # set from the steady loads (_steady_tyre_states)
        "dcr": float(carcass_damping), "dcf": float(carcass_damping),
        "carcass_sliding": float(carcass.check_sliding(carcass_sliding)),
        "carcass_viscosity": float(carcass_viscosity),
    })
    return params


def kept_speeds_slide(rhs, t, x):
    """The rear slide ``vsx_r`` [m/s] that keeps every speed across a plate-velocity jump at ``t``.

    The thesis authors' published code integrates all speeds as states and
    enforces the rear no-slip condition only through its time derivative, so
    when the plate stops instantly no speed jumps and the condition is left
    violated by a constant: the rear contact keeps sliding along its heading,
    relative to the stopped plate, at the plate's velocity before the stop
    times sin(yaw) (0.204 m/s in their 500 kPa run). This returns that slide
    (``rhs``'s own ``vsx_r`` included), to be imposed by the rear constraint
    for the rest of the run.

    Parameters
    ----------
    rhs : CompiledRHS
        Whose plate velocity jumps at ``t`` (``t`` itself belongs to after).
    t : float
        Time of the jump [s].
    x : array_like
        State arriving at ``t``.

    Returns
    -------
    float
    """
    x = np.asarray(x, dtype=float)
    ind = [X[n] for n in INDEPENDENT]
    _, A, a0_plus = rhs.impulse_terms(t, x)
    _, _, a0_minus = rhs.impulse_terms(np.nextafter(t, -np.inf), x)
    u = _PARTITION.dependent_speeds(A, a0_minus, x[ind])
    residual = A @ u + a0_plus
    # The rear row (vsx_r enters it as -vsx_r) is the only one the plate appears in.
    return float(rhs.p[P["vsx_r"]] + residual[0])


def velocity_jump(rhs, t, x, impulse=True):
    """Carry the state across a jump of the plate velocity at ``t`` (the plate stop).

    Parameters
    ----------
    rhs : CompiledRHS
        Whose plate velocity jumps at ``t`` (``t`` itself belongs to after).
    t : float
        Time of the jump [s].
    x : array_like
        State arriving at ``t``.
    impulse : bool
        True: the rear no-slip constraint's impulse
        (:func:`whipple_kick.kane.impulsive_projection`) sets all speeds and
        its work is added to the plate's work W_plate. False: the
        independent speeds are kept and only the dependent ones re-solved.

    Returns
    -------
    x_after : ndarray
    info : dict
        ``time_s``, ``kinetic_energy_change_j`` (from the kinetic-energy
        expression before and after), ``impulse_work_j`` (``-1/2 L.(a0+ + a0-)``,
        the same change computed from the impulse: an independent check;
        None without impulse) and ``constraint_impulse_n_s`` (``L``).
    """
    x = np.array(x, dtype=float)
    before = np.nextafter(t, -np.inf)
    M, A, a0_plus = rhs.impulse_terms(t, x)
    _, _, a0_minus = rhs.impulse_terms(before, x)
    ind = [X[n] for n in INDEPENDENT]
    ke_before = rhs.outputs(before, x)[1][OUT["kinetic_energy"]]
    work, impulse_value = None, None
    if impulse:
        u_minus = _PARTITION.dependent_speeds(A, a0_minus, x[ind])
        u_plus, impulse_value = kane.impulsive_projection(M, A, u_minus, a0_plus)
        x[ind] = u_plus[_PARTITION.ind]
        work = float(-0.5 * impulse_value @ (a0_plus + a0_minus))
        x[X["W_plate"]] += work
    ke_after = rhs.outputs(t, x)[1][OUT["kinetic_energy"]]
    return x, {"time_s": float(t), "kinetic_energy_change_j": float(ke_after - ke_before),
               "impulse_work_j": work,
               "constraint_impulse_n_s": None if impulse_value is None else [float(v) for v in impulse_value]}


# ---------------------------------------------------------------- linearisation

#: States of the linearisation in the heading frame: every dynamic state
#: except the ignorable position q1, q2 and wheel angles q6, q8, the yaw angle
#: q3 (the model is invariant to heading while the plate is at rest), the
#: dependent pitch q5, with the rear-contact velocity [m/s] resolved in the
#: heading frame: ``v_fwd`` along N.x and ``v_lat`` along N.y, both turned by
#: the yaw angle q3 about N.z (N.z points down, so ``v_lat`` > 0 is a drift to
#: the right). The last four are the tyre slots, named here for the default
#: transient form (:func:`linear_states` names them for any). See :func:`linearize`.
LINEAR_STATES = ("q4", "q7", "q9", "q10", "v_fwd", "v_lat", "u3", "u4", "u7", "u9", "u10") + PATCH_STATES


def linear_states(name=transient.DEFAULT_TRANSIENT):
    """:data:`LINEAR_STATES` with the tyre slots named for the transient form ``name``."""
    return LINEAR_STATES[:-len(PATCH_STATES)] + tyre_state_names(name)


def solve_pitch(rhs, x, tol=1e-14, max_iter=30):
    """Return ``x`` with q5 re-solved so the front contact is on the ground (Newton)."""
    x = np.array(x, dtype=float)
    h_step = 1e-7
    for _ in range(max_iter):
        h = rhs.outputs(0.0, x)[1][OUT["holonomic"]]
        xp = x.copy()
        xp[X["q5"]] += h_step
        slope = (rhs.outputs(0.0, xp)[1][OUT["holonomic"]] - h) / h_step
        step = h / slope
        x[X["q5"]] -= step
        if abs(step) < tol:
            return x
    raise FloatingPointError(f"pitch did not converge (last step {abs(step):.3g} rad)")


def heading_state(x):
    """The :data:`LINEAR_STATES` values of a full state ``x`` (velocities along the heading)."""
    c, s = np.cos(x[X["q3"]]), np.sin(x[X["q3"]])
    u1, u2 = x[X["u1"]], x[X["u2"]]
    z = np.array([x[X[n]] if n in X else 0.0 for n in LINEAR_STATES])
    z[LINEAR_STATES.index("v_fwd")] = c * u1 + s * u2
    z[LINEAR_STATES.index("v_lat")] = -s * u1 + c * u2
    return z


def _heading_derivative(rhs, x_ref, z, t, resolve_pitch):
    """d/dt of the heading-frame state ``z`` (yaw set to 0; pitch re-solved if a coordinate moved)."""
    x = np.array(x_ref, dtype=float)
    x[X["q3"]] = 0.0
    for name, value in zip(LINEAR_STATES, z, strict=True):
        if name == "v_fwd":
            x[X["u1"]] = value
        elif name == "v_lat":
            x[X["u2"]] = value
        else:
            x[X[name]] = value
    if resolve_pitch:
        x = solve_pitch(rhs, x)
    dx = rhs(t, x)
    u1, u2, u3 = x[X["u1"]], x[X["u2"]], x[X["u3"]]
    # Rotating-frame rates at q3 = 0: d(v_fwd)/dt = u1' + u3 u2, d(v_lat)/dt = u2' - u3 u1.
    rates = {"v_fwd": dx[X["u1"]] + u3 * u2, "v_lat": dx[X["u2"]] - u3 * u1}
    return np.array([rates[n] if n in rates else dx[X[n]] for n in LINEAR_STATES])


def linearize(rhs, x, step=1e-7, t=0.0):
    """Jacobian of the slip model in the heading frame, about the state ``x``.

    Resolving the rear-contact velocity along the heading removes the yaw
    angle from the equations (the plate must be at rest), so a steady turn,
    which rotates u1 and u2, is an equilibrium of the linearised system and
    its eigenvalues are exact. States :data:`LINEAR_STATES`; perturbed
    coordinates re-solve the pitch so every evaluated state satisfies the
    holonomic constraint. Central differences.

    Parameters
    ----------
    rhs : CompiledRHS
    x : array_like
        Full state (e.g. ``SteadyState.x``); its q3 is ignored.
    step : float
        Relative finite-difference step (tyre force states use 100 times it).
    t : float
        Time [s] at which to evaluate (the plate must be at rest then).

    Returns
    -------
    ndarray, shape (15, 15)
    """
    z0 = heading_state(x)
    x = solve_pitch(rhs, x)   # once for the reference; again only when a coordinate is perturbed
    J = np.empty((z0.size, z0.size))
    # Tyre force states (force_lag) are ~100 N: a step 100 times larger.
    force_scale = 1e2 if rhs.transient == "force_lag" else 1.0
    for j, name in enumerate(LINEAR_STATES):
        h = step * max(1.0, abs(z0[j])) * (force_scale if name in PATCH_STATES else 1.0)
        zp, zm = z0.copy(), z0.copy()
        zp[j] += h
        zm[j] -= h
        moved = name.startswith("q")
        J[:, j] = (_heading_derivative(rhs, x, zp, t, moved) - _heading_derivative(rhs, x, zm, t, moved)) / (2 * h)
    return J


#: Row of the constraint matrix A (:meth:`CompiledRHS.impulse_terms`) that is the
#: holonomic constraint's rate: its entries are d(front contact height)/dq_i,
#: since u_i = dq_i/dt (derivation.slip_equations: rear no-slip, front no-slip, holonomic).
HOLONOMIC_ROW = 2


@functools.cache
def _difference_scales(form):
    """Typical size of each state for the C Jacobian's steps ``1.5e-8 max(|x_j|, scale_j)``.

    Angles [rad] and speeds [m/s, rad/s] 1, compressions 1e-3 m, the
    force-lag states 100 (N, N m). Steps about 1.5e-8 of these keep forward
    differences at ~1e-7 relative (round-off ~eps/step times the terms'
    size, truncation ~step/2 times the curvature), and the compression's
    step stays far below a tyre's static compression even at 1e10 N/m
    (6e-8 m), so the normal force's kink is never crossed. (The integrator's
    scales, 100 to 1e4 times smaller, serve LSODA's Newton iteration but
    leave 1e-5 round-off here.) Read-only.
    """
    scale = np.ones(len(STATE_NAMES))
    for name in ("q9", "q10"):
        scale[X[name]] = 1e-3
    if form == "force_lag":
        scale[[X[s] for s in TYRE_STATES]] = 1e2
    if form == "carcass":   # deflections ~1e-2 m at the friction limit
        scale[[X["carcass_y_r"], X["carcass_y_f"]]] = 1e-2
    scale.flags.writeable = False
    return scale


#: Full-state slot of each heading-frame state (v_fwd, v_lat are u1, u2 at zero yaw).
_HEADING_SLOTS = np.array([X[{"v_fwd": "u1", "v_lat": "u2"}.get(n, n)] for n in LINEAR_STATES])
#: Heading-frame coordinates the front contact height depends on (pitch q5 follows them).
_PITCH_DRIVERS = [(LINEAR_STATES.index(n), SPEEDS.index("u" + n[1:])) for n in ("q4", "q7", "q9", "q10")]
_I_FWD, _I_LAT, _I_U3 = (LINEAR_STATES.index(n) for n in ("v_fwd", "v_lat", "u3"))


def heading_linearisation(rhs, x, t=0.0):
    """The Jacobian of :func:`linearize` and the steer-torque column, from one C Jacobian.

    The same heading-frame linear model as :func:`linearize` (states
    :data:`LINEAR_STATES`), obtained by the chain rule instead of by
    perturbing the heading-frame state: with ``x(z)`` the full state of a
    heading-frame state ``z`` (yaw 0, ``u1 = v_fwd``, ``u2 = v_lat``, pitch
    on the holonomic constraint), ``dz'/dz = S J E + R E``, where ``J`` is
    the compiled model's own Jacobian (:meth:`CompiledRHS.jacobian_function`,
    forward differences in C, steps :func:`_difference_scales`), ``E =
    dx/dz`` embeds ``z`` (its pitch row ``-h_q / h_q5`` is the exact gradient
    of the front contact height, :data:`HOLONOMIC_ROW`), ``S`` picks the rows
    and ``R`` holds the rotating-frame terms of ``v_fwd' = u1' + u3 u2``,
    ``v_lat' = u2' - u3 u1``. About 25 right-hand-side evaluations' worth of
    time instead of about 110 (``scripts/bench_stability.py``); agrees with
    :func:`linearize` to 1e-7 of each column's largest entry
    (``tests/test_stability.py``).

    The steer-torque column is exact: the model is affine in the steer
    torque ``T7 = -(... + ku7 u7)`` and its coefficient depends on the
    coordinates only, so two evaluations that differ only in ``ku7`` give it.

    Parameters
    ----------
    rhs : CompiledRHS
    x : array_like
        Full state (e.g. ``SteadyState.x``); its q3 is ignored, u1 and u2 are
        resolved along the heading. The plate must be at rest at ``t``.
    t : float
        Time [s].

    Returns
    -------
    A : ndarray, shape (15, 15)
        ``d(dz/dt)/dz`` of the model as parametrised (closed loop when
        ``rhs`` carries the rider's gains).
    B : ndarray, shape (15, 1)
        Per unit steer torque T7 [N m].

    Example
    -------
    >>> A, B = heading_linearisation(CompiledRHS(steady.params), steady.x)   # doctest: +SKIP
    """
    z = heading_state(x)
    x0 = np.array(x, dtype=float)
    x0[X["q3"]] = 0.0
    x0[X["u1"]], x0[X["u2"]] = z[_I_FWD], z[_I_LAT]
    if abs(rhs.outputs(t, x0)[1][OUT["holonomic"]]) > 1e-13:   # a steady state is on it already
        x0 = solve_pitch(rhs, x0)
    nd = len(DYNAMIC_STATES)
    J = rhs.jacobian_function(_difference_scales(rhs.transient))(t, x0)[:nd, :nd]
    h_q = rhs.impulse_terms(t, x0)[1][HOLONOMIC_ROW]
    # A = S J E: the picked columns of J, plus the pitch column times dq5/dz.
    A = J[np.ix_(_HEADING_SLOTS, _HEADING_SLOTS)]
    pitch_column = J[_HEADING_SLOTS, X["q5"]]
    for j, k in _PITCH_DRIVERS:
        A[:, j] -= pitch_column * (h_q[k] / h_q[SPEEDS.index("u5")])
    u1, u2, u3 = x0[X["u1"]], x0[X["u2"]], x0[X["u3"]]
    A[_I_FWD, _I_U3] += u2
    A[_I_FWD, _I_LAT] += u3
    A[_I_LAT, _I_U3] -= u1
    A[_I_LAT, _I_FWD] -= u3
    # Steer-torque column: with u7 moved to u7 + 1 (any value != 0 would do), raising
    # ku7 by 1 changes T7 by -(u7 + 1) and nothing else.
    x0[X["u7"]] += 1.0
    k = P["ku7"]
    f_base = rhs(t, x0)
    saved = rhs.p[k]
    try:
        rhs.p[k] = saved + 1.0
        f_bumped = rhs(t, x0)
    finally:
        rhs.p[k] = saved
    B = ((f_base - f_bumped)[_HEADING_SLOTS] / x0[X["u7"]]).reshape(-1, 1)
    return A, B


def linear_state_space(params, x, step=1e-7):
    """Open-loop ``A`` and steer-torque input ``B`` of the slip model about ``x``.

    ``x`` is a steady state of the closed loop with the gains in ``params``
    (the steady steer torque ``-K x`` stays applied as a constant). Because
    the controller enters as ``T7 = -K x``, the closed-loop Jacobian is
    ``A - B K``; ``B`` is the change of that Jacobian when the steer-rate
    gain grows by 1 N m s/rad, so both come from the compiled model.

    Returns
    -------
    A : ndarray (15, 15)
    B : ndarray (15, 1)
        Per unit steer torque T7 [N m].
    K : ndarray (1, 15)
        The gains of ``params`` on :data:`LINEAR_STATES` (so ``A - B K`` is the closed loop).
    """
    if params.get("kq3", 0.0):
        raise InputError("linear_state_space: a yaw-angle gain kq3 breaks the heading invariance")
    A_cl = linearize(CompiledRHS(params), x, step)
    bumped = dict(params)
    bumped["ku7"] = params["ku7"] + 1.0
    j = LINEAR_STATES.index("u7")
    B = (A_cl[:, j] - linearize(CompiledRHS(bumped), x, step)[:, j]).reshape(-1, 1)
    K = np.zeros((1, len(LINEAR_STATES)))
    for gain, state in (("kq4", "q4"), ("kq7", "q7"), ("ku3", "u3"), ("ku4", "u4"), ("ku7", "u7")):
        K[0, LINEAR_STATES.index(state)] = params[gain]
    return A_cl + B @ K, B, K
