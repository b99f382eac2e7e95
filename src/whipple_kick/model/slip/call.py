"""Calling the compiled model: parameters by name, :class:`CompiledRHS` (right-hand side, outputs, Jacobian)."""
import ctypes
import functools
import math

import numpy as np

from whipple_kick.errors import InputError
from whipple_kick.model import transient
import whipple_kick.model.slip.compiled as compiled  # noqa: PLR0402 -- the module, not the package that imports this one; tests patch its names
import whipple_kick.model.slip.layout as layouts  # the module by its full name, not through the package

from .description import Parameters


def _model_of(params):
    """The model ``params`` are for (``params.model``); a plain mapping has none and is refused."""
    model = getattr(params, "model", None)
    if model is None:
        raise TypeError("the compiled model needs the model's parameters with their model (slip.model_parameters "
                        "gives them; .copy() and .replace() keep it), not a plain mapping")
    return model


def parameter_vector(params, L=None):
    """Parameter array for the compiled model, looked up by name.

    Parameters
    ----------
    params : mapping
        Every parameter of the model by name.
    L : Layout, optional
        The model's layout; default ``params.model.layout``
        (:class:`~whipple_kick.model.slip.description.Parameters`).

    Raises
    ------
    InputError
        If a name is missing or unknown.
    """
    L = _model_of(params).layout if L is None else L
    names = L.PARAMETER_NAMES
    if type(params) in (dict, Parameters) and len(params) == len(names):
        # As many names as the model's, each found: the same names (the checks below would pass). float() of
        # each value, as the loop below, without a Python frame per name.
        try:
            return np.array(list(map(float, map(params.__getitem__, names))))
        except KeyError:
            pass
    missing = [n for n in names if n not in params]
    if missing:
        raise InputError(f"slip-model parameters are missing: {', '.join(missing[:8])}"
                         + (" ..." if len(missing) > 8 else ""))
    unknown = [n for n in params if n not in L.P]
    if unknown:
        raise InputError(f"unknown slip-model parameters: {', '.join(sorted(unknown)[:8])}")
    return np.array([float(params[n]) for n in names])


class CompiledRHS:
    """Callable ``f(t, x) -> dx/dt`` backed by the C library, for one parameter set.

    Parameters
    ----------
    params : whipple_kick.model.slip.description.Parameters
        Every parameter of the model by name, with the model they are for (``params.model``: its parts,
        delay filter and tyre form, :func:`whipple_kick.model.slip.parameters.model_parameters`); the model
        is not inferred from the names or values.

    Example
    -------
    >>> rhs = CompiledRHS(steady.params)           # doctest: +SKIP
    >>> dx = rhs(0.0, steady.x)                    # doctest: +SKIP
    """

    def __init__(self, params):
        model = _model_of(params)
        self._bind(model, parameter_vector(params, model.layout))

    def _bind(self, model, p):
        """Set up the model ``model`` with the parameter vector ``p`` (checked against the model)."""
        self.model = model
        self.layout = model.layout
        self.lib = compiled.library(self.layout)
        self.p = np.ascontiguousarray(p)
        # The values agree with the model they come with (the C reads the form's index and the delay).
        form, delay = self.p[self.layout.P["tyre_transient"]], self.p[self.layout.P["reflex_delay"]]
        if form != transient.check(model.transient):
            raise InputError(f"tyre_transient = {form:g} is not the {model.transient} model's index "
                             f"{transient.check(model.transient)}")
        if (delay != 0.0) != model.delayed_reflex:
            raise InputError(f"reflex_delay = {delay:g} s does not fit the {model.layout.key} model (a delay needs "
                             "the delay filter, the filter a delay > 0 s)")
        self._p_ptr = self.p.ctypes.data
        # The derivative, state and output buffers of outputs(): one block, one pointer looked up (a linearisation
        # builds two of these objects, the steady solve one).
        n = len(self.layout.STATE_NAMES)
        block = np.empty(2 * n + len(self.layout.OUTPUT_NAMES))
        self._dx, self._x, self._out = block[:n], block[n:2 * n], block[2 * n:]
        self._dx_ptr = block.ctypes.data
        self._x_ptr = self._dx_ptr + self._dx.nbytes
        self._out_ptr = self._x_ptr + self._x.nbytes
        self.fast = self.guarded()   # f(t, x): one foreign call (what the integrators call)

    def replaced(self, **changes):
        """The same model with the parameters ``changes`` (by name) changed: a new object with its own vector.

        As ``CompiledRHS(params.replace(**changes))`` gives, without looking every parameter up by name again
        (the linearisation's steer-torque column needs the model with ``ku7`` raised by 1).
        """
        p = self.p.copy()
        for name, value in changes.items():
            if name not in self.layout.P:
                raise InputError(f"unknown slip-model parameters: {name}")
            p[self.layout.P[name]] = float(value)
        new = CompiledRHS.__new__(CompiledRHS)
        new._bind(self.model, p)
        return new

    @property
    def transient(self):
        """Name of the model's tyre transient form."""
        return self.model.transient

    def __call__(self, t, x):
        return self.fast(t, x)

    def guarded(self, index=0, limit=math.inf, exception=None, index2=0, limit2=math.inf):
        """A fast ``f(t, x)`` that raises ``exception`` once ``|x[index]| > limit`` or ``|x[index2]| > limit2``.

        Where the Python headers are available this is an object of the
        compiled :mod:`whipple_kick.model.rhs_call` extension: one foreign call,
        no Python code, per evaluation (the integrator's hot path, about 1e4
        calls per run). Otherwise one Python frame with everything bound
        locally around the ctypes call. Without ``exception`` nothing is checked.
        """
        native = compiled._native_call()
        if native is not None:
            address = _rhs_address(self.lib)
            return native.Rhs(address, self.p, len(self.layout.STATE_NAMES), _raise_status, exception, index, limit, index2,
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
            right-hand-side evaluations one call makes (the layout's ``JACOBIAN_EVALUATIONS``:
            dynamic states + 1, less the :data:`IGNORABLE` columns).
        """
        scale = np.ascontiguousarray(scale, dtype=float)
        n = len(self.layout.STATE_NAMES)
        fn, p_ptr, s_ptr = self.lib.wk_slip_jacobian, self._p_ptr, scale.ctypes.data

        def jac(t, x):
            x = np.ascontiguousarray(x, dtype=float)
            J = np.empty((n, n))
            status = fn(t, x.ctypes.data, p_ptr, s_ptr, J.ctypes.data)
            if status:
                _raise_status(status, t)
            return J
        jac.scale = scale   # keeps the array alive with the closure
        jac.evaluations = self.layout.JACOBIAN_EVALUATIONS   # right-hand-side evaluations per call (the budget counts them)
        return jac

    def impulse_terms(self, t, x):
        """Mass matrix M (n, n), constraint matrix A (3, n) and offset a0 (3,) at ``(t, x)``, n speeds."""
        x = np.ascontiguousarray(x, dtype=float)
        n, m = len(self.layout.SPEEDS), len(self.layout.DEPENDENT)
        M, A, a0 = np.empty((n, n)), np.empty((m, n)), np.empty(m)
        self.lib.wk_slip_impulse_terms(t, x.ctypes.data, self._p_ptr, M.ctypes.data, A.ctypes.data,
                                       a0.ctypes.data)
        return M, A, a0

    def outputs_at(self, t, X, via_rhs=False, names=None):
        """Named outputs (the layout's ``OUTPUT_NAMES``) at many samples, in one C call.

        The outputs need no accelerations, so the C function evaluates the
        right-hand side's statements without Kane's mass matrix, forcing and
        solve (a third of a sweep case's time went there): the same statements,
        the same values bit for bit (a test compares them at every sample).

        Parameters
        ----------
        t : array_like, shape (n,)
            Times [s].
        X : array_like, shape (n, len(layout.STATE_NAMES))
            States.
        via_rhs : bool
            Evaluate the whole right-hand side at each sample instead (the
            reference the tests compare with; it also fails on a non-finite
            derivative).
        names : iterable of str, optional
            The outputs needed: the groups of :data:`~whipple_kick.model.slip.layout.OPTIONAL_OUTPUTS` that hold
            none of them are left out (their columns NaN), the others are the same bit for bit. Default: all.

        Returns
        -------
        ndarray, shape (n, len(layout.OUTPUT_NAMES))
        """
        t = np.ascontiguousarray(t, dtype=float)
        X = np.ascontiguousarray(X, dtype=float)
        ns = len(self.layout.STATE_NAMES)
        if X.shape != (t.size, ns):
            raise ValueError(f"states must have shape ({t.size}, {ns}), got {X.shape}")
        groups = optional_groups(names)
        if via_rhs or groups == optional_groups():
            out = np.empty((t.size, len(self.layout.OUTPUT_NAMES)))
            fn = self.lib.wk_slip_outputs if via_rhs else self.lib.wk_slip_outputs_only
            status = fn(t.size, t.ctypes.data, X.ctypes.data, self._p_ptr, out.ctypes.data)
        else:
            out = np.full((t.size, len(self.layout.OUTPUT_NAMES)), np.nan)   # the groups left out: never read as values
            status = self.lib.wk_slip_outputs_some(t.size, t.ctypes.data, X.ctypes.data, self._p_ptr, groups,
                                                   out.ctypes.data)
        if status:
            raise FloatingPointError(_STATUS.get(status, f"status {status}") + " while evaluating outputs")
        return out

    def friction_limits(self, wheel, camber, fz, force, search=False):
        """The friction-limit output (``fy_limit_r``/``fy_limit_f``) [N] at many points of one wheel, in one C call.

        Parameters
        ----------
        wheel : {"r", "f"}
        camber, fz, force : array_like, shape (n,)
            Camber [rad], normal load [N] and the lateral force [N] whose side the limit is on.
        search : bool
            By the rising branch's search alone, also where one set's interior peak gives the limit
            directly (the reference the tests compare the outputs with).

        Returns
        -------
        ndarray, shape (n,)
        """
        camber, fz, force = (np.ascontiguousarray(v, dtype=float) for v in (camber, fz, force))
        out = np.empty(camber.size)
        self.lib.wk_slip_friction_limits(camber.size, "rf".index(wheel), camber.ctypes.data, fz.ctypes.data,
                                         force.ctypes.data, self._p_ptr, int(search), out.ctypes.data)
        return out

    def carcass_slips(self, wheel, camber, lagged_camber, fz, force, search=False):
        """The undamped carcass' patch slips [rad] giving ``force`` at many points of one wheel, in one C call.

        Parameters
        ----------
        wheel : {"r", "f"}
        camber, lagged_camber, fz, force : array_like, shape (n,)
            Camber and the moment's lagged camber [rad], normal load [N], carcass force [N].
        search : bool
            Find a pressure blend's common rising branch by the sets' branch ends, and both ends of the
            rising branch before testing a force for saturation (the references the tests compare the
            shortcuts with).

        Returns
        -------
        ndarray, shape (n, 2)
            The patch slip at the camber (the force's) and at the lagged camber (the moment's), sliding law "peak".
        """
        camber, lagged_camber, fz, force = (np.ascontiguousarray(v, dtype=float)
                                            for v in (camber, lagged_camber, fz, force))
        out = np.empty((camber.size, 2))
        self.lib.wk_slip_carcass_slips(camber.size, "rf".index(wheel), camber.ctypes.data, lagged_camber.ctypes.data,
                                       fz.ctypes.data, force.ctypes.data, self._p_ptr, int(search), out.ctypes.data)
        return out / (180.0 / np.pi)   # as the C code converts its degrees

    def outputs(self, t, x):
        """Derivatives and named outputs (the layout's ``OUTPUT_NAMES``) at one state."""
        dx, out = self.outputs_view(t, x)
        return dx.copy(), out.copy()

    def outputs_view(self, t, x):
        """:meth:`outputs` in this object's own buffers (no copies): read them before its next call.

        The steady search and the linearisation make some 100 of these calls per run, each reading a few
        values; no ctypes view of a new array per call either.
        """
        self._x[:] = x
        status = self.lib.wk_slip_rhs(t, self._x_ptr, self._p_ptr, self._dx_ptr, self._out_ptr)
        if status:
            _raise_status(status, t)
        return self._dx, self._out


@functools.cache
def _rhs_address(lib):
    """Address of the compiled right-hand side of ``lib`` (one lookup per library)."""
    return ctypes.cast(lib.wk_slip_rhs, ctypes.c_void_p).value


def optional_groups(names=None):
    """Bit mask of the :data:`~whipple_kick.model.slip.layout.OPTIONAL_OUTPUTS` groups that hold one of the outputs
    ``names`` (None: every group)."""
    if names is None:
        return layouts.EVERY_OPTIONAL_GROUP
    names = set(names)
    return sum(1 << k for k, group in enumerate(layouts.OPTIONAL_OUTPUTS) if names & set(group))


_STATUS = {
    1: "singular constraint or mass matrix in the slip model",
    2: "non-finite derivative in the slip model",
    3: "a reflex delay was set on a compiled model without the delay filter (make a new CompiledRHS)",
}


def _raise_status(status, t):
    """Raise the model's error for a nonzero status of its C function at time ``t`` [s]."""
    raise FloatingPointError(_STATUS.get(status, f"status {status}") + f" at t = {t:.6g} s")
