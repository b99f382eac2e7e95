"""The validation harness: the recordings' processing chain on signals of known answer, and the nine cases run."""
import json
import math

import numpy as np
import pandas as pd
import pytest

import whipple_kick as wk
from whipple_kick.errors import InputError
from whipple_kick.library import experiments
from whipple_kick.simulate import analysis
from whipple_kick.studies import recommend, validation

F_HZ, DECAY = 5.0, 1.5        # a damped 5 Hz sine: period 0.2 s, log decrement DECAY * 0.2 = 0.3 per period
OMEGA = 2 * math.pi * F_HZ


def damped(t, f_hz=F_HZ, decay=DECAY):
    """exp(-decay t) sin(2 pi f t), smooth through the kick at t = 0 (no onset for the filter to smear)."""
    return np.exp(-decay * t) * np.sin(2 * math.pi * f_hz * t)


@pytest.fixture(scope="module")
def synthetic():
    t = np.arange(-0.5, 3.0, 1e-3)     # a fine 'simulation' clock, as the model's 1 kHz output
    return t, validation.recorded_metrics(t, damped(t))


def test_damped_sine_gives_its_period_and_log_decrement(synthetic):
    """Period 0.2 s and delta = decay x period = 0.3, exactly, for every peak pair.

    A damped sine's same-sign extrema are exactly one period apart and in the
    ratio exp(decay T). Tolerances: 1 ms on the period (three-point parabola
    through 100 Hz samples of a 5 Hz sine: bias below 0.3 ms), 0.005 on delta
    (the zero-phase 20 Hz filter scales every peak alike, by 1 - 2e-5 at 5 Hz).
    """
    _, m = synthetic
    assert m["period_s"] == pytest.approx(0.2, abs=1e-3)
    for key in ("log_dec_13", "log_dec_24", "log_dec_35"):
        assert m[key] == pytest.approx(DECAY * 0.2, abs=5e-3), key
    assert analysis.damping_ratio(m["log_dec_13"]) == pytest.approx(0.3 / math.sqrt(4 * math.pi ** 2 + 0.09), abs=1e-3)


def test_the_8_percent_rule_counts_the_known_peaks(synthetic):
    """|peak k| / |peak 1| = exp(-decay (k-1) T/2): peaks 1..17 are above 8 % (k-1 <= ln(12.5)/0.15 = 16.8)."""
    _, m = synthetic
    expected = math.floor(math.log(1 / 0.08) / (DECAY * 0.1)) + 1
    assert expected == 17 and m["n_peaks"] == expected
    # Peak #1 of sin is at t = atan(omega/decay)/omega; from it the last peak is (n-1) half-periods on.
    t1 = math.atan(OMEGA / DECAY) / OMEGA
    assert m["last_peak_from_kick_s"] == pytest.approx(t1 + 16 * 0.1, abs=1e-3)
    assert m["last_peak_time_s"] == pytest.approx(16 * 0.1, abs=1e-3)     # origin peak #1 (the default)


def test_time_origin_kick_is_measured_from_the_kick():
    t = np.arange(-0.5, 3.0, 1e-3)
    m = validation.recorded_metrics(t, damped(t), time_origin="kick")
    assert m["last_peak_time_s"] == m["last_peak_from_kick_s"]
    with pytest.raises(InputError, match="time origin 'x' is unknown"):
        validation.recorded_metrics(t, damped(t), time_origin="x")


def test_dominant_frequency_and_slow_swing():
    """5 Hz and 7 Hz sines are found on their 1 Hz bins; the slow-swing ratio matches a direct evaluation."""
    t = np.arange(-0.5, 3.0, 1e-3)
    for f in (5.0, 7.0):
        assert validation.recorded_metrics(t, damped(t, f))["dominant_frequency_hz"] == f
    # A slow 0.3 Hz swing of amplitude 0.25 under the decaying 5 Hz oscillation: the ratio is the largest
    # |signal| 0.5-1 s after the kick over peak #1, evaluated here on the exact signal (0.5 % tolerance:
    # the 100 Hz sampling and the filter).
    signal = damped(t) + 0.25 * np.sin(2 * math.pi * 0.3 * t)
    m = validation.recorded_metrics(t, signal)
    fine = np.arange(0.0, 1.0, 1e-5)
    exact = damped(fine) + 0.25 * np.sin(2 * math.pi * 0.3 * fine)
    peak1 = exact[np.argmax(np.abs(exact[fine < 0.1]))]
    window = (fine >= 0.5)
    assert m["slow_swing_ratio"] == pytest.approx(np.max(np.abs(exact[window])) / abs(peak1), rel=5e-3)


def test_a_spectrum_without_a_peak_has_no_dominant_frequency():
    """A decaying pulse's spectrum falls from 0 Hz: no local maximum, reported, never NaN."""
    t = np.arange(-0.5, 3.0, 1e-3)
    pulse = np.where(t > 0, t * np.exp(-t / 0.05), 0.0)
    m = validation.recorded_metrics(t, pulse)
    assert m["dominant_frequency_hz"] is None
    assert "no local maximum" in m["unavailable"]["dominant_frequency_hz"]
    assert m["n_peaks"] == 1 and m["period_s"] is None and "peak #3 not found" in m["unavailable"]["period_s"]


def test_as_recorded_samples_through_the_kick_without_phase_shift():
    t = np.arange(-0.503, 2.0, 1e-3)
    t_rec, x_rec = analysis.as_recorded(t, np.sin(OMEGA * t), t_kick=0.0)
    assert np.allclose(np.diff(t_rec), 0.01) and np.min(np.abs(t_rec)) < 1e-12     # 100 Hz, through t = 0
    inner = (t_rec > -0.3) & (t_rec < 1.8)     # away from the filter's end transients
    # 4th-order Butterworth at 20 Hz, forward and back: gain 1 / (1 + (5/20)^8) = 1 - 1.5e-5 at 5 Hz, no delay.
    assert np.max(np.abs(x_rec[inner] - np.sin(OMEGA * t_rec[inner]))) < 1e-4
    with pytest.raises(InputError, match="recording rate"):
        analysis.as_recorded(t, t, rate_hz=0.0)


def test_steady_turn_is_removed():
    """The model starts in a steady turn: its yaw rate is measured from it, as the recordings from 0."""
    t = np.arange(-0.5, 3.0, 1e-3)
    plain = validation.recorded_metrics(t, damped(t))
    offset = validation.recorded_metrics(t, damped(t) + 0.03, steady=0.03)
    for key in ("n_peaks", "period_s", "log_dec_13", "dominant_frequency_hz", "slow_swing_ratio"):
        assert offset[key] == pytest.approx(plain[key], rel=1e-9, abs=1e-12), key


def test_dependence_says_what_the_answer_depends_on():
    assert recommend.dependence({"kicks to the right": 500.0, "kicks to the left": 300.0}, "direction") == (
        "500 kPa for kicks to the right, 300 kPa for kicks to the left: the answer depends on the direction")
    assert recommend.dependence({"a": 400.0, "b": 400.0}, "tyre transient") == "400 kPa whatever the tyre transient"
    assert recommend.dependence({"a": 400.0, "b": None}, "x").endswith("none for b: the answer depends on the x")
    assert recommend.dependence({"a": None}, "x") == "no pressure recovered in any x"
    with pytest.raises(InputError):
        recommend.dependence({}, "x")


def test_best_by_rule_skips_missing_and_failed_rows():
    rows = [dict(case="c", fz_n=570.0, pressure_kpa=p, direction="right", source="model", status=s,
                 last_peak_time_s=v, recovery_time_s=None)
            for p, v, s in ((300.0, 0.5, "ok"), (400.0, 0.2, "fell"), (500.0, 0.3, "ok"))]
    table = pd.DataFrame(rows)
    assert validation.best_by_rule(table, "last_peak", "right") == {570.0: 500.0}
    assert validation.best_by_rule(table, "settling", "right") == {570.0: None}


@pytest.fixture(scope="module")
def nine_cases(tmp_path_factory):
    result = validation.validate(workers=2)
    out = tmp_path_factory.mktemp("validation")
    files = validation.write(result, out, plot=True)
    return result, out, files


def test_nine_cases_both_directions(nine_cases):
    result, out, files = nine_cases
    table = pd.read_csv(out / "validation.csv", keep_default_na=False)
    assert list(table.columns) == list(validation.CSV_COLUMNS)
    assert len(table) == 27 and (table["source"] == "measured").sum() == 9
    model = table[table["source"] == "model"]
    assert sorted(set(model["direction"])) == ["left", "right"] and set(table[table["source"] == "measured"]["direction"]) == {""}
    # The measured rows are the file's numbers.
    exp = experiments.load()
    for _, r in table[table["source"] == "measured"].iterrows():
        case = exp.cases[r["case"]]
        assert float(r["last_peak_time_s"]) == case.values["last_peak_time"]
        assert float(r["period_s"]) == case.values["period"] and int(r["n_peaks"]) == case.last_peak_number
    # Every model run is in cases/ and the plate moved the way its direction says.
    for name, run in result.runs.items():
        assert (out / "cases" / name / "trajectory.csv").exists()
        plate = run["trajectory"]["plate_y"].to_numpy()
        assert np.sign(plate[-1]) == (1 if name.endswith("_right") else -1)
    assert len(result.runs) == 18
    # A kick to the right and one to the left start the yaw rate off in opposite senses (peak #1).
    for c in exp.cases:
        first = {d: result.runs[f"{c}_{d}"]["recording"] for d in validation.DIRECTIONS}
        signs = set()
        for d, (t, y) in first.items():
            steady = result.runs[f"{c}_{d}"]["steady"]
            peaks = analysis.yaw_rate_peaks(t, y, 0.0, 0.08, baseline=steady)
            signs.add(np.sign(peaks.values[0]))
        assert signs == {-1.0, 1.0}, c
    assert (out / "validation.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert files[:2] == ["validation.csv", "cases/ (18 run folders)"]
    # Each case is a run folder (issue 31 item 20): Result.load gives back the run's summary and trajectory.
    for name, run in result.runs.items():
        loaded = wk.Result.load(out / "cases" / name)
        assert loaded.summary == run["summary"] and list(loaded.trajectory.columns) == list(run["trajectory"].columns)


def test_summary_compares_and_gives_verdicts(nine_cases):
    result, out, _ = nine_cases
    summary = json.loads((out / "summary.json").read_text())
    assert summary["best_pressure"]["measured"] == {"570.0": 300.0, "635.0": 400.0, "701.0": 500.0}
    assert summary["best_pressure"]["table_8_9"] == summary["best_pressure"]["measured"]
    for rule in validation.RULES:
        assert set(summary["best_pressure"][rule]) == {"right", "left"}
        assert summary["verdicts"][rule].count(" N: ") == 3
        for d in validation.DIRECTIONS:
            assert summary["agreement_with_table_8_9"][rule][d].endswith("of 3 loads")
    # The mean |error| recomputed from the table, for one metric.
    t = result.table
    measured = t[t["source"] == "measured"].set_index("case")["period_s"]
    model = t[(t["source"] == "model") & (t["status"] == "ok")]
    errors = [abs(r["period_s"] - measured[r["case"]]) for _, r in model.iterrows() if r["period_s"] is not None
              and np.isfinite(r["period_s"])]
    assert summary["mean_abs_error"]["period_s"]["all"] == pytest.approx(np.mean(errors), rel=1e-12)
    assert summary["mean_abs_error"]["period_s"]["n"] == len(errors)
    assert summary["setup"]["scenario"]["speed"] == 2.0 and summary["setup"]["scenario"]["kick_accel"] == 35.0
    assert summary["setup"]["scenario"]["kick_profile"] == "smooth"


def test_recommend_variants_names_answers_within_the_spread(monkeypatch):
    """The verdict per load across variants, with the best pressures inside the model's spread named."""
    def fake(loads, base=None, **options):
        right = base.kick_direction == "right"
        return [recommend.Recommendation(fz, "T03", 500.0 if right else 300.0, None, "settling", 0.1 if right else 0.5,
                                         0.218, "no clear optimum" if right else "clear", None) for fz in loads]
    monkeypatch.setattr(recommend, "recommend_pressures", fake)
    from whipple_kick.simulate.scenario import Scenario
    variants = {(d, "contact_patch"): Scenario(kick_direction=d) for d in ("right", "left")}
    recs, verdicts = recommend.recommend_variants([570.0], variants)
    assert set(recs) == set(variants)
    assert verdicts == ["570 N, contact_patch transient: 500 kPa for kicks to the right, 300 kPa for kicks to the "
                        "left: the answer depends on the direction (no clear optimum for kicks to the right)"]


def test_the_kick_is_the_measured_one():
    """150 mm on the minimum-jerk profile at a 35 m/s^2 peak lasts T = sqrt(10/sqrt(3) x 0.150 / 35) = 0.157 s.

    The quintic's peak acceleration is 10/sqrt(3) D/T^2 (at t/T = 1/2 -+ sqrt(3)/6); the thesis' kick lasted
    about 0.15 s and the wheel stayed on the plate 0.2-0.22 s (Section 8.5).
    """
    from whipple_kick.library import inputs
    kick = inputs.kick_of(validation.base_scenario().validate())
    assert kick.duration == pytest.approx(math.sqrt(10 / math.sqrt(3) * 0.150 / 35.0), rel=1e-9)
    assert 0.15 < kick.duration < experiments.load().conditions["wheel_on_plate_min"]


def test_with_symmetric_tyres_the_two_directions_mirror():
    """Without the tyres' zero-slip offsets the bicycle is symmetric: a kick to the left mirrors one to the right,
    so every processed metric is the same (to the integration's accuracy; 1e-6 relative, rtol 1e-10)."""
    result = validation.validate(validation.base_scenario(symmetric_tyres=True, duration=2.0), workers=2)
    model = result.table[result.table["source"] == "model"]
    right = model[model["direction"] == "right"].set_index("case")
    left = model[model["direction"] == "left"].set_index("case")
    for column in ("last_peak_time_s", "n_peaks", "period_s", "log_dec_13", "dominant_frequency_hz", "slow_swing_ratio"):
        for case in right.index:
            a, b = right.loc[case, column], left.loc[case, column]
            if a is None or (isinstance(a, float) and math.isnan(a)):
                assert b is None or (isinstance(b, float) and math.isnan(b)), (case, column)
                continue
            assert float(b) == pytest.approx(float(a), rel=1e-6, abs=1e-9), (case, column)
