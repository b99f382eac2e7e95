"""The integrator's call into the compiled model: the one-foreign-call extension against the ctypes call."""

import math

import numpy as np
import pytest

import whipple_kick as wk
from whipple_kick.model import compiler, rhs_call, slip
from whipple_kick.simulate import lsoda


@pytest.fixture(scope="module")
def steady(rider_bike, gains, t03):
    par = slip.model_parameters(rider_bike, t03, t03, gains=gains, kick=dict(t0=0.0, duration=0.15, displacement=0.15))
    return wk.steady.steady_state(par, 3.0)


@pytest.fixture(scope="module")
def states(steady):
    """Steady state and three disturbed states inside the kick (plate moving)."""
    rng = np.random.default_rng(7)
    xs = [steady.x]
    for _ in range(3):
        x = steady.x.copy()
        x[[slip.X[n] for n in ("q4", "q7", "u4", "u7")]] += rng.normal(0.0, 0.05, 4)
        xs.append(x)
    return xs


def _ctypes_path(rhs, monkeypatch):
    """The ctypes fallback ``f(t, x)`` (what runs where the extension cannot be built)."""
    monkeypatch.setattr(slip.compiled, "_native_call", lambda: None)
    return rhs.guarded()


def test_the_extension_is_built_here(steady):
    """Python.h is on this machine, so the integrators use the extension (else the timings mean nothing)."""
    assert rhs_call.module(compiler.find()) is not None
    assert hasattr(slip.CompiledRHS(steady.params).fast, "repeat")


def test_extension_and_ctypes_call_give_the_same_numbers(steady, states, monkeypatch):
    """Both paths call the same C function on the same memory: bit-identical derivatives."""
    rhs = slip.CompiledRHS(steady.params)
    fallback = _ctypes_path(rhs, monkeypatch)
    for t in (0.0, 0.05, 0.12):
        for x in states:
            fast = rhs.fast(t, x)
            assert fast.shape == (len(slip.STATE_NAMES),)
            np.testing.assert_array_equal(fast, fallback(t, x))
            np.testing.assert_array_equal(rhs(t, x), fast)


def test_each_call_returns_a_new_array(steady, states):
    """LSODA (scipy.integrate.LSODA) keeps the derivatives it was given; a shared buffer would corrupt them."""
    rhs = slip.CompiledRHS(steady.params)
    first = rhs.fast(0.05, states[1])
    kept = first.copy()
    second = rhs.fast(0.05, states[2])
    assert first is not second
    np.testing.assert_array_equal(first, kept)


def test_extension_accepts_any_float_sequence_and_checks_its_length(steady):
    rhs = slip.CompiledRHS(steady.params)
    np.testing.assert_array_equal(rhs.fast(0.0, list(steady.x)), rhs.fast(0.0, steady.x))
    strided = np.repeat(steady.x, 2)[::2]   # not contiguous
    np.testing.assert_array_equal(rhs.fast(0.0, strided), rhs.fast(0.0, steady.x))
    with pytest.raises(ValueError, match="entries"):
        rhs.fast(0.0, steady.x[:-1])


def test_parameters_changed_in_place_are_seen(steady):
    """The extension reads the parameter array on every call (heading_linearisation bumps ku7 in place)."""
    rhs = slip.CompiledRHS(steady.params)
    x = steady.x.copy()
    x[slip.X["u7"]] += 1.0
    before = rhs.fast(0.0, x)
    rhs.p[slip.P["ku7"]] += 1.0
    after = rhs.fast(0.0, x)
    assert not np.array_equal(before, after)
    np.testing.assert_array_equal(after, slip.CompiledRHS(steady.params.replace(ku7=steady.params["ku7"] + 1.0))(0.0, x))


class _Past(Exception):
    pass


@pytest.mark.parametrize("use_extension", [True, False])
def test_guard_raises_past_either_limit_only(steady, monkeypatch, use_extension):
    rhs = slip.CompiledRHS(steady.params)
    if not use_extension:
        monkeypatch.setattr(slip.compiled, "_native_call", lambda: None)
    roll, steer = slip.X["q4"], slip.X["q7"]
    f = rhs.guarded(roll, 0.5, _Past, steer, 1.0)
    x = steady.x.copy()
    x[roll], x[steer] = -0.5, 1.0   # on the limits: not past
    f(0.0, x)
    for index, value in ((roll, -0.5 - 1e-12), (steer, 1.0 + 1e-12)):
        past = x.copy()
        past[index] = value
        with pytest.raises(_Past):
            f(0.0, past)
    unguarded = rhs.guarded()
    past[roll] = 3.0
    np.testing.assert_array_equal(unguarded(0.0, past), rhs(0.0, past))


@pytest.mark.parametrize("use_extension", [True, False])
def test_a_non_finite_state_raises_the_models_error(steady, monkeypatch, use_extension):
    rhs = slip.CompiledRHS(steady.params)
    if not use_extension:
        monkeypatch.setattr(slip.compiled, "_native_call", lambda: None)
    f = rhs.guarded(slip.X["q4"], math.inf, _Past)
    x = steady.x.copy()
    x[slip.X["u4"]] = np.nan
    with pytest.raises(FloatingPointError, match=r"slip model at t = 0\.25 s"):
        f(0.25, x)


def test_c_function_alone_loop_reports_the_models_status(steady, states):
    """``repeat`` (what scripts/bench.py times as the C function alone) runs the model and reports its errors."""
    rhs = slip.CompiledRHS(steady.params)
    assert rhs.fast.repeat(0.05, states[1], 3) is None
    bad = states[1].copy()
    bad[slip.X["u4"]] = np.nan
    with pytest.raises(FloatingPointError):
        rhs.fast.repeat(0.05, bad, 3)


def test_integration_is_the_same_on_either_path(steady, monkeypatch):
    """The 6 s base case's first second through the extension and through ctypes: identical trajectories."""
    rhs = slip.CompiledRHS(steady.params)
    fast = lsoda.integrate(rhs, steady.x, 1.0, breakpoints=(0.15,), rtol=1e-10)
    monkeypatch.setattr(slip.compiled, "_native_call", lambda: None)
    slow_rhs = slip.CompiledRHS(steady.params)
    assert not hasattr(slow_rhs.fast, "repeat")
    slow = lsoda.integrate(slow_rhs, steady.x, 1.0, breakpoints=(0.15,), rtol=1e-10)
    assert fast.nfev == slow.nfev and fast.njev == slow.njev
    np.testing.assert_array_equal(fast.x, slow.x)


@pytest.mark.parametrize("cause", ["headers", "compiler"])
def test_falling_back_to_ctypes_is_one_warning_once_per_process(cause, tmp_path, monkeypatch, capsys):
    """Before, the slower ctypes path was taken silently (about 1.9 times the cost per evaluation); then it was a
    print to stderr a library caller could not filter (issue 31 item 16): now a PerformanceWarning, once."""
    import shutil
    import sysconfig
    import warnings

    from whipple_kick.errors import PerformanceWarning, WhippleKickWarning
    monkeypatch.setattr(rhs_call, "_warned", False)
    if cause == "headers":
        monkeypatch.setattr(sysconfig, "get_paths", lambda: {"include": str(tmp_path)})
        compilers = ["cc-a", "cc-b"]
    else:
        monkeypatch.setenv("WHIPPLE_KICK_CACHE", str(tmp_path / "cache"))
        compilers = [shutil.which("false"), shutil.which("true") + "-not-there"]
    rhs_call.module.cache_clear()
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            assert [rhs_call.module(c) for c in compilers] == [None, None]
    finally:
        rhs_call.module.cache_clear()
    assert capsys.readouterr().err == ""                       # nothing printed behind the caller's back
    assert len(caught) == 1 and issubclass(caught[0].category, PerformanceWarning)
    assert issubclass(PerformanceWarning, WhippleKickWarning)  # filtered with the package's other warnings
    text = str(caught[0].message)
    assert text.startswith("the fast call into the compiled model is not available: ") and "\n" not in text
    assert ("Python headers are missing" if cause == "headers" else f"building it with {compilers[0]} failed") in text
    assert "about 1.9 times as costly" in text
