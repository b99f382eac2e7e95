"""P(best) under the calibration's posterior (issue 39 item 3): pairing, shares, rules, bad folders."""
import json
import math

import numpy as np
import pandas as pd
import pytest

from whipple_kick.errors import InputError
from whipple_kick.library import priors
from whipple_kick.studies import calibration as cal
from whipple_kick.studies import posterior_study as ps

CELLS3 = [(570.0, 300.0), (635.0, 400.0), (701.0, 500.0)]


@pytest.fixture(scope="module")
def calibrated(tmp_path_factory):
    """A calibrate folder from the toy (posterior of the gain scale and carcass stiffness scale; rigid rider,
    kicks to the right: the toy's settings are the default model runner's)."""
    folder = tmp_path_factory.mktemp("calibrated")
    pl = cal.choose_priors(priors.load(), ["gain_scale", "carcass_stiffness_scale"])
    result, _, _ = cal.known_answer(cal.ToySimulator, pl, np.array([0.5, 0.5]), seed=0, cells=CELLS3,
                                    walkers=16, steps=400, waves=1)
    result.write(folder)
    return folder


def _outcomes(times, fz=635.0, pressures=(300.0, 400.0, 500.0), status=None, fell=None):
    """A synthetic outcomes table: ``times[row][k]`` for each criterion (NaN: not recovered)."""
    rows = []
    for r, row in enumerate(times):
        for k, p in enumerate(pressures):
            rows.append({"row": r, "fz_n": fz, "pressure_kpa": p,
                         "status": "ok" if status is None else status[r][k],
                         "fell": False if fell is None else fell[r][k],
                         "recovery.time_s": row[k], "last_peak_time_s": row[k]})
    return pd.DataFrame(rows)


def test_p_best_known_answer_and_rules():
    """Four rows: 400 kPa fastest twice, a tie 300/500 (half each), a row where none recovered; a failed run
    leaves its row out; a fall ranks last. Shares sum to 1 per load and criterion."""
    nan = math.nan
    times = [[2.0, 1.0, 3.0], [2.0, 1.5, nan], [1.0, 2.0, 1.0], [nan, nan, nan], [0.5, 9.0, 9.0], [3.0, 2.0, 1.0]]
    status = [["ok"] * 3] * 4 + [["failed", "ok", "ok"]] + [["ok"] * 3]
    fell = [[False] * 3] * 5 + [[False, False, True]]
    table, notes = ps.p_best_table(_outcomes(times, status=status, fell=fell), [635.0], [300.0, 400.0, 500.0],
                                   {635.0: 400.0})
    assert list(table.columns) == ps.P_BEST_COLUMNS
    s = table[table["criterion"] == "settling"]
    s = s.set_index(s["pressure_kpa"].fillna(-1))
    assert s.loc[300.0, "p"] == pytest.approx(0.5 / 5) and s.loc[400.0, "p"] == pytest.approx(3 / 5)
    assert s.loc[500.0, "p"] == pytest.approx(0.5 / 5) and s.loc[-1, "p"] == pytest.approx(1 / 5)
    assert (s["rows"] == 5).all() and (s["rows_failed"] == 1).all()
    assert s.loc[400.0, "measured_best"] and not s.loc[300.0, "measured_best"]
    assert (s["low"] <= s["p"]).all() and (s["p"] <= s["high"]).all()
    assert table.groupby(["fz_n", "criterion"])["p"].sum().to_numpy() == pytest.approx([1.0, 1.0])
    assert notes[0] == "635 N: 1 of 6 rows left out (a run failed)"
    assert notes[1].startswith("635 N, settling: 5 of 18 runs without a value (1 fell")


@pytest.mark.parametrize("make, message", [
    (lambda d: d / "nowhere", "no such folder"),
    (lambda d: d, "no posterior.csv in it"),
    (lambda d: (d / "posterior.csv").write_text("gain_scale\n") and d, "posterior.csv has no rows"),
    (lambda d: (d / "posterior.csv").write_text("gain_scale\n1.0\n") and (d / "settings.json").write_text("{")
     and d, "settings.json is not calibrate's"),
])
def test_bad_calibration_folder_is_a_one_line_error(tmp_path, make, message):
    folder = make(tmp_path)
    if (tmp_path / "posterior.csv").exists() and not (tmp_path / "settings.json").exists():
        (tmp_path / "settings.json").write_text(json.dumps({"format": cal.SETTINGS_FORMAT,
                                                            "fields": {"gain_scale": "gain_scale"},
                                                            "choices": {}}))
    with pytest.raises(InputError, match=message) as info:
        ps.run(folder, samples=2)
    assert "\n" not in str(info.value)


def test_rows_are_paired_and_shares_sum_to_one(calibrated, tmp_path):
    """Real runs (2 posterior rows x 2 pressures x 2 loads): every row has the same inputs at every pressure
    and load (the sampled speed and load share too), the calibrated fields are the posterior's, the choices
    the calibration's; the shares sum to 1 per load and criterion; a rerun resumes (no new runs)."""
    runs = tmp_path / "runs"
    study = ps.run(calibrated, samples=2, seed=1, loads=[570.0, 701.0], pressures=[300.0, 500.0], runs=runs,
                   workers=1)
    table = pd.read_csv(runs / "table.csv")
    merged = study.outcomes.merge(table, on="case_id", suffixes=("", "_run"))
    inputs = ["gain_scale", "carcass_stiffness_scale", "speed", "rear_load_share", "rider_body", "kick_direction"]
    for _, part in merged.groupby("row"):
        assert len(part) == 4 and len(part[inputs].drop_duplicates()) == 1
    posterior = pd.read_csv(calibrated / "posterior.csv")
    for _, r in study.rows.iterrows():
        assert r["gain_scale"] == posterior["gain_scale"].iloc[int(r["posterior_index"])]
    assert set(merged["rider_body"]) == {"rigid"} and set(merged["kick_direction"]) == {"right"}
    assert study.rows["speed"].between(1.92, 2.0).all() and study.rows["speed"].nunique() == 2
    sums = study.p_best.groupby(["fz_n", "criterion"])["p"].sum()
    assert len(sums) == 4 and sums.to_numpy() == pytest.approx(1.0)
    class NoRuns:   # an executor that refuses work: the rerun must find every case in the folder
        def submit(self, *args, **kwargs):
            raise AssertionError("a resumed study ran a case again")

    again = ps.run(calibrated, samples=2, seed=1, loads=[570.0, 701.0], pressures=[300.0, 500.0], runs=runs,
                   executor=NoRuns())
    pd.testing.assert_frame_equal(again.p_best, study.p_best)
    paths = {p.name for p in study.write(tmp_path)}
    assert set(ps.FILES) <= paths
