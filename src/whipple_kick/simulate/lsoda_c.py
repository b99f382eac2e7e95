"""LSODA driven from C with the compiled model: the fast path's chunk loop and the careful path.

:func:`whipple_kick.simulate.lsoda.integrate` integrates each smooth piece in
chunks of about half a second with ``odeint``'s LSODA, redoing a chunk in
which a limit is passed with the careful path (LSODA stepped from Python,
the fall event). Through ``odeint`` each right-hand side and Jacobian crosses
into Python and back, and each chunk sets LSODA up from Python. Here the
chunks of one piece run in one C call (``lsoda_src/driver.c``): SciPy's own
LSODA, ``lsoda_src/lsoda.c`` of SciPy 1.17.1 (its C translation of ODEPACK,
``scipy/integrate/src/lsoda.c`` at tag v1.17.1, commit 527eb7fd; BSD licence,
``lsoda_src/LICENSE-scipy.txt``), called with the options ``odeint`` gives it,
the model's ``wk_slip_rhs`` and ``wk_slip_jacobian`` by function pointer, and
the LAPACK routines SciPy's LSODA uses (``scipy.linalg.cython_lapack``'s
``dgetrf``/``dgetrs``): the same steps, evaluations and states, bit for bit
(``tests/simulate/test_lsoda_c.py``). The call stops before the first chunk
that the careful path must redo.

The careful path runs in C too (:meth:`FastChunks.careful`, one call per
chunk): the same LSODA stepped one step at a time as SciPy's
``scipy.integrate.LSODA`` steps it (its work arrays and options, ``itask`` 5),
the samples and the fall event from each step's interpolant (the polynomial
SciPy's ``LsodaDenseOutput`` builds from LSODA's Nordsieck history, evaluated
by Horner's rule as LSODA's own ``intdy``), the fall time by a port of SciPy's
``brentq`` (same tolerances), the budget and the stall window after every
step. So the same steps, evaluation counts, ending and messages as the
Python path; the samples, the fall time and the state at the fall agree
with it to round-off (``np.dot`` sums the interpolant's terms in another
order): measured at most 4.3e-16 of a state's peak and no fall time
changed on the falling regression references and 39 falling runs, tested
within 1e-13 and 1e-12 s.

Where no C compiler is found, or the build fails, or the installed SciPy is not
the release the source comes from (:data:`SCIPY_RELEASE`: another release's
odeint may step differently, and a run must give the same numbers whichever
path it takes: the same steps, to round-off in a careful chunk's samples),
:func:`driver` returns None and the Python path runs (slower).
"""
import ctypes
from dataclasses import dataclass
import functools
import hashlib
import pathlib

import numpy as np
import scipy
from scipy.linalg import cython_lapack

from whipple_kick.errors import BuildError, CompilerNotFoundError
from whipple_kick.model import cache, compiler

#: SciPy release (major.minor) whose LSODA source is vendored; with another release odeint's path is used.
SCIPY_RELEASE = (1, 17)
_FOLDER = pathlib.Path(__file__).with_name("lsoda_src")
_SOURCES = ("driver.c", "lsoda.c", "lsoda.h", "blaslapack_declarations.h")
_FLAGS = (*compiler.EXTENSION_FLAGS, "-fvisibility=hidden")


def _capsule_pointer(capsule):
    """Address of the C function in a Cython ``__pyx_capi__`` capsule."""
    get_name = ctypes.pythonapi.PyCapsule_GetName
    get_name.restype, get_name.argtypes = ctypes.c_char_p, [ctypes.py_object]
    get_pointer = ctypes.pythonapi.PyCapsule_GetPointer
    get_pointer.restype, get_pointer.argtypes = ctypes.c_void_p, [ctypes.py_object, ctypes.c_char_p]
    return get_pointer(capsule, get_name(capsule))


@functools.cache
def driver():
    """The compiled driver (ctypes library, built into the cache on a miss), or None where it cannot be used."""
    if tuple(int(v) for v in scipy.__version__.split(".")[:2]) != SCIPY_RELEASE:
        return None
    try:
        cc = compiler.find()
    except CompilerNotFoundError:
        return None
    digest = hashlib.sha256(f"{cc} {' '.join(_FLAGS)}".encode())
    for name in _SOURCES:
        digest.update((_FOLDER / name).read_bytes())
    name = f"lsoda_driver_{digest.hexdigest()[:20]}.so"

    def build(path):
        compiler.compile_shared(cc, (*_FLAGS, f"-I{_FOLDER}"), _FOLDER / "driver.c", path, ("-lm",))

    try:
        lib = ctypes.CDLL(str(cache.build_once(name, build)))
    except (BuildError, OSError):
        return None
    lib.wk_lsoda_set_lapack.argtypes = [ctypes.c_void_p] * 4
    lib.wk_lsoda_set_lapack(*(_capsule_pointer(cython_lapack.__pyx_capi__[f])
                              for f in ("dgetrf", "dgetrs", "dgbtrf", "dgbtrs")))
    pointer, c_int, c_double = ctypes.c_void_p, ctypes.c_int, ctypes.c_double
    lib.wk_lsoda_fast_chunks.restype = c_int
    lib.wk_lsoda_fast_chunks.argtypes = [pointer, pointer, pointer, pointer, c_int, pointer, pointer, c_int, pointer,
                                         c_double, pointer, c_int, c_int, c_double, c_int, c_double, c_int,
                                         c_double, c_double, c_double, pointer, pointer]
    lib.wk_lsoda_all_finite.restype = c_int
    lib.wk_lsoda_all_finite.argtypes = [pointer, ctypes.c_long]
    lib.wk_lsoda_careful_chunk.restype = c_int
    lib.wk_lsoda_careful_chunk.argtypes = [pointer, pointer, pointer, pointer, c_int, pointer, c_int, pointer,
                                           c_double, pointer, c_int, c_double, c_int, c_double, c_int, c_double,
                                           c_double, c_double, ctypes.c_longlong, ctypes.c_longlong, c_double,
                                           pointer, pointer, pointer, pointer, pointer]
    return lib


@functools.cache
def _model_functions(model_lib):
    """Addresses of a compiled model library's ``wk_slip_rhs`` and ``wk_slip_jacobian`` (looked up once per library)."""
    return tuple(ctypes.cast(f, ctypes.c_void_p).value for f in (model_lib.wk_slip_rhs, model_lib.wk_slip_jacobian))


#: How a careful chunk ended: ``wk_lsoda_careful_chunk``'s codes (driver.c's CAREFUL_* enumeration).
CAREFUL_STATUS = {0: "completed", 1: "fell", 2: "lsoda", 3: "model", 4: "budget", 5: "stall", 6: "root_nan",
                  7: "root_signs", 8: "root_iterations"}


@dataclass(frozen=True)
class CarefulChunk:
    """What one careful chunk in C produced (:meth:`FastChunks.careful`); the caller words the messages.

    Attributes
    ----------
    samples : ndarray
        States at the chunk's first ``len(samples)`` times.
    end : (float, ndarray)
        Last time and state reached (the fall's; the last accepted step's where it failed).
    status : str
        A value of :data:`CAREFUL_STATUS`.
    counts : (int, int, int)
        LSODA's evaluations, its Jacobians, all evaluations (the budget's count).
    step : float
        Last accepted step's time [s] (where LSODA or the model failed, or the budget or stall was judged).
    step_size : float
        That step's size [s].
    window : (int, float)
        Evaluations and time at the stall window's start (budget and stall).
    failed : tuple or None
        For ``model``: the time, the state and the function (``"rhs"`` or ``"jacobian"``) at which the model
        failed; for ``root_nan``: ``(t, None)``, the time at which the fall margin was NaN.
    istate : int
        LSODA's ``istate`` where it failed.
    """

    samples: np.ndarray
    end: tuple
    status: str
    counts: tuple
    step: float
    step_size: float
    window: tuple
    failed: tuple | None
    istate: int


_CAREFUL_RTOL_FLOOR = 100 * float(np.finfo(float).eps)


class FastChunks:
    """The C chunk loop bound to one compiled model, its Jacobian's scale and the run's limits and tolerances.

    Parameters
    ----------
    rhs : whipple_kick.model.slip.CompiledRHS
        The compiled model with its parameters.
    jac : callable
        Its Jacobian (``rhs.jacobian_function(scale)``): the scale and the evaluation count are read from it.
    rtol, atol : float, ndarray
        LSODA's tolerances.
    mxstep : int
        Most steps between two samples (odeint's ``mxstep``).
    limits : (int, float, int, float)
        Roll index, fall angle [rad], steer index, steer limit [rad].
    budget : Budget
        The run's evaluation budget; ``t_start`` [s] its start.
    """

    def __init__(self, lib, rhs, jac, rtol, atol, mxstep, limits, budget, t_start):
        self.lib = lib
        self.rhs_address, self.jac_address = _model_functions(rhs.lib)
        self.p = rhs.p   # kept alive: C reads it
        self.scale = np.ascontiguousarray(jac.scale, dtype=float)
        self.jac_evaluations = int(jac.evaluations)
        self.atol = np.ascontiguousarray(atol, dtype=float)
        # The addresses of the arrays every call passes, once (each `ctypes.data` builds an object).
        self._constant = (self.p.ctypes.data, self.scale.ctypes.data, self.atol.ctypes.data)
        self.rtol, self.mxstep, self.limits = float(rtol), int(mxstep), limits
        self.budget = (float(budget.allowance), float(budget.per_second), float(t_start))
        self.stall = (int(budget.stall_window), float(budget.stall_progress))
        # scipy's LSODA solver object raises its rtol to 100 eps (scipy.integrate._ivp.common.validate_tol).
        self.careful_rtol = max(float(rtol), _CAREFUL_RTOL_FLOOR)

    def __call__(self, grid, cuts, x, counts, into=None):
        """Integrate the chunks ``grid[cuts[k]:cuts[k + 1] + 1]`` from ``x`` until one needs the careful path.

        Parameters
        ----------
        grid : ndarray
            The piece's chunk edges and sample times [s].
        cuts : sequence of int
            Indices of the chunk edges in ``grid``.
        x : ndarray
            State at ``grid[cuts[0]]``.
        counts : ndarray of int64, shape (3,)
            ``nfev, njev, evaluations`` so far; the chunks done are added to it.
        into : int, optional
            Address of grid row 0's row in a C-ordered float64 array of rows of ``x.size`` that the states are
            written into (rows ``cuts[0]`` to ``cuts[done]``; the rows of the chunk that stopped the call, up to
            ``cuts[done + 1]``, are written too, with no meaning: the caller makes room for rows ``cuts[0]`` to
            ``cuts[-1]``); default an array of this call's own.

        Returns
        -------
        done : int
            Chunks done.
        states : ndarray or None
            States at ``grid[cuts[0]:cuts[done] + 1]`` (None with ``into``).
        x : ndarray
            State at ``grid[cuts[done]]``.
        """
        grid = np.ascontiguousarray(grid, dtype=float)
        c = np.ascontiguousarray(cuts, dtype=np.intc)
        x = np.array(x, dtype=float)
        n = x.size
        out = np.empty((grid.size, n)) if into is None else None
        roll, fall_angle, steer, steer_limit = self.limits
        p, scale, atol = self._constant
        done = self.lib.wk_lsoda_fast_chunks(
            self.rhs_address, self.jac_address, p, scale, n, grid.ctypes.data, c.ctypes.data, c.size, x.ctypes.data,
            self.rtol, atol, self.mxstep, roll, fall_angle, steer, steer_limit, self.jac_evaluations, *self.budget,
            counts.ctypes.data, out.ctypes.data if into is None else into)
        if done < 0:
            raise MemoryError("the C chunk loop ran out of memory")
        return done, None if out is None else out[c[0]:c[done] + 1], x

    def careful(self, times, x, spent):
        """One chunk of the careful path in C: LSODA stepped one step at a time, the fall event, the budget.

        As :func:`whipple_kick.simulate.lsoda._careful_chunk` with ``scipy.integrate.LSODA`` (the same steps,
        evaluations and ending; the samples and the fall time from the same interpolant, to round-off).

        Parameters
        ----------
        times : ndarray
            The chunk's sample times [s], its start and end included.
        x : ndarray
            State at ``times[0]``.
        spent : int
            Evaluations the run spent before the chunk (the budget's count).

        Returns
        -------
        CarefulChunk
        """
        times = np.ascontiguousarray(times, dtype=float)
        x = np.ascontiguousarray(x, dtype=float)
        n, m = x.size, times.size
        samples, end, failed_x = np.empty((m, n)), np.empty(n + 1), np.empty(n)
        counts, report = np.zeros(8, dtype=np.int64), np.zeros(4)
        roll, fall_angle, steer, steer_limit = self.limits
        p, scale, atol = self._constant
        code = self.lib.wk_lsoda_careful_chunk(
            self.rhs_address, self.jac_address, p, scale, n, times.ctypes.data, m, x.ctypes.data, self.careful_rtol,
            atol, roll, fall_angle, steer, steer_limit,
            self.jac_evaluations, *self.budget, int(spent), *self.stall, samples.ctypes.data, end.ctypes.data,
            failed_x.ctypes.data, counts.ctypes.data, report.ctypes.data)
        if code < 0:
            raise MemoryError("the C careful chunk ran out of memory")
        status = CAREFUL_STATUS[code]
        failed = None
        if status == "model":
            failed = (float(report[3]), failed_x, "jacobian" if counts[6] == 2 else "rhs")
        elif status == "root_nan":
            failed = (float(report[3]), None)
        return CarefulChunk(samples[:int(counts[3])], (float(end[0]), end[1:]), status,
                            (int(counts[0]), int(counts[1]), int(counts[2])), float(report[0]), float(report[1]),
                            (int(counts[5]), float(report[2])), failed, int(counts[4]))
