"""The integrator's call into the compiled slip model: one foreign call per right-hand side.

LSODA (through :func:`scipy.integrate.odeint` or :class:`scipy.integrate.LSODA`)
calls ``f(t, x)`` from C with a new array ``x`` every time. Through ctypes
that call costs a Python frame, ``x.ctypes.data`` (about 1.5 us, as much as
a third of the model itself) and a copy of the result. This module compiles,
once per Python and NumPy version, a tiny CPython extension whose callable
object holds the model's function pointer and parameter pointer: a call
reads ``x``'s buffer, optionally checks the roll and steer limits, and lets
the model write straight into the new result array. No Python code runs per
call.

It needs the Python headers (``Python.h``) beside the interpreter; where they
are missing, or the compiler fails on them, :func:`module` returns None and
:class:`whipple_kick.model.slip.CompiledRHS` keeps its ctypes call (the same
numbers, slower: ``scripts/bench.py rhs`` shows which path is in use), and
a :class:`~whipple_kick.errors.PerformanceWarning` says so, once per process
(:func:`_fall_back`; a library caller can filter it).
"""
import functools
import hashlib
import importlib.machinery
import importlib.util
import pathlib
import platform
import sys
import sysconfig
import warnings

import numpy as np

from whipple_kick.errors import CacheError, PerformanceWarning

from . import cache
from . import compiler as compilers

_NAME = "whipple_kick_rhs_call"

_SOURCE = r"""
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <math.h>
#define NPY_NO_DEPRECATED_API NPY_1_7_API_VERSION
#include <numpy/arrayobject.h>

/* wk_slip_rhs(t, x, p, dx, out) of the generated model; 0 = success. */
typedef int (*rhs_fn)(double, const double *, const double *, double *, double *);

typedef struct {
    PyObject_HEAD
    rhs_fn fn;
    PyObject *params;       /* the parameter array, kept alive: the model reads it on every call */
    npy_intp n;             /* state length */
    Py_ssize_t i1, i2;      /* states whose |x| is limited */
    double lim1, lim2;
    PyObject *limit_error;  /* raised (no arguments) once |x[i1]| > lim1 or |x[i2]| > lim2; None: no check */
    PyObject *on_status;    /* on_status(status, t) raises the model's error */
} Rhs;

static void Rhs_dealloc(Rhs *self)
{
    Py_XDECREF(self->params);
    Py_XDECREF(self->limit_error);
    Py_XDECREF(self->on_status);
    Py_TYPE(self)->tp_free((PyObject *)self);
}

static int Rhs_init(Rhs *self, PyObject *args, PyObject *kw)
{
    static char *names[] = {"function", "params", "n", "on_status", "limit_error", "i1", "lim1", "i2", "lim2",
                            NULL};
    unsigned long long address;
    PyObject *params, *on_status, *limit_error = Py_None;
    Py_ssize_t n, i1 = 0, i2 = 0;
    double lim1 = INFINITY, lim2 = INFINITY;
    if (!PyArg_ParseTupleAndKeywords(args, kw, "KOnO|Ondnd", names, &address, &params, &n, &on_status,
                                     &limit_error, &i1, &lim1, &i2, &lim2))
        return -1;
    if (!PyArray_Check(params) || PyArray_TYPE((PyArrayObject *)params) != NPY_DOUBLE
        || !PyArray_IS_C_CONTIGUOUS((PyArrayObject *)params)) {
        PyErr_SetString(PyExc_TypeError, "params must be a C-contiguous float64 array");
        return -1;
    }
    if (n <= 0 || i1 < 0 || i1 >= n || i2 < 0 || i2 >= n) {
        PyErr_SetString(PyExc_ValueError, "state length and limited indices out of range");
        return -1;
    }
    self->fn = (rhs_fn)(uintptr_t)address;
    Py_INCREF(params);
    Py_XSETREF(self->params, params);
    Py_INCREF(on_status);
    Py_XSETREF(self->on_status, on_status);
    Py_XSETREF(self->limit_error, limit_error == Py_None ? NULL : (Py_INCREF(limit_error), limit_error));
    self->n = n;
    self->i1 = i1;
    self->i2 = i2;
    self->lim1 = lim1;
    self->lim2 = lim2;
    return 0;
}

/* x as a C-contiguous float64 array of the state length (a new reference), or NULL with an error set. */
static PyArrayObject *state_array(Rhs *self, PyObject *obj)
{
    PyArrayObject *x = (PyArrayObject *)PyArray_FROMANY(obj, NPY_DOUBLE, 1, 1, NPY_ARRAY_IN_ARRAY);
    if (x && PyArray_DIM(x, 0) != self->n) {
        PyErr_Format(PyExc_ValueError, "the state must have %zd entries, got %zd", (Py_ssize_t)self->n,
                     (Py_ssize_t)PyArray_DIM(x, 0));
        Py_CLEAR(x);
    }
    return x;
}

static PyObject *model_error(Rhs *self, int status, double t)
{
    PyObject *r = PyObject_CallFunction(self->on_status, "id", status, t);
    Py_XDECREF(r);
    if (!PyErr_Occurred())
        PyErr_Format(PyExc_FloatingPointError, "slip model status %d", status);
    return NULL;
}

static PyObject *Rhs_call(Rhs *self, PyObject *args, PyObject *kw)
{
    if (kw || PyTuple_GET_SIZE(args) != 2) {
        PyErr_SetString(PyExc_TypeError, "f(t, x) takes exactly two positional arguments");
        return NULL;
    }
    double t = PyFloat_AsDouble(PyTuple_GET_ITEM(args, 0));
    if (t == -1.0 && PyErr_Occurred())
        return NULL;
    PyArrayObject *x = state_array(self, PyTuple_GET_ITEM(args, 1));
    if (!x)
        return NULL;
    const double *xs = (const double *)PyArray_DATA(x);
    if (self->limit_error && (fabs(xs[self->i1]) > self->lim1 || fabs(xs[self->i2]) > self->lim2)) {
        Py_DECREF(x);
        PyErr_SetNone(self->limit_error);
        return NULL;
    }
    PyObject *dx = PyArray_SimpleNew(1, &self->n, NPY_DOUBLE);
    if (!dx) {
        Py_DECREF(x);
        return NULL;
    }
    int status = self->fn(t, xs, (const double *)PyArray_DATA((PyArrayObject *)self->params),
                          (double *)PyArray_DATA((PyArrayObject *)dx), NULL);
    Py_DECREF(x);
    if (status) {
        Py_DECREF(dx);
        return model_error(self, status, t);
    }
    return dx;
}

/* repeat(t, x, count): the model function alone, count times in a C loop (what scripts/bench.py times). */
static PyObject *Rhs_repeat(Rhs *self, PyObject *args)
{
    double t;
    PyObject *obj;
    Py_ssize_t count;
    if (!PyArg_ParseTuple(args, "dOn", &t, &obj, &count))
        return NULL;
    PyArrayObject *x = state_array(self, obj);
    if (!x)
        return NULL;
    double *dx = PyMem_Malloc(sizeof(double) * self->n);
    const double *p = (const double *)PyArray_DATA((PyArrayObject *)self->params);
    int status = 0;
    for (Py_ssize_t k = 0; k < count && !status; k++)
        status = self->fn(t, (const double *)PyArray_DATA(x), p, dx, NULL);
    PyMem_Free(dx);
    Py_DECREF(x);
    if (status)
        return model_error(self, status, t);
    Py_RETURN_NONE;
}

static PyMethodDef Rhs_methods[] = {
    {"repeat", (PyCFunction)Rhs_repeat, METH_VARARGS, "repeat(t, x, count): the C function alone, count times"},
    {NULL, NULL, 0, NULL}
};

static PyTypeObject RhsType = {
    PyVarObject_HEAD_INIT(NULL, 0)
    .tp_name = "whipple_kick_rhs_call.Rhs",
    .tp_basicsize = sizeof(Rhs),
    .tp_flags = Py_TPFLAGS_DEFAULT,
    .tp_doc = "Rhs(function, params, n, on_status, limit_error=None, i1=0, lim1=inf, i2=0, lim2=inf): f(t, x)",
    .tp_new = PyType_GenericNew,
    .tp_init = (initproc)Rhs_init,
    .tp_dealloc = (destructor)Rhs_dealloc,
    .tp_call = (ternaryfunc)Rhs_call,
    .tp_methods = Rhs_methods,
};

static struct PyModuleDef module_def = {PyModuleDef_HEAD_INIT, "whipple_kick_rhs_call", NULL, -1, NULL};

PyMODINIT_FUNC PyInit_whipple_kick_rhs_call(void)
{
    import_array();
    if (PyType_Ready(&RhsType) < 0)
        return NULL;
    PyObject *m = PyModule_Create(&module_def);
    if (!m)
        return NULL;
    Py_INCREF(&RhsType);
    if (PyModule_AddObject(m, "Rhs", (PyObject *)&RhsType) < 0) {
        Py_DECREF(&RhsType);
        Py_DECREF(m);
        return NULL;
    }
    return m;
}
"""


def _flags():
    """Compiler flags of the extension (include folders of this Python and NumPy)."""
    flags = [*compilers.EXTENSION_FLAGS, f"-I{sysconfig.get_paths()['include']}", f"-I{np.get_include()}"]
    if sys.platform == "darwin":   # Python's symbols come from the interpreter at load time
        flags += ["-undefined", "dynamic_lookup"]
    return flags


def _key(compiler):
    """Cache key: the C source, the compiler and flags, this Python's ABI and NumPy's version."""
    text = (f"{_SOURCE}\n{compiler} {' '.join(_flags())}\n{sysconfig.get_config_var('EXT_SUFFIX')}\n"
            f"{sys.version}\nnumpy {np.__version__}\n{platform.machine()}")
    return hashlib.sha256(text.encode()).hexdigest()[:20]


@functools.cache
def module(compiler):
    """The compiled extension (built into the cache on a miss), or None where it cannot be built.

    Parameters
    ----------
    compiler : str
        Path of the C compiler (:func:`whipple_kick.model.compiler.find`).

    Returns
    -------
    module or None
        With the type ``Rhs(function, params, n, on_status, limit_error=None,
        i1=0, lim1=inf, i2=0, lim2=inf)``, a callable ``f(t, x)``.
    """
    headers = pathlib.Path(sysconfig.get_paths()["include"], "Python.h")
    if not headers.exists():
        _fall_back(f"the Python headers are missing ({headers}; install the python3-dev package of this Python)")
        return None
    folder = cache.cache_dir()

    def build(path):
        src = folder / f"rhs_call_{_key(compiler)}.c"
        src.write_text(_SOURCE)
        try:
            compilers.compile_shared(compiler, _flags(), src, path)
        finally:
            src.unlink(missing_ok=True)

    try:
        path = cache.build_once(f"rhs_call_{_key(compiler)}.so", build)
        spec = importlib.util.spec_from_file_location(
            _NAME, path, loader=importlib.machinery.ExtensionFileLoader(_NAME, str(path)))
        mod = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(mod)
    except CacheError:
        raise   # the model itself cannot be cached either: one error, not a warning
    except (RuntimeError, OSError, ImportError) as exc:
        first = (str(exc).strip().splitlines() or [type(exc).__name__])[-1][:200]
        _fall_back(f"building it with {compiler} failed ({first})")
        return None
    return mod


#: Cost of a right-hand-side call through ctypes against the extension (2.07 against 1.10 of the
#: C function alone, docs/simulate.md "LSODA calls the compiled model").
CTYPES_COST = 1.9
_warned = False


def _fall_back(why):
    """Say once per process why the extension is not used and what it costs.

    A :class:`~whipple_kick.errors.PerformanceWarning` (not a print), so that a
    library caller can filter it; the command-line tools print it as one line.
    """
    global _warned
    if not _warned:
        _warned = True
        warnings.warn(f"the fast call into the compiled model is not available: {why}; using ctypes instead "
                      f"(same results, each model evaluation about {CTYPES_COST:g} times as costly)",
                      PerformanceWarning, stacklevel=2)
