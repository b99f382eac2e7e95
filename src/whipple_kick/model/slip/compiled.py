"""The compiled libraries: the cache entries (built on a miss), loading each once per process.

One library per model: the base model (the rigid rider) and each combination of declared parts a run
asks for (:class:`whipple_kick.model.slip.layout.Layout`), each built on its first use.
"""
import ctypes
import functools
import json
import os

from whipple_kick.model import cache, compiler, rhs_call, transient
import whipple_kick.model.slip.layout as layouts  # the module by its full name, not through the package

from .layout import _SOURCES


@functools.cache
def _native_call():
    """The compiled call extension (:func:`whipple_kick.model.rhs_call.module`), or None; looked up once per process."""
    return rhs_call.module(compiler.find())


def metadata_layout(L=layouts.BASE):
    """The layouts the running code expects of the compiled library of ``L`` (as its metadata records them)."""
    return L.record()


def _metadata_matches(path, L):
    """Whether the metadata file at ``path`` exists, is private and records ``L``'s layouts."""
    try:
        cache.check_private_file(path)
        return json.loads(path.read_text()).get("layout") == metadata_layout(L)
    except (OSError, ValueError, AttributeError):
        return False


def library_path(L=layouts.BASE):
    """Path of the compiled slip model of the layout ``L`` in the cache, built first on a cache miss.

    The cache entry is ``slip_<model>_<key>.so`` with its C source and plain-data
    metadata (``.json``) beside it, ``<model>`` naming its parts (``rigid``
    for the base model) and the key hashing the package sources it is
    generated from, the parts' declarations and build code, the SymPy
    version, the compiler and its flags. A miss runs
    :func:`whipple_kick.model.symbolic.slip_build.build_library` (SymPy,
    20-60 s, announced by a :class:`~whipple_kick.errors.PerformanceWarning`). An entry whose metadata is missing or
    records other layouts (states, parameters, outputs) is built again.
    """
    cc = compiler.find()
    key = L.key + "_" + cache.source_hash(_SOURCES, extra=f"{os.path.basename(cc)} {' '.join(compiler.MODEL_FLAGS)} "
                                                          f"{L.fingerprint()} forms {transient.fingerprint()}")
    name = f"slip_{key}.so"
    def build(tmp):
        from whipple_kick.model.symbolic import slip_build  # SymPy and the derivation: only on a cache miss
        slip_build.build_library(tmp, key, cc, compiler.MODEL_FLAGS, L.part_names, L.delayed_reflex)

    lib_path = cache.build_once(name, build)
    if not _metadata_matches(lib_path.with_suffix(".json"), L):
        with cache.locked(lib_path):
            lib_path.unlink(missing_ok=True)
        lib_path = cache.build_once(name, build)
        if not _metadata_matches(lib_path.with_suffix(".json"), L):
            raise RuntimeError(f"the compiled slip model {lib_path} has no matching metadata; remove the cache folder")
    return lib_path


def model_hash(L=layouts.BASE):
    """Name of the compiled slip model of ``L`` (``slip_<model>_<key>``, its cache entry): what a sweep folder records."""
    return os.path.splitext(os.path.basename(library(L)._name))[0]


def library(L=layouts.BASE):
    """The compiled slip model of the layout ``L`` (ctypes library of :func:`library_path`), loaded once per process
    and set of declared tyre forms (a form declared later is in another library)."""
    return _library(L, transient.fingerprint())


@functools.cache
def _library(L, forms):
    """:func:`library` of ``L`` with the declared tyre forms whose fingerprint is ``forms``."""
    lib = ctypes.CDLL(str(library_path(L)))
    pointer = ctypes.c_void_p
    lib.wk_slip_rhs.restype = ctypes.c_int
    lib.wk_slip_rhs.argtypes = [ctypes.c_double, pointer, pointer, pointer, pointer]
    lib.wk_slip_outputs.restype = ctypes.c_int
    lib.wk_slip_outputs.argtypes = [ctypes.c_int, pointer, pointer, pointer, pointer]
    lib.wk_slip_outputs_only.restype = ctypes.c_int
    lib.wk_slip_outputs_only.argtypes = [ctypes.c_int, pointer, pointer, pointer, pointer]
    lib.wk_slip_outputs_some.restype = ctypes.c_int
    lib.wk_slip_outputs_some.argtypes = [ctypes.c_int, pointer, pointer, pointer, ctypes.c_int, pointer]
    lib.wk_slip_jacobian.restype = ctypes.c_int
    lib.wk_slip_jacobian.argtypes = [ctypes.c_double, pointer, pointer, pointer, pointer]
    lib.wk_slip_impulse_terms.restype = ctypes.c_int
    lib.wk_slip_impulse_terms.argtypes = [ctypes.c_double, pointer, pointer, pointer, pointer, pointer]
    lib.wk_slip_cornering_stiffness.restype = ctypes.c_int
    lib.wk_slip_cornering_stiffness.argtypes = [ctypes.c_double, ctypes.c_double, pointer, pointer]
    lib.wk_slip_friction_limits.restype = ctypes.c_int
    lib.wk_slip_friction_limits.argtypes = [ctypes.c_int, ctypes.c_int, pointer, pointer, pointer, pointer,
                                            ctypes.c_int, pointer]
    lib.wk_slip_carcass_slips.restype = ctypes.c_int
    lib.wk_slip_carcass_slips.argtypes = [ctypes.c_int, ctypes.c_int, pointer, pointer, pointer, pointer, pointer,
                                          ctypes.c_int, pointer]
    sizes = (ctypes.c_int * 4)()
    lib.wk_slip_sizes(sizes)
    if tuple(sizes) != (len(L.STATE_NAMES), len(L.PARAMETER_NAMES), len(L.OUTPUT_NAMES), len(L.DYNAMIC_STATES)):
        raise RuntimeError(f"compiled slip model has sizes {tuple(sizes)}; rebuild the cache")
    return lib
