"""The fast path's chunk loop in C (:mod:`whipple_kick.simulate.lsoda_c`) against the odeint path it replaces.

Both run SciPy's LSODA (the same C source, odeint's options, the same LAPACK routines) on the same compiled
model, so the comparison is exact (tolerance 0): the same samples bit for bit, the same evaluation counts, the
same ending. A difference of one ulp would mean a different call sequence, i.e. a bug in the C driver.
"""
import numpy as np
import pytest

from whipple_kick.library import inputs
from whipple_kick.simulate import assembly, integration, lsoda, lsoda_c, simulation


def _states(scenario):
    kick = inputs.kick_of(scenario.validate())
    return integration.integrate_run(assembly.assemble(scenario, kick), scenario, kick).states


def _both(scenario, monkeypatch):
    """The run's states with the C chunk loop, then with odeint's (the driver made unavailable)."""
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

    def counting(self, *args):
        used.append(1)
        return original(self, *args)
    monkeypatch.setattr(lsoda_c.FastChunks, "__call__", counting)
    _states(simulation.Scenario(duration=1.0))
    assert used


@pytest.mark.parametrize("settings", [
    dict(pressure_kpa=300.0, fz_n=570.0),                  # a thesis case (the most Jacobians of the nine)
    dict(pressure_kpa=500.0, fz_n=701.0),
    dict(pressure_kpa=400.0, fz_n=635.0, controller="off"),   # falls: the careful path ends it (steer limit)
], ids=["300kPa_570N", "500kPa_701N", "off_falls"])
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

    def counting_call(self, grid, cuts, x, counts):
        done, states, x = original_call(self, grid, cuts, x, counts)
        resumed.append(done > 0 and cuts[0] > 0)   # chunks done in C after a careful one in the same piece
        return done, states, x
    monkeypatch.setattr(lsoda, "_careful_chunk", counting_careful)
    monkeypatch.setattr(lsoda_c.FastChunks, "__call__", counting_call)
    a, b = _both(simulation.Scenario(duration=2.0), monkeypatch)
    assert careful and any(resumed)
    assert not a.failed
    _assert_identical(a, b)
