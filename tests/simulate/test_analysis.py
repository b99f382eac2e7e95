"""Kick-response metrics on synthetic signals with exact answers.

The reference signal is the free response of a linear damped oscillator
started by the kick at t = 0:

    x(t) = exp(-sigma t) sin(wd t),  sigma = zeta wn,  wd = wn sqrt(1 - zeta^2)

Its extrema are at t1 + k pi / wd with tan(wd t1) = wd / sigma, successive
extrema alternate in sign and shrink by exp(-sigma pi / wd), so between peaks
#k and #k+2 the logarithmic decrement (eq. 8.2, n = 1) is exactly
2 pi zeta / sqrt(1 - zeta^2), eq. 8.3 returns exactly zeta, and the period is
2 pi / wd.
"""
import math

import numpy as np
import pandas as pd
import pytest

from whipple_kick.errors import InputError
from whipple_kick.simulate import analysis as an

ZETA, FN = 0.07, 5.5  # like the thesis' yaw rate: lightly damped, ~5.5 Hz
WN = 2 * math.pi * FN
WD = WN * math.sqrt(1 - ZETA ** 2)
SIGMA = ZETA * WN
T1 = math.atan(WD / SIGMA) / WD
DELTA = 2 * math.pi * ZETA / math.sqrt(1 - ZETA ** 2)
PERIOD = 2 * math.pi / WD
# Peak k (1-based) has magnitude |x(T1)| exp(-(k-1) DELTA/2). With 8 % of the
# first one as the limit, peaks 1..12 pass (#12: 8.85 %) and #13 fails
# (7.09 %), margins of about 10 % either side of the threshold.
N_EXPECTED = 12


def damped(t, t_kick=0.0, amplitude=1.0):
    tau = np.clip(t - t_kick, 0.0, None)
    return np.where(t >= t_kick, amplitude * np.exp(-SIGMA * tau) * np.sin(WD * tau), 0.0)


def exact_peaks(n, t_kick=0.0, amplitude=1.0):
    times = t_kick + T1 + np.arange(n) * math.pi / WD
    return times, damped(times, t_kick, amplitude)


def test_exact_count_follows_from_the_8_percent_rule():
    ratios = np.exp(-np.arange(14) * DELTA / 2)
    assert np.count_nonzero(ratios >= 0.08) == N_EXPECTED
    assert ratios[N_EXPECTED - 1] > 0.085 and ratios[N_EXPECTED] < 0.075


def test_damped_sine_peaks_times_and_values():
    # 1 kHz, kick at 0.2 s after a quiet lead-in. The three-point parabola's
    # error on this smooth signal is ~1e-6 s and ~1e-6 relative; the
    # tolerances allow 10x that, still 100x below the 1 ms sample interval.
    t = np.arange(-0.3, 3.0, 1e-3)
    p = an.yaw_rate_peaks(t, damped(t, 0.2), t_kick=0.2)
    times, values = exact_peaks(N_EXPECTED, 0.2)
    assert len(p) == N_EXPECTED
    assert p.stop_reason == "below_threshold"
    np.testing.assert_allclose(p.times, times, rtol=0, atol=1e-5)
    np.testing.assert_allclose(p.values, values, rtol=1e-5)
    assert np.all(np.sign(p.values[1:]) == -np.sign(p.values[:-1]))
    # indices point at the sample nearest each peak
    np.testing.assert_allclose(t[p.indices], times, atol=0.5e-3 + 1e-12)
    assert an.last_peak_time(p) == pytest.approx(times[-1] - 0.2, abs=1e-5)


@pytest.mark.parametrize("pair", an.PEAK_PAIRS)
def test_log_decrement_damping_ratio_period_exact(pair):
    # Relative errors of the refined peaks (~1e-6) give these tolerances.
    t = np.arange(0.0, 3.0, 1e-3)
    m = an.peak_pair_metrics(an.yaw_rate_peaks(t, damped(t)), *pair)
    assert m["log_decrement"] == pytest.approx(DELTA, rel=1e-4)
    assert m["damping_ratio"] == pytest.approx(ZETA, rel=1e-4)
    assert m["period"] == pytest.approx(PERIOD, abs=1e-5)


def test_thesis_sampling_rate_is_refined_below_the_sample_interval():
    # At the thesis' 100 Hz a peak time rounded to the sample would be up to
    # 5 ms off; parabolic refinement measured ~0.1 ms, asserted at 0.5 ms.
    t = np.arange(0.0, 3.0, 0.01)
    p = an.yaw_rate_peaks(t, damped(t))
    times, _ = exact_peaks(len(p))
    assert len(p) == N_EXPECTED
    np.testing.assert_allclose(p.times, times, atol=0.5e-3)
    m = an.peak_pair_metrics(p, 1, 3)
    assert m["log_decrement"] == pytest.approx(DELTA, rel=5e-3)
    assert m["period"] == pytest.approx(PERIOD, abs=0.5e-3)


def test_non_uniform_sampling():
    # Intervals drawn from 0.5-1.5 ms; the parabola is fitted on the real
    # time axis, so accuracy matches the uniform 1 kHz case (10x margin).
    rng = np.random.default_rng(1)
    t = np.concatenate(([0.0], np.cumsum(rng.uniform(0.5e-3, 1.5e-3, 3000))))
    p = an.yaw_rate_peaks(t, damped(t))
    times, values = exact_peaks(N_EXPECTED)
    assert len(p) == N_EXPECTED
    np.testing.assert_allclose(p.times, times, atol=2e-5)
    np.testing.assert_allclose(p.values, values, rtol=2e-5)


def lobes(amplitudes, width=0.1, fs=1000.0):
    """Half-sine lobes of the given signed amplitudes, back to back, after 0.1 s of zeros."""
    t = np.arange(0.0, 0.1 + width * (len(amplitudes) + 3), 1 / fs)
    x = np.zeros_like(t)
    for k, amp in enumerate(amplitudes):
        start = 0.1 + k * width
        inside = (t >= start) & (t < start + width)
        x[inside] = amp * np.sin(math.pi * (t[inside] - start) / width)
    centres = 0.1 + width * (np.arange(len(amplitudes)) + 0.5)
    return t, x, centres


def test_stops_at_first_peak_below_threshold_even_if_a_larger_one_follows():
    amps = [1.0, -0.5, 0.2, -0.081, 0.079, -0.3]
    t, x, centres = lobes(amps)
    p = an.yaw_rate_peaks(t, x)
    assert p.stop_reason == "below_threshold"
    np.testing.assert_allclose(p.values, amps[:4], rtol=1e-5)
    np.testing.assert_allclose(p.times, centres[:4], atol=1e-5)
    assert p.largest == pytest.approx(1.0, rel=1e-5)


def test_threshold_is_relative_to_the_largest_peak_and_skips_leading_ripple():
    # A 5 % ripple before the main response is not peak #1; a first peak
    # smaller than the largest one still is.
    t, x, centres = lobes([0.05, -0.6, 1.0, -0.5, 0.2])
    p = an.yaw_rate_peaks(t, x)
    np.testing.assert_allclose(p.values, [-0.6, 1.0, -0.5, 0.2], rtol=1e-5)
    assert p.stop_reason == "decayed"  # nothing after the last lobe, 0.3 s of zeros
    t, x, _ = lobes([1.0, -0.5, 0.2])
    assert len(an.yaw_rate_peaks(t, x, threshold=0.3)) == 2


def test_noise_does_not_create_peaks():
    # White noise of 0.2 % of the first peak's size (peaks ~ +/-0.7 %) stays
    # inside the default 4 % hysteresis band. Tolerances from 200 seeds: max
    # errors 0.0037 (decrement) and 0.43 ms (period) with a 21-point parabola;
    # asserted at 0.01 and 1 ms.
    t = np.arange(0.0, 3.0, 1e-3)
    y = damped(t) + 0.002 * np.random.default_rng(7).standard_normal(t.size)
    p = an.yaw_rate_peaks(t, y, refine_points=21)
    assert len(p) == N_EXPECTED
    assert np.all(np.sign(p.values[1:]) == -np.sign(p.values[:-1]))
    m = an.peak_pair_metrics(p, 1, 3)
    assert m["log_decrement"] == pytest.approx(DELTA, abs=0.01)
    assert m["period"] == pytest.approx(PERIOD, abs=1e-3)


def test_noisy_measurement_with_thesis_20hz_lowpass():
    # 1 % noise, filtered at 20 Hz as in the thesis. Over 200 seeds: always 12
    # peaks, max errors 0.021 (decrement) and 0.92 ms (period); asserted at
    # 0.03 and 2 ms.
    t = np.arange(-0.5, 3.0, 1e-3)
    y = damped(t) + 0.01 * np.random.default_rng(3).standard_normal(t.size)
    m = an.kick_metrics({"time": t, "yaw_rate": y}, lowpass_hz=20.0)
    assert m["n_peaks"] == N_EXPECTED
    assert m["log_decrement_1_3"] == pytest.approx(DELTA, abs=0.03)
    assert m["period"] == pytest.approx(PERIOD, abs=2e-3)


def test_pre_kick_baseline_removes_a_bias():
    t = np.arange(-0.5, 3.0, 1e-3)
    biased = damped(t) + 0.3
    p = an.yaw_rate_peaks(t, biased, baseline="pre_kick")
    times, values = exact_peaks(N_EXPECTED)
    assert len(p) == N_EXPECTED
    np.testing.assert_allclose(p.times, times, atol=1e-5)
    np.testing.assert_allclose(p.values, values, rtol=1e-5)


def test_no_oscillation_gives_one_peak_and_explicit_reasons():
    # A single overdamped lobe: one peak, last-peak time defined, no decrement.
    t = np.arange(-0.2, 3.0, 1e-3)
    tau = np.clip(t, 0, None)
    x = tau * np.exp(-tau / 0.1)
    m = an.kick_metrics({"time": t, "yaw_rate": x})
    assert m["n_peaks"] == 1 and m["peak_stop_reason"] == "decayed"
    assert m["last_peak_time"] == pytest.approx(0.1, abs=1e-5)  # peak of tau exp(-tau/0.1)
    for key in ("log_decrement_1_3", "damping_ratio_2_4", "period_3_5", "period"):
        assert m[key] is None
        assert "only 1 peaks" in m["unavailable"][key]


def test_flat_signal_reports_no_peaks_and_no_nan():
    t = np.linspace(0.0, 1.0, 101)
    m = an.kick_metrics({"time": t, "yaw_rate": np.zeros_like(t)})
    assert m["n_peaks"] == 0 and m["peak_stop_reason"] == "no_peaks"
    assert m["last_peak_time"] is None and "no yaw-rate peak" in m["unavailable"]["last_peak_time"]
    scalars = [v for k, v in m.items() if isinstance(v, float)]
    assert all(math.isfinite(v) for v in scalars)


def test_too_few_peaks_for_later_pairs():
    t, x, _ = lobes([1.0, -0.6, 0.3, -0.05])
    m = an.kick_metrics({"time": t, "yaw_rate": x})
    assert m["n_peaks"] == 3
    assert m["log_decrement_1_3"] == pytest.approx(math.log(1 / 0.3), rel=1e-5)
    assert m["log_decrement_2_4"] is None and "peak #4 not found" in m["unavailable"]["log_decrement_2_4"]


def test_quiet_tail_shorter_than_a_period_is_not_trusted():
    # Last peak at 0.35 s, peak spacing 0.1 s: a tail of 0.35 s counts as
    # decayed, one of 0.15 s (< one period, 0.2 s) might hide another peak.
    t, x, centres = lobes([1.0, -0.5, 0.2])
    assert an.yaw_rate_peaks(t, x).stop_reason == "decayed"
    short = t <= centres[-1] + 0.15
    p = an.yaw_rate_peaks(t[short], x[short])
    assert len(p) == 3 and p.stop_reason == "end_of_record"


def test_record_ending_mid_oscillation_has_no_last_peak_time():
    t = np.arange(0.0, 1.0, 1e-3)
    p = an.yaw_rate_peaks(t, np.sin(2 * math.pi * 5.3 * t))
    assert p.stop_reason == "end_of_record"
    with pytest.raises(an.MetricUnavailable, match="record ends"):
        an.last_peak_time(p)


def test_log_decrement_and_damping_ratio_formulas():
    assert an.log_decrement(2.0, -0.5, 1) == pytest.approx(math.log(4))  # magnitudes
    assert an.log_decrement(1.0, 0.25, 2) == pytest.approx(math.log(4) / 2)
    # Table 8.6, 300 kPa, to the table's two decimals (half a unit in the last place):
    assert an.damping_ratio(0.46) == pytest.approx(0.07, abs=0.005)
    assert an.damping_ratio(3.49) == pytest.approx(0.49, abs=0.005)
    with pytest.raises(InputError):
        an.log_decrement(1.0, 0.0)


def test_spectrum_of_bin_centred_sinusoids_is_exact():
    # 2 s at 200 Hz: bins every 0.5 Hz, Nyquist 100 Hz. Exact to rounding
    # (1e-12) for both windows: the periodic Hann window has no leakage
    # further than one bin, and the sum(w) scaling keeps bin-centred amplitudes.
    fs, n = 200.0, 400
    t = np.arange(n) / fs
    x = 0.3 + 1.0 * np.sin(2 * math.pi * 5.0 * t) + 0.25 * np.cos(2 * math.pi * 12.5 * t + 0.3)
    expected = {0.0: 0.3, 5.0: 1.0, 12.5: 0.25}
    for window in ("boxcar", "hann"):
        f, a = an.amplitude_spectrum(t, x, window=window)
        assert f[-1] == 25.0 and f[1] - f[0] == 0.5
        for freq, amp in expected.items():
            assert a[f == freq][0] == pytest.approx(amp, abs=1e-12)
        if window == "boxcar":
            others = ~np.isin(f, list(expected))
            assert np.max(a[others]) < 1e-12
    f, a = an.amplitude_spectrum(t, 0.7 * np.cos(math.pi * fs * t), f_max=1000.0)
    assert f[-1] == 100.0 and a[-1] == pytest.approx(0.7, abs=1e-12)  # Nyquist not doubled


def test_spectrum_of_non_uniform_samples():
    # Resampled linearly at the median interval: the error is the linear
    # interpolation's, about (w h)^2 / 8 = 0.3 % at 5 Hz with 5 ms samples.
    rng = np.random.default_rng(2)
    t = np.sort(np.concatenate(([0.0, 2.0], rng.uniform(0.0, 2.0, 398))))
    f, a = an.amplitude_spectrum(t, np.sin(2 * math.pi * 5.0 * t))
    assert a[np.argmin(np.abs(f - 5.0))] == pytest.approx(1.0, abs=0.02)


def test_kick_metrics_on_a_full_run():
    t = np.arange(-0.5, 3.0, 1e-3)
    tau = np.clip(t, 0, None)
    roll = np.where(t >= 0, 0.05 * np.sin(3 * tau) + 0.4 * tau, 0.0)  # passes 45 deg
    data = {"time": t, "yaw_rate": damped(t), "roll": roll, "roll_rate": np.gradient(roll, t),
            "steer": -2 * roll, "fy_rear": 300 * damped(t)}
    m = an.kick_metrics(data)
    from_frame = an.kick_metrics(pd.DataFrame(data), include_spectra=False)
    assert {k: v for k, v in m.items() if k != "spectra"} == from_frame
    assert m["n_peaks"] == N_EXPECTED
    assert m["damping_ratio_1_3"] == pytest.approx(ZETA, rel=1e-4)
    assert m["max_abs_steer"] == pytest.approx(2 * np.max(np.abs(roll)))
    # Maxima are over the samples (not refined): exactly the largest sample,
    # which lies below the true peak by at most (w dt / 2)^2 / 2 = 1.5e-4 relative.
    assert m["max_abs_fy_rear"] == np.max(np.abs(data["fy_rear"]))
    assert m["max_abs_fy_rear"] == pytest.approx(300 * abs(exact_peaks(1)[1][0]), rel=1.5e-4)
    assert m["max_abs_fy_front"] is None and "fy_front" in m["unavailable"]["max_abs_fy_front"]
    assert m["fell"] is True
    crossing = t[np.argmax(np.abs(roll) > math.pi / 4)]
    assert crossing - 1e-3 <= m["fall_time"] <= crossing
    assert set(m["spectra"]) == {"yaw_rate", "roll_rate"}
    f, a = m["spectra"]["yaw_rate"]
    assert f[-1] <= 25.0 and abs(f[np.argmax(a)] - FN) <= 1.0  # 1 s window: 1 Hz bins
    for key, value in m.items():
        assert key in an.METRIC_UNITS or key in ("unavailable", "spectra")
        if isinstance(value, float):
            assert math.isfinite(value)


def test_no_roll_column_means_fall_unknown():
    t = np.arange(0.0, 2.0, 1e-3)
    m = an.kick_metrics({"time": t, "yaw_rate": damped(t)}, include_spectra=False)
    assert m["fell"] is None and "roll" in m["unavailable"]["fell"]
    assert "spectra" not in m


def test_load_measurement_csv(tmp_path):
    t = np.arange(0.0, 2.0, 0.01)
    path = tmp_path / "imu.csv"
    pd.DataFrame({"t_s": t, "gyro_z_deg": np.degrees(damped(t))}).to_csv(path, index=False)
    df = an.load_measurement_csv(path, rename={"t_s": "time", "gyro_z_deg": "yaw_rate"},
                                 scale={"yaw_rate": math.pi / 180})
    np.testing.assert_allclose(df["yaw_rate"], damped(t), atol=1e-12)
    assert an.kick_metrics(df)["n_peaks"] == N_EXPECTED


@pytest.mark.parametrize("text, message", [
    ("time,roll\n0,1\n1,2\n", "lacks column"),
    ("time,yaw_rate\n0,1\n1,abc\n", "non-numeric"),
    ("time,yaw_rate\n0,1\n0,2\n", "strictly increasing"),
    ("time,yaw_rate\n0,1\n1\n2,3,4,5\n", "not a delimited table"),
    ("", "not a delimited table"),
])
def test_load_measurement_csv_errors(tmp_path, text, message):
    path = tmp_path / "bad.csv"
    path.write_text(text)
    with pytest.raises(InputError, match=message):
        an.load_measurement_csv(path)


def test_missing_file(tmp_path):
    with pytest.raises(InputError, match="does not exist"):
        an.load_measurement_csv(tmp_path / "nope.csv")


@pytest.mark.parametrize("kwargs, message", [
    ({"t_kick": 5.0}, "outside the record"),
    ({"threshold": 0.0}, "threshold"),
    ({"threshold": 1.5}, "threshold"),
    ({"refine_points": 4}, "odd integer"),
    ({"baseline": "mean"}, "pre_kick"),
])
def test_bad_arguments(kwargs, message):
    t = np.arange(0.0, 1.0, 1e-3)
    with pytest.raises(InputError, match=message):
        an.yaw_rate_peaks(t, damped(t), **kwargs)


def test_lowpass_needs_uniform_sampling_and_resample_provides_it():
    rng = np.random.default_rng(4)
    t = np.cumsum(rng.uniform(0.5e-3, 1.5e-3, 2000))
    with pytest.raises(InputError, match="uniform"):
        an.lowpass(t, damped(t))
    tu, xu = an.resample_uniform(t, damped(t))
    assert np.ptp(np.diff(tu)) < 1e-9 and tu[0] == t[0] and tu[-1] <= t[-1]
    # 5.5 Hz passes a 20 Hz 4th-order Butterworth applied twice with gain
    # |H|^2 = 1 / (1 + (5.5/20)^8) = 1 - 3.3e-5 (the damped sine's spectrum is
    # broader, hence 1e-3), away from the ends where filtfilt's padding
    # transients live.
    inner = (tu > tu[0] + 0.3) & (tu < tu[-1] - 0.3)
    assert np.max(np.abs(an.lowpass(tu, xu) - xu)[inner]) < 1e-3
    with pytest.raises(InputError, match="cutoff_hz"):
        an.lowpass(tu, xu, cutoff_hz=600.0)


def test_bad_series():
    t = np.arange(0.0, 1.0, 1e-3)
    x = damped(t)
    x[10] = np.nan
    with pytest.raises(InputError, match="NaN"):
        an.yaw_rate_peaks(t, x)
    with pytest.raises(InputError, match="strictly increasing"):
        an.yaw_rate_peaks(t[::-1], damped(t))
    with pytest.raises(InputError, match="'yaw_rate'"):
        an.kick_metrics({"time": t})


# --------------------------------------------------------------- settling and recovery

def _exact_settling(t_kick, fraction=0.05):
    """Settling time of ``damped`` from the continuous signal: where the last lobe whose peak
    exceeds ``fraction`` of the first falls through the band (Brent's method on the formula)."""
    from scipy.optimize import brentq
    times, values = exact_peaks(40, t_kick)
    band = fraction * abs(values[0])
    k = np.flatnonzero(np.abs(values) > band)[-1]
    zero = t_kick + (k + 1) * math.pi / WD          # the zero crossing after peak k
    return brentq(lambda s: abs(damped(np.array([s]), t_kick)[0]) - band, times[k], zero - 1e-12) - t_kick


@pytest.mark.parametrize("t_kick", [0.0, 0.2137])
def test_settling_time_of_a_damped_sine_against_the_continuous_signal(t_kick):
    # Sampled at 1 kHz, the settling time is the first sample after the continuous crossing:
    # within one sample interval (1 ms) after it.
    t = np.arange(-0.3, 4.0, 1e-3)
    s = an.settling_time(t, damped(t, t_kick), t_kick)
    exact = _exact_settling(t_kick)
    assert s.reason is None
    assert s.first_peak == pytest.approx(abs(exact_peaks(1, t_kick)[1][0]), rel=1e-5)
    assert 0.0 <= s.time - exact <= 1e-3 + 1e-9


def test_settling_time_uses_the_baseline_and_the_first_large_peak():
    # A small ripple (30 % of the main lobe) first: the first peak is the main lobe's
    # (the first reaching half the largest), so the band is 5 % of 1.0, not of 0.3.
    t, x, centres = lobes([0.3, -1.0, 0.5, -0.2, 0.04, -0.01])
    s = an.settling_time(t, x + 2.0, baseline=2.0)
    assert s.first_peak == pytest.approx(1.0, rel=1e-5)
    # Lobe 4 (0.2) is the last above 0.05: it drops below the band 0.05 at
    # sin(pi tau / 0.1) = 0.25 on its falling side.
    lobe4_end = centres[3] + 0.05
    expected = lobe4_end - math.asin(0.25) * 0.1 / math.pi
    assert s.time == pytest.approx(expected, abs=1e-3)


def test_signal_that_never_settles_or_never_moves():
    t = np.arange(0.0, 2.25, 1e-3)      # ends at a trough of the undamped sine
    s = an.settling_time(t, np.sin(2 * math.pi * t), label="roll rate")
    assert s.time is None and "roll rate still outside 5% of its first peak at the end" in s.reason
    flat = an.settling_time(t, np.zeros_like(t), label="steer rate")
    assert flat.time is None and flat.first_peak is None and "no steer rate peak" in flat.reason


def test_recovery_is_the_latest_of_yaw_roll_and_steer_settling():
    t = np.arange(-0.2, 4.0, 1e-3)
    yaw, roll = damped(t), 0.5 * damped(t)
    steer = np.where(t > 0, np.exp(-8 * np.clip(t, 0, None)) * np.sin(30 * t), 0.0)   # settles first
    rec = an.recovery({"time": t, "yaw_rate": yaw, "roll_rate": roll, "steer_rate": steer}, 0.0,
                      {"yaw_rate": 0.0})
    sig = rec["signals"]
    assert sig["yaw_rate"]["time_s"] == sig["roll_rate"]["time_s"] == rec["time_s"]   # same shape, same time
    assert sig["steer_rate"]["time_s"] < rec["time_s"] and rec["last_to_settle"] == "yaw_rate"
    assert rec["time_s"] == pytest.approx(_exact_settling(0.0), abs=1e-3)
    # A record that cannot show a recovery (a fall) keeps the peaks but no times.
    fell = an.recovery({"time": t, "yaw_rate": yaw, "roll_rate": roll, "steer_rate": steer}, ended="fell")
    assert fell["time_s"] is None and fell["reason"] == "fell"
    assert all(v["time_s"] is None and v["first_peak_rad_s"] > 0 for v in fell["signals"].values())
    with pytest.raises(InputError, match="'steer_rate'"):
        an.recovery({"time": t, "yaw_rate": yaw, "roll_rate": roll})


def test_the_peak_parabola_is_polyfit_bit_for_bit():
    """The refinement's own least-squares parabola gives numpy.polyfit's coefficients exactly (same matrix, same
    solve), on 3 and on more samples, and warns as polyfit does where the samples cannot fix a parabola."""
    rng = np.random.default_rng(7)
    for n in (3, 3, 3, 5, 7, 21):
        x = np.sort(rng.normal(size=n)) * 10.0 ** rng.integers(-4, 2)
        x -= x[n // 2]   # centred, as the refinement fits them (an exact 0.0 in the middle)
        y = rng.normal(size=n) * 10.0 ** rng.integers(-3, 3)
        assert an._parabola(x, y).tobytes() == np.polyfit(x, y, 2).tobytes()
    same = np.array([-1.0, -1.0, 1.0])   # two distinct samples: rank 2
    rank_warning = getattr(np, "exceptions", np).RankWarning
    with pytest.warns(rank_warning, match="Polyfit may be poorly conditioned"):
        fitted = an._parabola(same, np.array([1.0, 2.0, 3.0]))
    with pytest.warns(rank_warning):
        assert fitted.tobytes() == np.polyfit(same, np.array([1.0, 2.0, 3.0]), 2).tobytes()


def test_several_signals_of_one_record_are_checked_as_each_alone():
    """kick_metrics and recovery check the shared time once, and each signal as _as_series would."""
    t = np.arange(0.0, 2.0, 1e-3)
    x = damped(t)
    bad = x.copy()
    bad[[5, 9]] = np.nan
    with pytest.raises(InputError, match="roll rate has 2 NaN/inf values"):
        an.recovery({"time": t, "yaw_rate": x, "roll_rate": bad, "steer_rate": x})
    with pytest.raises(InputError, match=r"time and steer rate must be 1-D arrays of equal length"):
        an.recovery({"time": t, "yaw_rate": x, "roll_rate": x, "steer_rate": x[:-1]})
    with pytest.raises(InputError, match="roll has 2 NaN/inf values"):
        an.kick_metrics({"time": t, "yaw_rate": x, "roll": bad})
    late = t.copy()
    late[3] = late[2]
    with pytest.raises(InputError, match="time must be strictly increasing"):
        an.kick_metrics({"time": late, "yaw_rate": x})


def _forward_filled_lobes(x, band):
    """The half-waves by the definition: the sign (+1 above the band, -1 below, 0 in it) forward-filled over the
    samples in the band, split where it changes; the samples before the band is first left are in none."""
    raw = np.where(x > band, 1, np.where(x < -band, -1, 0))
    last = np.where(raw != 0, np.arange(x.size), 0)
    state = raw[np.maximum.accumulate(last)]
    edges = np.flatnonzero(np.diff(state)) + 1
    starts, stops = np.concatenate(([0], edges)), np.concatenate((edges, [x.size]))
    return [(int(a), int(b), int(state[a])) for a, b in zip(starts, stops, strict=True) if state[a] != 0]


def test_half_waves_are_the_forward_filled_sign():
    rng = np.random.default_rng(3)
    for trial in range(2000):
        n = int(rng.integers(1, 50))
        x = rng.normal(size=n) * rng.choice([0.1, 1.0, 10.0])
        if trial % 3 == 0:
            x[:rng.integers(0, n)] = 0.0   # a start inside the band
        band = float(abs(rng.normal())) * rng.choice([0.0, 0.5, 1.0])
        if trial % 7 == 0:
            x[rng.integers(0, n)] = band   # on the band's edge: inside it
        lobes = an._lobes(x, band)
        assert [(int(a), int(b), s) for a, b, s in lobes] == _forward_filled_lobes(x, band), (x, band)
        assert all(type(s) is int for _, _, s in lobes)
