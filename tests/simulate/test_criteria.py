"""The recovery criteria: one declaration and its function each, read by everything that lists criteria."""
import math

import numpy as np
import pandas as pd
import pytest

import whipple_kick as wk
from whipple_kick.simulate import criteria, results, simulation

#: Roll within this of its steady value counts as settled (the test criterion's own threshold).
_ROLL_BAND_RAD = math.radians(0.5)


def _roll_settled(summary, trajectory):
    """Time after the kick from which |roll - steady roll| stays within 0.5 deg; None if it is outside at the end."""
    t = np.asarray(trajectory["time"])
    off = np.abs(np.asarray(trajectory["roll"]) - summary["steady_state"]["roll_rad"]) > _ROLL_BAND_RAD
    after = t >= 0.0
    if off[after][-1]:
        return None
    outside = np.flatnonzero(off & after)
    return 0.0 if outside.size == 0 else float(t[outside[-1] + 1])


@pytest.fixture
def roll_settled():
    """A criterion declared here, in the test module alone (removed again after the test)."""
    criteria.declare("roll_settled", tie_break="settling", text="roll back within 0.5 deg of steady",
                     short="roll settled", spread_s=0.05, columns_read=("time", "roll"))(_roll_settled)
    try:
        yield criteria.CRITERIA["roll_settled"]
    finally:
        del criteria.CRITERIA["roll_settled"]


def test_a_criterion_declared_in_a_test_is_in_every_list(roll_settled, capsys):
    """The recommender's spreads and columns, the uncertainty figures the command writes, the command's choices
    and help all list it: nothing else was edited."""
    from conftest import run_console
    assert roll_settled.column == "criteria.roll_settled" and roll_settled.columns[1] == "recovery.time_s"
    assert wk.recommend.CRITERION_SPREAD_S["roll_settled"] == 0.05
    assert "criteria.roll_settled" in wk.recommend._recommendation_columns()
    assert {"recovery_roll_settled.png", "sobol_roll_settled.png"} <= set(wk.cli.UNCERTAINTY_FIGURES)
    code, text, _ = run_console(wk.cli.recommend_main, ["--help"], capsys)
    assert code == 0 and "roll-settled: roll back within 0.5 deg of steady" in " ".join(text.split())
    code, _, err = run_console(wk.cli.recommend_main, ["--fz", "635", "--criterion", "no-such"], capsys)
    assert code == 2 and "roll-settled" in err
    assert wk.recommend.criterion_key("roll-settled") == "roll_settled"


def test_a_declared_criterion_is_in_the_run_summary_and_its_table_row(roll_settled):
    """Its value is in the summary's criteria section and the flattened row (a sweep table's), the same number
    its function gives, also on a sweep's lean path; in the default 6 s run the roll settles (3.06 s after the
    kick, as the rates do at 2.75 s)."""
    result = simulation.run(simulation.Scenario())
    value = result.summary["criteria"]["roll_settled"]
    assert value == _roll_settled(result.summary, result.trajectory)
    assert 0.2 < value < 6.0
    assert results.flatten_summary(result.summary)["criteria.roll_settled"] == value
    # A sweep's lean path (no table, only the columns the summary reads) keeps the columns the criterion reads.
    lean = simulation.run(simulation.Scenario(), columns=())
    assert isinstance(lean.trajectory, dict) and lean.summary["criteria"]["roll_settled"] == value


def test_a_declared_criterion_ranks_the_pressures():
    """Ranked by its own column, its tie-break's column after it."""
    criteria.declare("roll_settled", tie_break="settling", text="roll settled", short="roll settled",
                     spread_s=0.05)(_roll_settled)
    try:
        rows = pd.DataFrame({"pressure_kpa": [300.0, 400.0, 500.0], "measured": [True] * 3,
                             "criteria.roll_settled": [1.0, 0.5, 0.5], "recovery.time_s": [1.0, 3.0, 2.0],
                             "last_peak_time_s": [np.nan] * 3, "fell": [False] * 3, "status": ["ok"] * 3})
        assert list(np.argsort(wk.recommend._rank(rows, "roll_settled")) + 1) == [3, 2, 1]
        assert wk.recommend._verdict(rows, "roll_settled") == (500.0, 0.0, "no clear optimum")
    finally:
        del criteria.CRITERIA["roll_settled"]


def test_the_criteria_a_run_reports_elsewhere_are_their_functions_values():
    """settling and last_peak name the summary entries that hold them: their functions read the same numbers,
    and the summary's criteria section is empty (nothing is reported twice)."""
    result = simulation.run(simulation.Scenario(duration=3.0))
    flat = results.flatten_summary(result.summary)
    for key in ("settling", "last_peak"):
        c = criteria.CRITERIA[key]
        assert c.reported and c.value(result.summary, result.trajectory) == flat[c.column]
    assert result.summary["criteria"] == {}


def test_a_criterion_that_gives_nan_is_refused_by_name():
    criteria.declare("broken", tie_break="settling", text="x", short="x", spread_s=1.0)(lambda s, t: math.nan)
    try:
        with pytest.raises(ValueError, match="criterion 'broken' gave nan"):
            criteria.summary_section({}, None)
    finally:
        del criteria.CRITERIA["broken"]
    with pytest.raises(ValueError, match="spread_s must be a positive"):
        criteria.declare("bad", tie_break="settling", text="x", short="x", spread_s=0.0)
