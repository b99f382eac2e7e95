"""``recommend-pressure --posterior DIR`` and calibrate's answer flags (issue 39 items 3-4): one-line refusals
with exit status 2, the answer read from the folder or run there."""
import json

import pandas as pd
import pytest

from whipple_kick import cli
from whipple_kick.library import priors
from whipple_kick.studies import calibration as cal
from whipple_kick.studies import posterior_study as ps

CELLS3 = [(570.0, 300.0), (635.0, 400.0), (701.0, 500.0)]


@pytest.fixture(scope="module")
def calibrated(tmp_path_factory):
    """A calibrate folder written by hand: four posterior rows of the gain scale and carcass stiffness scale
    and the settings of the default model runner (rigid rider, kicks to the right)."""
    folder = tmp_path_factory.mktemp("calibrated")
    spec = priors.load()
    pl = cal.choose_priors(spec, ["gain_scale", "carcass_stiffness_scale"])
    pd.DataFrame({"gain_scale": [0.8, 0.9, 1.0, 1.1], "carcass_stiffness_scale": [0.6, 0.7, 0.8, 0.9]}).to_csv(
        folder / "posterior.csv", index=False)
    settings = cal.settings(pl, None, CELLS3, list(cal.FEATURE_UNITS), spec)
    (folder / cal.SETTINGS_FILE).write_text(json.dumps(settings))
    return folder


def _console(main, argv, capsys):
    with pytest.raises(SystemExit) as info:
        main(argv)
    out, err = capsys.readouterr()
    return info.value.code, out, err


@pytest.mark.parametrize("argv_of, message", [
    (lambda d: ["--posterior", str(d / "nowhere")], "no such folder"),
    (lambda d: ["--posterior", str(d)], "no posterior.csv in it"),
    (lambda d: [], "the following arguments are required: --fz"),
    (lambda d: ["--fz", "635", "--prior-study", str(d)], "--prior-study goes with --posterior"),
])
def test_recommend_posterior_refuses_a_bad_folder_in_one_line(tmp_path, capsys, argv_of, message):
    code, out, err = _console(cli.recommend_main, argv_of(tmp_path), capsys)
    assert code == 2 and message in err and err.count("\n") == 1, err


@pytest.mark.parametrize("argv, message", [
    (["--samples", "5"], "--samples = 5 is more than the posterior's 4 rows"),
    (["--samples", "1"], "--samples = 1 posterior rows is outside the allowed range [2, 100000] posterior rows"),
    (["--pressures", "300", "900"], "pressure of tyre T03 = 900.0 kPa is outside the allowed range [300, 500] kPa"),
    (["--fz", "-5"], "rear-tyre load fz = -5.0 N is outside the allowed range (0, inf] N"),
])
def test_recommend_posterior_refuses_bad_values_before_any_run(calibrated, capsys, argv, message):
    code, _, err = _console(cli.recommend_main, ["--posterior", str(calibrated), *argv], capsys)
    assert code == 2 and message in err and err.count("\n") == 1, err


def test_recommend_posterior_refuses_other_studies_flags(calibrated, capsys):
    code, _, err = _console(cli.recommend_main, ["--posterior", str(calibrated), "--uncertain", "--fine"], capsys)
    assert code == 2 and "--uncertain, --fine cannot go with --posterior" in err and err.count("\n") == 1


def test_recommend_posterior_runs_then_reads_the_answer(calibrated, capsys, tmp_path):
    """Run (2 rows, 2 pressures, one load) into the folder, then read it back without running; a prior study's
    P(best) is put beside; a prior-study folder without p_best.csv is refused before any run."""
    prior = tmp_path / "prior"
    prior.mkdir()
    code, _, err = _console(cli.recommend_main, ["--posterior", str(calibrated), "--samples", "2", "--fz", "635",
                                                 "--pressures", "300", "500", "--prior-study", str(prior)], capsys)
    assert code == 2 and "no p_best.csv in it" in err and err.count("\n") == 1
    pd.DataFrame([{"fz_n": 635.0, "criterion": "settling", "pressure_kpa": 300.0, "p": 0.25, "low": 0.1,
                   "high": 0.5, "rows": 64}]).to_csv(prior / "p_best.csv", index=False)
    argv = ["--posterior", str(calibrated), "--samples", "2", "--fz", "635", "--pressures", "300", "500",
            "--workers", "1", "--prior-study", str(prior)]
    code, out, err = _console(cli.recommend_main, argv, capsys)
    assert code == 0, err
    table = pd.read_csv(calibrated / "p_best.csv")
    assert list(table.columns) == ps.P_BEST_COLUMNS and len(table) == 2 * 3
    assert "conditional on: rider_body rigid" in out and "prior 0.25 (0.10-0.50)" in out
    assert (calibrated / cli.ANSWER_FIGURE).stat().st_size > 1000
    beside = pd.read_csv(calibrated / ps.BESIDE_PRIOR)
    assert beside["p_prior"].notna().sum() == 1
    code, out, err = _console(cli.recommend_main, ["--posterior", str(calibrated)], capsys)
    assert code == 0 and "read from" in out and "635 N" in out


@pytest.mark.parametrize("argv, message", [
    (["--samples", "1"], "--samples = 1 must be 0 (no answer) or a whole number >= 2"),
    (["--held-out", "pressure"], "argument --held-out: invalid choice: 'pressure'"),
    (["--lqr-model", "pid"], "argument --lqr-model: invalid choice: 'pid'"),
])
def test_calibrate_refuses_bad_answer_flags(tmp_path, capsys, argv, message):
    code, out, err = _console(cli.calibrate_main, ["--out", str(tmp_path), *argv], capsys)
    assert code == 2 and message in err and err.count("\n") == 1, err
