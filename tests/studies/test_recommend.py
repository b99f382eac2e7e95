"""The pressure recommender: ranking, margins against the model's spread, the recommend-pressure command."""
import os
import subprocess
import sys

import numpy as np
import pandas as pd
import pytest

import whipple_kick as wk
from whipple_kick.errors import InputError
from whipple_kick.simulate.scenario import Scenario

# Short runs: the sweep machinery, not the physics, is under test here.
BASE = Scenario(duration=3.0, settle=0.1, output_rate=200.0, fz_n=635.0)


def _cli(*args):
    exe = os.path.join(os.path.dirname(sys.executable), "recommend-pressure")
    return subprocess.run([exe, *args], capture_output=True, text=True, timeout=600)


def test_recommend_pressure_prints_table_and_recommendation_for_thesis_loads():
    proc = _cli("--fz", "570", "635", "701")
    assert proc.returncode == 0, proc.stderr
    out = proc.stdout
    for fz in (570, 635, 701):
        assert f"rear load {fz} N, tyre T03" in out
        assert f"recommendation for {fz} N: " in out
    # Three pressures per load, each a table row with the recovery time, and the margin to the second best.
    rows = [line.split() for line in out.splitlines() if line.strip().startswith(("300 ", "400 ", "500 "))]
    assert len(rows) == 9 and all(float(r[2]) > 0 for r in rows)
    assert out.count("ahead of the second best") == 3 and "ranked by the recovery time" in out


@pytest.mark.parametrize("args, message", [
    (("--fz", "-3"), "rear-tyre load fz = -3.0 N is outside the allowed range [322.71, 1535.65] N"),
    (("--fz", "635", "10"), "rear-tyre load fz = 10.0 N is outside the allowed range [322.71, 1535.65] N"),
    (("--fz", "635", "--pressures", "700"), "700.0 kPa is outside the allowed range [300, 500] kPa"),
    (("--fz", "635", "--tyre", "T99"), "tyre = 'T99' is unknown"),
    (("--fz", "x"), "'x' is not a number (N)"),
])
def test_recommend_pressure_bad_input_is_one_line_exit_2(args, message):
    proc = _cli(*args)
    assert proc.returncode == 2
    assert message in proc.stderr and len(proc.stderr.strip().splitlines()) == 1
    assert proc.stdout == ""


def test_recommend_pressure_function_fine_grid():
    # 3 s runs: too short for the rates to settle, so rank by the thesis' last-peak time here.
    base = Scenario(duration=3.0, output_rate=200.0)
    rec = wk.recommend.recommend_pressure(701, pressures=[300, 500], fine=True, step_kpa=50, base=base,
                                   criterion="last-peak")
    assert rec.criterion == "last_peak"
    assert list(rec.table["pressure_kpa"]) == [300.0, 350.0, 400.0, 450.0, 500.0]
    assert list(rec.table["measured"]) == [True, False, True, False, True]
    best = rec.table.loc[rec.table["rank"] == 1]
    assert float(best["pressure_kpa"].iloc[0]) == rec.best_pressure_kpa
    assert float(best["last_peak_time_s"].iloc[0]) == rec.table["last_peak_time_s"].min()
    assert rec.best_measured_kpa in (300.0, 400.0, 500.0)
    assert "recommendation for 701 N:" in wk.recommend.format_recommendation(rec)


# ---------------------------------------------------------- the recommender's rules on the nine cases

@pytest.fixture(scope="module")
def nine_case_recommendations(tmp_path_factory):
    """The nine thesis cases (default scenario, 6 s) ranked by both criteria (one sweep: the second
    call resumes the folder of the first and runs nothing)."""
    folder = tmp_path_factory.mktemp("nine") / "sweep"
    return {criterion: wk.recommend.recommend_pressures([570, 635, 701], criterion=criterion, folder=folder)
            for criterion in ("settling", "last-peak")}


@pytest.mark.parametrize("criterion", ["settling", "last-peak"])
def test_recommendation_margin_and_no_clear_optimum_rule_on_the_nine_cases(nine_case_recommendations,
                                                                        criterion):
    key = wk.recommend.criterion_key(criterion)
    column = wk.recommend.CRITERIA[key].column
    for rec, fz in zip(nine_case_recommendations[criterion], (570.0, 635.0, 701.0), strict=True):
        assert rec.fz_n == fz and rec.criterion == key and rec.spread_s == wk.recommend.CRITERION_SPREAD_S[key] > 0
        table = rec.table
        assert list(table["pressure_kpa"]) == [300.0, 400.0, 500.0] and table["measured"].all()
        ok = table[(table["status"] == "ok") & ~table["fell"].astype(bool) & table[column].notna()]
        values = np.sort(ok[column].to_numpy(dtype=float))
        assert rec.best_pressure_kpa == float(ok.loc[ok[column].idxmin(), "pressure_kpa"])
        assert rec.margin_s == pytest.approx(values[1] - values[0], abs=1e-12)
        assert rec.verdict == ("no clear optimum" if rec.margin_s < rec.spread_s else "clear")
        assert int(table.loc[table["pressure_kpa"] == rec.best_pressure_kpa, "rank"].iloc[0]) == 1
        text = wk.recommend.format_recommendation(rec)
        assert f"{rec.margin_s:.3f} s ahead of the second best" in text
        assert f"{rec.spread_s:.3f} s" in text
        assert ("no clear optimum" in text) == (rec.verdict == "no clear optimum")
        for p in (300, 400, 500):   # every pressure's value is printed
            cell = table.loc[table["pressure_kpa"] == p, column].iloc[0]
            assert f"{cell:.3f}" in text


@pytest.mark.parametrize("fz, base", [
    # The issue's case, which needs the thesis' force lag: 2 m/s, 35 m/s^2; 400 kPa falls, 300 and
    # 500 kPa do not (measured). On the default tyre nothing falls there, nor at 2-3 m/s for any
    # load and pressure of the nine cases with kicks of 30-100 m/s^2 over 150 mm.
    (701, Scenario(speed=2.0, design_speed=2.0, kick_accel=35.0, duration=4.0,
                              tyre_transient="force_lag")),
    # On the default tyre a longer plate travel does it: 350 mm in 150 ms (31 m/s^2, within the
    # plate peaks the thesis measured) at 701 N: 300 and 400 kPa fall (1.38 and 1.84 s), 500 kPa
    # recovers (3.27 s, roll at most 16.6 deg).
    (701, Scenario(kick_displacement=0.35, kick_duration=0.15)),
], ids=["force_lag_issue_case", "default_350mm_kick"])
def test_a_run_that_fell_is_never_ranked_ahead(fz, base):
    """By either criterion a run that fell ranks after the runs that did not fall, and is never the
    recommendation."""
    for criterion in ("last-peak", "settling"):
        rec = wk.recommend.recommend_pressure(fz, base=base, criterion=criterion)
        fell = rec.table["fell"].astype(bool).to_numpy()
        assert fell.any() and not fell.all()
        assert rec.table["rank"].to_numpy()[fell].min() > rec.table["rank"].to_numpy()[~fell].max()
        assert rec.best_pressure_kpa is not None and rec.best_pressure_kpa not in set(rec.table["pressure_kpa"][fell])


def _rows(**columns):
    n = len(columns["pressure_kpa"])
    defaults = {"measured": [True] * n, "recovery.time_s": [np.nan] * n, "last_peak_time_s": [np.nan] * n,
                "fell": [False] * n, "status": ["ok"] * n}
    return pd.DataFrame({**defaults, **columns})


def test_ranking_rules_on_a_synthetic_table():
    # A fall with the shortest last-peak time still ranks last; ties broken by the other criterion.
    rows = _rows(pressure_kpa=[300.0, 400.0, 500.0], last_peak_time_s=[1.0, 0.2, 1.0],
                 **{"recovery.time_s": [4.0, np.nan, 3.0]}, fell=[False, True, False])
    assert list(np.argsort(wk.recommend._rank(rows, "last_peak")) + 1) == [2, 3, 1]
    assert wk.recommend._verdict(rows, "last_peak") == (500.0, 0.0, "no clear optimum")
    assert wk.recommend._verdict(rows, "settling") == (500.0, 1.0, "clear")
    # Only one pressure recovered: it is the recommendation, with no margin.
    one = _rows(pressure_kpa=[300.0, 400.0], **{"recovery.time_s": [np.nan, 3.0]})
    assert wk.recommend._verdict(one, "settling") == (400.0, None, "clear")
    assert wk.recommend._verdict(_rows(pressure_kpa=[300.0, 400.0]), "settling") == (None, None, "none recovered")
    # A failed case has no result: the verdict is never "clear" (issue 31 item 10; it was).
    failed = _rows(pressure_kpa=[300.0, 400.0], status=["failed", "ok"], **{"recovery.time_s": [1.0, 3.0]})
    assert wk.recommend._verdict(failed, "settling") == (400.0, None, "incomplete")
    assert wk.recommend._verdict(_rows(pressure_kpa=[400.0], **{"recovery.time_s": [3.0]}), "settling") == (
        None, None, "nothing to choose")
    assert wk.recommend.criterion_key("last-peak") == "last_peak"
    with pytest.raises(InputError, match="settling, last-peak"):
        wk.recommend.criterion_key("fastest")


def test_a_failed_case_ranks_after_the_falls_and_the_verdict_says_how_many_failed():
    """Issue 31 item 10: a failing case (no result) was ranked like a fall, among the falls by pressure, and the
    verdict could still read "clear". Now the failed cases come after every fall and the verdict is
    "incomplete", naming how many failed."""
    rows = _rows(pressure_kpa=[300.0, 400.0, 500.0, 600.0], fell=[False, True, False, False],
                 status=["failed", "ok", "ok", "ok"], **{"recovery.time_s": [np.nan, np.nan, 2.0, 3.0]})
    rank = list(np.argsort(wk.recommend._rank(rows, "settling")) + 1)
    assert rank == [4, 3, 1, 2]                    # the failed 300 kPa after the fall at 400 kPa
    rows["rank"] = rank
    for col in wk.recommend._recommendation_columns():
        rows[col] = rows[col] if col in rows else np.nan
    rows["error"] = ["InputError: a stand-in", None, None, None]
    best, margin, verdict = wk.recommend._verdict(rows, "settling")
    assert (best, margin, verdict) == (500.0, 1.0, "incomplete")
    rec = wk.recommend.Recommendation(635.0, "T03", best, best, "settling", margin, 0.218, verdict, rows, failed=1)
    text = wk.recommend.format_recommendation(rec)
    last = text.splitlines()[-1]
    assert "1 of 4 cases failed (300 kPa" in last and "500 kPa" in last and "clear" not in last, last
    assert "failed: InputError: a stand-in" in text


def test_recommend_pressure_with_a_failing_pressure_is_incomplete(monkeypatch):
    """End to end through the sweep (in threads, so the stand-in failure reaches the cases): the 400 kPa case
    fails, the others run."""
    import concurrent.futures as cf

    from whipple_kick.simulate import simulation
    run = simulation.run

    def failing_at_400(scenario, **kwargs):
        if scenario.pressure_kpa == 400.0:
            raise RuntimeError("a stand-in failure")
        return run(scenario, **kwargs)
    monkeypatch.setattr(simulation, "run", failing_at_400)
    short = Scenario(duration=3.0, settle=0.1, output_rate=200.0)
    with cf.ThreadPoolExecutor(1) as executor:
        rec = wk.recommend.recommend_pressure(635, pressures=[300.0, 400.0, 500.0], base=short, executor=executor)
    assert rec.failed == 1 and rec.verdict == "incomplete"
    assert rec.table.loc[rec.table["status"] != "ok", "rank"].tolist() == [3]
    assert "1 of 3 cases failed (400 kPa" in wk.recommend.format_recommendation(rec)


def test_one_measured_pressure_leaves_nothing_to_choose():
    """T01 was measured at 400 kPa only (thesis Table 7.9): there is nothing to choose."""
    rec = wk.recommend.recommend_pressure(635, tyre="T01", base=Scenario(duration=1.0, output_rate=200.0))
    assert rec.verdict == "nothing to choose" and rec.best_pressure_kpa is None and rec.margin_s is None
    assert list(rec.table["pressure_kpa"]) == [400.0]
    assert "nothing to choose: only 400 kPa was run (T01 was measured at one pressure)" in (
        wk.recommend.format_recommendation(rec))


def test_recommend_pressure_cli_criterion_and_extend(tmp_path):
    folder = tmp_path / "runs"
    first = _cli("--fz", "635", "--pressures", "300", "500", "--duration", "3", "--criterion", "last-peak",
                 "--out", str(folder), "--no-progress")
    assert first.returncode == 0, first.stderr
    assert "ranked by the last-peak time" in first.stdout
    assert (folder / "recommendation.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"   # beside table.csv
    assert "wrote recommendation.png" in first.stdout
    # Another sweep into the same folder needs --extend.
    refused = _cli("--fz", "701", "--pressures", "300", "--duration", "3", "--out", str(folder), "--no-progress")
    assert refused.returncode == 2 and "extend" in refused.stderr
    extended = _cli("--fz", "701", "--pressures", "300", "--duration", "3", "--out", str(folder), "--extend",
                    "--no-progress")
    assert extended.returncode == 0, extended.stderr
    assert len(wk.sweep_store.read_log(folder)) == 3


def test_recommend_pressure_help_prints_single_percent_signs():
    """argparse formats help strings with %, not the description: "5 %%" there was printed as is."""
    proc = _cli("--help")
    assert proc.returncode == 0 and "%%" not in proc.stdout and "within 5 % of their first peaks" in proc.stdout


def test_a_sweep_whose_every_case_fails_is_an_error_not_a_verdict(monkeypatch):
    """Before: the verdict "none recovered" and, from the command line, exit status 0."""
    import concurrent.futures as cf

    from whipple_kick.simulate import simulation
    from whipple_kick.studies.sweep_engine import SweepFailed

    def broken(scenario, **options):
        raise ZeroDivisionError("a bug")
    monkeypatch.setattr(simulation, "run", broken)
    with cf.ThreadPoolExecutor(1) as pool, pytest.raises(SweepFailed) as info:
        wk.recommend.recommend_pressures([635.0], pressures=[300, 400], base=BASE, executor=pool)
    message = str(info.value)
    assert message.startswith("all 2 cases failed (a bug or a broken set-up, not a result); the first, case ")
    assert message.endswith("with ZeroDivisionError: a bug") and "\n" not in message


def test_recommend_pressure_reports_a_sweep_whose_every_case_failed_in_one_line_exit_1(monkeypatch, capsys):
    from whipple_kick import cli
    from whipple_kick.studies.sweep_engine import SweepFailed

    def failed(*args, **kwargs):
        raise SweepFailed("all 3 cases failed (...); the first, case 0123, with ZeroDivisionError: a bug")
    monkeypatch.setattr(wk.recommend, "recommend_pressures", failed)
    with pytest.raises(SystemExit) as info:
        cli.recommend_main(["--fz", "635", "--pressures", "300", "400", "500"])
    out, err = capsys.readouterr()
    assert info.value.code == 1 and out == ""
    assert err == "recommend-pressure: all 3 cases failed (...); the first, case 0123, with ZeroDivisionError: a bug\n"
