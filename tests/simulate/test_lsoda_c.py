"""LSODA driven from C (:mod:`whipple_kick.simulate.lsoda_c`) against the Python paths it replaces.

The fast path's chunk loop against odeint's: both run SciPy's LSODA (the same C source, odeint's options, the
same LAPACK routines) on the same compiled model, so the comparison is exact (tolerance 0): the same samples bit
for bit, the same evaluation counts, the same ending. A difference of one ulp would mean a different call
sequence, i.e. a bug in the C driver. There the careful path runs in Python on both sides.

The careful path (a chunk with a fall, LSODA's trouble or the budget) in C against scipy's LSODA stepped from
Python: the same steps, so the same evaluation counts, outcome, message and sample times (tolerance 0); the
samples, the fall time and the state at the fall come from the same interpolant evaluated in another order
(Horner's rule in C, ``np.dot`` in SciPy), so they agree to round-off: each state within
``STATE_TOLERANCE`` = 1e-13 of its column's largest value, the fall time within ``FALL_TIME_TOLERANCE`` =
1e-12 s. Measured on the falling regression references, the falling runs below and 34 falling runs of the
thesis' set-up and the 3 m/s rider at 1.5-2.2 m/s, kicks of 50-200 m/s^2 and the nine cases without control:
at most 4.3e-16 of a column's peak and no difference in any fall time. Why these bounds: the interpolant sums
at most 13 terms, so the two orders differ by a few tens of ulps of a state's size; brentq stops within
4 eps (1 + t) of the root of each, and round-off in the margin (1e-15 rad) moves the root by 2e-16 s at the
slowest rate of the limited angle at a fall in those runs (4.3 rad/s). A wrong interpolant (a column, the step or the order's rescale) moves the samples by the
local error, rtol x a state's size, 1e3 times the bound and more.
"""
import functools
import warnings

import numpy as np
import pytest

from tests.simulate.test_regression import CONTACT_PATCH, DATA, THESIS_FORM, load_reference
from whipple_kick.library import inputs
from whipple_kick.model import slip
from whipple_kick.simulate import assembly, integration, lsoda, lsoda_c, simulation


def _states(scenario):
    kick = inputs.kick_of(scenario.validate())
    return integration.integrate_run(assembly.assemble(scenario, kick), scenario, kick).states


def _python_careful(monkeypatch):
    """The careful path through scipy's LSODA from Python, also where the fast chunks run in C."""
    monkeypatch.setattr(lsoda, "_careful_chunk_in_c", lambda chunks_in_c, *arguments: lsoda._careful_chunk(*arguments))


def _both(scenario, monkeypatch):
    """The run's states with the C chunk loop, then with odeint's (the driver made unavailable); the careful
    path in Python in both, so that the fast paths are compared."""
    with monkeypatch.context() as m:
        _python_careful(m)
        with_c = _states(scenario)
    with monkeypatch.context() as m:
        m.setattr(lsoda_c, "driver", lambda: None)
        with_odeint = _states(scenario)
    return with_c, with_odeint


def _assert_identical(a, b):
    assert (a.nfev, a.njev, a.evaluations) == (b.nfev, b.njev, b.evaluations)
    assert (a.fell, a.fall_time, a.fall_reason, a.failed, a.message) == (b.fell, b.fall_time, b.fall_reason,
                                                                          b.failed, b.message)
    np.testing.assert_array_equal(a.t, b.t)
    np.testing.assert_array_equal(a.x, b.x)
    np.testing.assert_array_equal(a.end_state, b.end_state)


def test_the_driver_builds_and_is_used_for_the_compiled_model(monkeypatch):
    """The comparisons below compare two paths, not one with itself: the C loop runs for a compiled model."""
    assert lsoda_c.driver() is not None
    used = []
    original = lsoda_c.FastChunks.__call__

    def counting(self, *args, **kwargs):
        used.append(1)
        return original(self, *args, **kwargs)
    monkeypatch.setattr(lsoda_c.FastChunks, "__call__", counting)
    _states(simulation.Scenario(duration=1.0))
    assert used


@pytest.mark.parametrize("settings", [
    dict(pressure_kpa=300.0, fz_n=570.0),                  # a thesis case (the most Jacobians of the nine)
    dict(pressure_kpa=500.0, fz_n=701.0),
    dict(pressure_kpa=400.0, fz_n=635.0, controller="off"),   # falls: the careful path ends it (steer limit)
    # 5 Hz: the kick's piece (0.15 s) holds no sample, so the C loop's rows written into the result are not taken
    # in place there (its one chunk has no sample after its start); the next piece's are.
    dict(output_rate=5.0),
], ids=["300kPa_570N", "500kPa_701N", "off_falls", "5Hz_samples"])
def test_the_c_chunk_loop_gives_the_odeint_path_bit_for_bit(settings, monkeypatch):
    a, b = _both(simulation.Scenario(duration=6.0, **settings), monkeypatch)
    _assert_identical(a, b)
    if settings.get("controller") == "off":
        assert a.fell


def test_a_chunk_over_the_budget_goes_to_the_careful_path_as_before(monkeypatch):
    """The budget is checked in C after each chunk as in Python: the careful path then fails the run, the same way."""
    monkeypatch.setattr(lsoda, "DEFAULT_BUDGET", lsoda.Budget(allowance=3000, per_second=1000.0))
    a, b = _both(simulation.Scenario(duration=3.0), monkeypatch)
    assert a.failed and "budget" in a.message
    _assert_identical(a, b)


def test_the_c_loop_resumes_after_a_chunk_the_careful_path_did(monkeypatch):
    """A chunk LSODA gives up on in C (here: more than 25 steps between two samples, a small stall window)
    goes to the careful path, and the C loop takes the piece's next chunks from the state it reached.

    ``stall_progress`` is tiny so that the careful path completes the chunk rather than failing the run.
    """
    monkeypatch.setattr(lsoda, "DEFAULT_BUDGET", lsoda.Budget(stall_window=100, stall_progress=1e-12))
    careful, resumed = [], []
    original_careful, original_call = lsoda._careful_chunk, lsoda_c.FastChunks.__call__

    def counting_careful(*args, **kwargs):
        careful.append(1)
        return original_careful(*args, **kwargs)

    def counting_call(self, grid, cuts, x, counts, **kwargs):
        done, states, x = original_call(self, grid, cuts, x, counts, **kwargs)
        resumed.append(done > 0 and cuts[0] > 0)   # chunks done in C after a careful one in the same piece
        return done, states, x
    monkeypatch.setattr(lsoda, "_careful_chunk", counting_careful)
    monkeypatch.setattr(lsoda_c.FastChunks, "__call__", counting_call)
    a, b = _both(simulation.Scenario(duration=2.0), monkeypatch)
    assert careful and any(resumed)
    assert not a.failed
    _assert_identical(a, b)


# ------------------------------------------------------------------- the careful path in C

STATE_TOLERANCE = 1e-13        # of each state's largest |value| in the run (module docstring)
FALL_TIME_TOLERANCE = 1e-12    # s


def _careful_both(scenario, monkeypatch):
    """The run's states with the careful path in C, then in Python (the fast chunks in C in both)."""
    in_c = _states(scenario)
    with monkeypatch.context() as m:
        _python_careful(m)
        in_python = _states(scenario)
    return in_c, in_python


def _assert_same_to_round_off(a, b):
    """The same steps and ending (exact); the samples, the fall time and the end state to round-off."""
    assert (a.nfev, a.njev, a.evaluations) == (b.nfev, b.njev, b.evaluations)
    assert (a.fell, a.fall_reason, a.failed, a.message) == (b.fell, b.fall_reason, b.failed, b.message)
    assert a.t.shape == b.t.shape and a.x.shape == b.x.shape
    fall = -1 if a.fell else None   # the fall's sample is the fall time
    np.testing.assert_array_equal(a.t[:fall], b.t[:fall])
    if a.fell:
        assert abs(a.fall_time - b.fall_time) <= FALL_TIME_TOLERANCE and a.t[-1] == a.fall_time
    peak = np.max(np.abs(b.x), axis=0)
    assert np.all(np.abs(a.x - b.x) <= STATE_TOLERANCE * peak)
    assert np.all(np.abs(a.end_state - b.end_state) <= STATE_TOLERANCE * peak)


#: Every regression reference whose run ends in a fall (its folder and name).
FALLING_REFERENCES = [(DATA, "off_400kPa_635N"), (THESIS_FORM, "off_400kPa_635N"), (THESIS_FORM, "kick40_400kPa_635N"),
                      (CONTACT_PATCH, "off_400kPa_635N")]


@pytest.mark.parametrize(("folder", "name"), FALLING_REFERENCES, ids=[f"{f.name}/{n}" for f, n in FALLING_REFERENCES])
def test_the_careful_path_in_c_ends_every_falling_reference_as_python_does(folder, name, monkeypatch):
    scenario, _ = load_reference(name, folder)
    a, b = _careful_both(scenario, monkeypatch)
    assert a.fell
    _assert_same_to_round_off(a, b)


FALLING_RUNS = {
    "low_speed": simulation.Scenario(speed=1.5, design_speed=3.0),            # the fork turns over (steer)
    "big_kick": simulation.Scenario(kick_accel=200.0, speed=1.5, design_speed=3.0),
    "thesis_1.92_300kPa": simulation.Scenario.thesis(pressure_kpa=300.0, speed=1.92),   # |roll| reaches 45 deg
    "thesis_1.92_400kPa": simulation.Scenario.thesis(pressure_kpa=400.0, speed=1.92),   # the budget's largest run
    "off_rtol_1e-8": simulation.Scenario(controller="off", rtol=1e-8),
}


def _careful_both_counted(scenario, monkeypatch):
    """:func:`_careful_both`, and how each careful chunk in C ended (a list of statuses)."""
    ended = []
    original = lsoda_c.FastChunks.careful

    def counting(self, *args):
        out = original(self, *args)
        ended.append(out.status)
        return out
    with monkeypatch.context() as m:
        m.setattr(lsoda_c.FastChunks, "careful", counting)
        a, b = _careful_both(scenario, m)
    return a, b, ended


@pytest.mark.parametrize("name", FALLING_RUNS)
def test_the_careful_path_in_c_ends_falling_runs_as_python_does(name, monkeypatch):
    a, b, ended = _careful_both_counted(FALLING_RUNS[name], monkeypatch)
    assert a.fell and ended[-1] == "fell"   # the fall was found in C
    assert a.fall_reason == ("roll" if name == "thesis_1.92_300kPa" else "steer")
    _assert_same_to_round_off(a, b)


#: Budgets that stop the default run in a careful chunk, and the words of each stop: 3000 evaluations and
#: 1000 per second run out; a window of 100 evaluations that must advance 1 ms stalls the first one.
STOPPING_BUDGETS = {"budget": (lsoda.Budget(allowance=3000, per_second=1000.0), "more than the budget 3000 + 1000/s"),
                    "stall": (lsoda.Budget(stall_window=100, stall_progress=1e-3), "advanced it only")}


@pytest.mark.parametrize("stop", STOPPING_BUDGETS)
def test_the_budget_stops_the_careful_path_in_c_as_in_python(stop, monkeypatch):
    budget, words = STOPPING_BUDGETS[stop]
    monkeypatch.setattr(lsoda, "DEFAULT_BUDGET", budget)
    a, b, ended = _careful_both_counted(simulation.Scenario(duration=2.0), monkeypatch)
    assert a.failed and words in a.message and ended[-1] == stop
    _assert_same_to_round_off(a, b)


def test_a_careful_chunk_that_completes_in_c_hands_on_the_state_python_does(monkeypatch):
    """Chunks the fast path gives up on (more than 25 steps between samples) that the careful path completes:
    the run goes on from the exact end state, so every later chunk is the same."""
    monkeypatch.setattr(lsoda, "DEFAULT_BUDGET", lsoda.Budget(stall_window=100, stall_progress=1e-12))
    a, b, ended = _careful_both_counted(simulation.Scenario(duration=2.0), monkeypatch)
    assert ended.count("completed") > 1 and not a.failed
    _assert_same_to_round_off(a, b)


def _one_chunk(x, atol):
    """The two careful paths (C, then Python) and their arguments for one chunk (0-0.5 s, 1 kHz) of the
    default scenario's model from ``x`` (its NaN entries: the steady motion's)."""
    scenario = simulation.Scenario(duration=1.0)
    start = assembly.assemble(scenario, inputs.kick_of(scenario.validate())).start
    rhs = slip.CompiledRHS(start.params)
    rtol = 1e-10
    jac = rhs.jacobian_function(lsoda.default_atol(rtol) / rtol)
    limits = (slip.X["q4"], np.deg2rad(45.0), slip.X["q7"], np.inf)

    def fall(t, x):
        return min(limits[1] - abs(x[limits[0]]), limits[3] - abs(x[limits[2]]))
    chunks = lsoda._chunks_in_c(rhs, jac, rtol, atol, 5000, limits, lsoda.DEFAULT_BUDGET, 0.0)
    arguments = (rhs.fast, np.where(np.isnan(x), start.x, x), np.linspace(0.0, 0.5, 501), rtol, atol, fall, 0,
                 lsoda.DEFAULT_BUDGET, 0.0, jac)
    return (functools.partial(lsoda._careful_chunk_in_c, chunks), lsoda._careful_chunk), arguments


def _one_chunk_both(x, atol):
    """:func:`_one_chunk` run on both paths: their returns and the warnings each raised."""
    paths, arguments = _one_chunk(x, atol)
    out = []
    for careful in paths:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            out.append((careful(*arguments), [str(w.message) for w in caught]))
    return out


def test_a_model_failure_in_the_careful_path_in_c_is_reported_as_in_python():
    """A compression rate of 1e300 m/s: the model's derivative is not finite at the first evaluation."""
    x = np.full(len(slip.STATE_NAMES), np.nan)
    x[slip.X["u9"]] = 1e300
    (a, _), (b, _) = _one_chunk_both(x, lsoda.default_atol(1e-10))
    assert a[3:] == b[3:] == ("failed", "LSODA stopped at t = 0 s: non-finite derivative in the slip model at "
                                        "t = 0 s", (1, 0, 1))
    assert a[2][0] == b[2][0] == 0.0 and np.array_equal(a[2][1], b[2][1]) and np.array_equal(a[1], b[1])


def test_lsoda_refusing_in_the_careful_path_in_c_is_reported_as_in_python():
    """Zero absolute tolerances where states are zero: LSODA refuses (istate -3) on its first call, with
    scipy's warning."""
    (a, warned_c), (b, warned_python) = _one_chunk_both(np.full(len(slip.STATE_NAMES), np.nan),
                                                        np.zeros(len(slip.STATE_NAMES)))
    assert a[3:] == b[3:] == ("failed", "LSODA stopped at t = 0 s: Unexpected istate in LSODA.", (1, 0, 1))
    assert warned_c == warned_python == ["lsoda: Illegal input detected (internal error)."]


def test_a_careful_chunk_in_c_starting_past_the_limit_falls_at_its_start():
    """|roll| = 1 rad > 45 deg at the chunk's start: a fall there, no step taken, on both paths."""
    x = np.full(len(slip.STATE_NAMES), np.nan)
    x[slip.X["q4"]] = 1.0
    (a, _), (b, _) = _one_chunk_both(x, lsoda.default_atol(1e-10))
    assert a[3:] == b[3:] == ("fell", None, (0, 0, 0))
    assert a[0].tolist() == b[0].tolist() == [0.0] and a[2][0] == b[2][0] == 0.0
    assert np.array_equal(a[1], b[1]) and np.array_equal(a[2][1], b[2][1]) and a[2][1][slip.X["q4"]] == 1.0


def test_a_non_finite_start_is_refused_by_both_careful_paths():
    x = np.full(len(slip.STATE_NAMES), np.nan)
    x[slip.X["u9"]] = np.inf
    paths, arguments = _one_chunk(x, lsoda.default_atol(1e-10))
    for careful in paths:
        with pytest.raises(ValueError, match="must be finite"):
            careful(*arguments)


@pytest.mark.parametrize("size", [0, 1, 7, 8, 9, 17, 1000])
def test_the_c_finite_check_is_numpys(size):
    """The C chunk loop's check of a chunk's states (a sum, then value by value where the sum is not finite) says
    what ``np.all(np.isfinite(...))`` says: also for finite values whose sum overflows, and for a NaN or an
    infinity anywhere (in the summed pairs or the rest)."""
    lib = lsoda_c.driver()

    def check(values):
        values = np.ascontiguousarray(values, dtype=float)
        return bool(lib.wk_lsoda_all_finite(values.ctypes.data, values.size))
    rng = np.random.default_rng(size)
    values = rng.normal(size=size)
    assert check(values)
    assert check(np.full(size, 1e308)) and check(np.tile([1e308, -1e308, np.finfo(float).max], size)[:size])
    for position in {0, size // 2, size - 1} if size else ():
        for bad in (np.nan, np.inf, -np.inf):
            spoiled = values.copy()
            spoiled[position] = bad
            assert not check(spoiled) and not np.all(np.isfinite(spoiled))
            spoiled = np.full(size, 1e308)
            spoiled[position] = bad
            assert not check(spoiled)
