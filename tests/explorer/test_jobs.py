"""The work the page hands to the pool, run here in-process: a run's folder, its words, the overlay, the
stability and the animation, each the files its command writes."""
import pytest

from whipple_kick.explorer import jobs
from whipple_kick.simulate.results import Result
from whipple_kick.simulate.scenario import Scenario

SHORT = Scenario(duration=2.0, output_rate=200.0)


@pytest.fixture(scope="module")
def run_folder(tmp_path_factory):
    folder = tmp_path_factory.mktemp("run") / "kick"
    return folder, jobs.run_into(SHORT, folder)


def test_a_run_writes_simulates_files_and_says_how_it_ended(run_folder):
    folder, outcome = run_folder
    assert outcome["files"] == ["trajectory.csv", "summary.json", "scenario.toml", "response.png"]
    result = Result.load(folder)
    assert result.scenario == SHORT and outcome["outcome"] == result.summary["outcome"] == "completed"
    assert outcome["words"] == jobs.words(result.summary)
    if result.summary["recovery"]["time_s"] is None:
        assert outcome["words"][0].startswith("Not recovered within the run's 2 s")
    else:
        assert outcome["words"][0].startswith(f"Recovered {result.summary['recovery']['time_s']:.3f} s")
    assert Scenario.from_file(folder / "scenario.toml") == SHORT


def test_a_fall_is_said(tmp_path):
    outcome = jobs.run_into(Scenario(controller="off", duration=3.0, output_rate=200.0), tmp_path / "fall")
    assert outcome["outcome"] == "fell" and outcome["recovery_s"] is None
    assert outcome["words"][0].startswith("The bicycle FELL 1.5")
    assert "linearly unstable" in " ".join(outcome["words"])   # the rider-less bicycle's note


def test_a_numerical_failure_is_said():
    summary = {"outcome": "failed", "fell": False, "message": "LSODA: repeated error test failures",
               "scenario": {}, "metrics": {}, "controller": {}, "linear_stability": {}}
    assert jobs.words(summary) == ["The run FAILED numerically: LSODA: repeated error test failures (the download "
                                   "holds the run up to then)."]


def test_overlay_and_animation(run_folder, tmp_path):
    folder, _ = run_folder
    other = tmp_path / "other"
    jobs.run_into(SHORT.with_changes(pressure_kpa=300.0), other)
    jobs.overlay([str(folder), str(other)], [1, 2], tmp_path / "compare.png")
    assert (tmp_path / "compare.png").stat().st_size > 10_000
    movie = jobs.animate_into(str(other), fps=5, size=(160, 90))
    assert (other / jobs.ANIMATION).read_bytes()[:6] == b"GIF89a" and movie["frames"] > 5


def test_stability_writes_the_stability_commands_files(tmp_path):
    lines = jobs.stability_into(Scenario(symmetric_tyres=True, speed=3.0), [3.0, 4.0], tmp_path)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["eigenvalues.csv", "stability.png", "summary.json"]
    assert lines[1].strip() == "open loop (no rider control):"


def test_the_pool_is_the_sweeps():
    import os

    from whipple_kick.studies import sweep_engine
    assert jobs.pool() is sweep_engine._default_pool(os.cpu_count() or 1)
