"""Kick-response metrics of thesis Section 8.3 "Data analysis", on any time series.

The same functions serve simulated trajectories and measured recordings (e.g.
an IMU log read with :func:`load_measurement_csv`), so that the two are
reduced to numbers in exactly the same way. Definitions (see
``docs/analysis.md`` for the reasoning and the thesis' ambiguities):

* **Peaks.** Yaw-rate extrema of alternating sign from the kick onward, one
  per half-wave ("lobe" between zero crossings). Peak #1 is the first one
  whose magnitude reaches ``threshold`` x the largest; detection stops at the
  first later peak whose magnitude is below that (8 % in the thesis).
* **Last-peak time** (the thesis' "recovery time", Tables 8.6-8.8). Time of
  the last such peak *relative to the kick*. Not a recovery time: the
  signal may still be at half its first peak then.
* **Settling time** (:func:`settling_time`). Time after the kick from which
  ``|signal - steady|`` stays within 5 % of the signal's first peak; the
  **recovery time** (:func:`recovery`) is when yaw, roll and steer rates
  have all settled. The one definition of recovery in whipple_kick.
* **Logarithmic decrement** (eq. 8.2) ``delta = (1/n) ln(|U0| / |Un|)``
  between same-sign peaks #k and #(k+2), which are one period apart, so
  ``n = 1``; **damping ratio** (eq. 8.3) ``zeta = delta / sqrt(4 pi^2 + delta^2)``.
* **Period** between the same pair of peaks: ``t(#k+2) - t(#k)``; the
  "period of the signal" is the one between peaks #1 and #3.
* **Amplitude spectrum**: single-sided FFT amplitude up to 25 Hz.

Sampling may be uniform or non-uniform (strictly increasing time). Peak
detection and refinement work on the samples as given; the FFT and the
low-pass filter need a uniform grid and resample non-uniform input linearly
onto one (see :func:`resample_uniform`).

A metric that cannot be computed is never NaN: low-level functions raise
:class:`MetricUnavailable` with the reason, and :func:`kick_metrics` reports
``None`` for the value and the reason under ``"unavailable"``.
"""
from dataclasses import dataclass
import math
import pathlib
import warnings

import numpy as np
import pandas as pd

from whipple_kick.errors import InputError, check_range
from whipple_kick.library.experiments import damping_ratio

#: Column names understood by :func:`kick_metrics`, with their units.
COLUMNS = {
    "time": "s",
    "yaw_rate": "rad/s",
    "roll_rate": "rad/s",
    "roll": "rad",
    "steer": "rad",
    "steer_rate": "rad/s",
    "slip_rear": "rad",
    "fy_rear": "N",
    "fy_front": "N",
}

#: Units of the scalar entries returned by :func:`kick_metrics`.
METRIC_UNITS = {
    "n_peaks": "-",
    "peak_times": "s from kick",
    "peak_values": "rad/s",
    "peak_stop_reason": "-",
    "last_peak_time": "s from kick",
    "log_decrement_1_3": "-", "damping_ratio_1_3": "-", "period_1_3": "s",
    "log_decrement_2_4": "-", "damping_ratio_2_4": "-", "period_2_4": "s",
    "log_decrement_3_5": "-", "damping_ratio_3_5": "-", "period_3_5": "s",
    "period": "s",
    "fell": "-",
    "fall_time": "s from kick",
    **{f"max_abs_{name}": unit for name, unit in COLUMNS.items() if name != "time"},
}

#: Peak pairs of the thesis' Tables 8.6-8.8, as (first, second) peak numbers.
PEAK_PAIRS = ((1, 3), (2, 4), (3, 5))

#: Recovery: ``|signal - steady|`` stays within this fraction of the signal's first peak.
SETTLING_FRACTION = 0.05
#: A signal's first peak is the first extremum of ``|signal - steady|`` after the kick that reaches
#: this fraction of the largest (a smaller lobe before it is a ripple, not the response).
FIRST_PEAK_FRACTION = 0.5
#: Signals that must all have settled for the bicycle to have recovered, with their units.
RECOVERY_SIGNALS = {"yaw_rate": "rad/s", "roll_rate": "rad/s", "steer_rate": "rad/s"}

#: Relative spread of sample intervals below which sampling counts as uniform.
_UNIFORM_RTOL = 1e-3


class MetricUnavailable(Exception):
    """A metric cannot be computed from this signal (e.g. too few peaks).

    Not a user mistake: the data simply do not contain what the metric needs.
    The message says why.
    """


@dataclass(frozen=True)
class PeakSeries:
    """Yaw-rate peaks after a kick, as found by :func:`yaw_rate_peaks`.

    Attributes
    ----------
    times : ndarray
        Refined peak times [s], on the same clock as the input ``t``.
    values : ndarray
        Refined peak values (signal units, baseline removed); signs alternate.
    indices : ndarray of int
        Index into the input arrays of the sample nearest each peak.
    t_kick : float
        Kick time [s] the search started from.
    largest : float
        Largest peak magnitude found after the kick (0 if none).
    threshold : float
        Stopping fraction of ``largest``.
    stop_reason : str
        ``"below_threshold"`` (a later peak fell below the threshold),
        ``"decayed"`` (no further half-wave left the noise band for at least
        one period before the record ended), ``"end_of_record"`` (the record
        ends while the oscillation may still go on) or ``"no_peaks"``.
    """

    times: np.ndarray
    values: np.ndarray
    indices: np.ndarray
    t_kick: float
    largest: float
    threshold: float
    stop_reason: str

    def __len__(self):
        return len(self.times)


# --------------------------------------------------------------------------
# input checks
# --------------------------------------------------------------------------

def _as_series(t, signal, name="signal"):
    """Return float arrays (t, x), checking shape, finiteness and monotonic time."""
    t = np.asarray(t, dtype=float)
    x = np.asarray(signal, dtype=float)
    if t.ndim != 1 or x.shape != t.shape:
        _unequal(t, x, name)
    if t.size < 3:
        raise InputError(f"{name} needs at least 3 samples, got {t.size}")
    _check_finite(t, "time")
    if x is not t:   # a time checked against itself is checked once
        _check_finite(x, name)
    # t[1:] <= t[:-1] is diff(t) <= 0 for finite times, without the differences' array.
    if np.any(t[1:] <= t[:-1]):
        raise InputError("time must be strictly increasing (s); found a repeated or decreasing sample")
    return t, x


def _as_signal(t, signal, name):
    """``_as_series(t, signal, name)[1]`` for a time ``t`` that :func:`_as_series` accepted: only the signal's
    checks are left (several signals of one record share its time)."""
    x = np.asarray(signal, dtype=float)
    if x.shape != t.shape:
        _unequal(t, x, name)
    _check_finite(x, name)
    return x


def _unequal(t, x, name):
    raise InputError(f"time and {name} must be 1-D arrays of equal length, got shapes {t.shape} and {x.shape}")


def _check_finite(values, label):
    """InputError counting the NaN/inf of ``values`` if there are any."""
    if not np.isfinite(values).all():
        bad = np.count_nonzero(~np.isfinite(values))
        raise InputError(f"{label} has {bad} NaN/inf values; drop or interpolate them first")


def _is_uniform(t):
    dt = np.diff(t)
    return np.ptp(dt) <= _UNIFORM_RTOL * np.median(dt)


def resample_uniform(t, signal, dt=None):
    """Linearly interpolate a series onto a uniform grid.

    Parameters
    ----------
    t, signal : array_like
        Strictly increasing time [s] and the signal.
    dt : float, optional
        Grid step [s]; default the median sample interval of ``t``.

    Returns
    -------
    t_u, x_u : ndarray
        Uniform grid starting at ``t[0]`` (not past ``t[-1]``) and the signal on it.
        If ``t`` is already uniform (interval spread <= 0.1 %) and ``dt`` is not
        given, the input is returned unchanged.
    """
    t, x = _as_series(t, signal)
    if dt is None:
        if _is_uniform(t):
            return t, x
        dt = float(np.median(np.diff(t)))
    dt = check_range("resampling step dt", dt, 0.0, None, "s", low_open=True)
    n = int(math.floor((t[-1] - t[0]) / dt * (1 + 1e-12))) + 1
    t_u = t[0] + dt * np.arange(n)
    return t_u, np.interp(t_u, t, x)


# --------------------------------------------------------------------------
# peaks
# --------------------------------------------------------------------------

def _lobes(x, band):
    """Split ``x`` into half-waves with a +/- ``band`` hysteresis on the sign.

    The sign state only flips when the signal goes past the *opposite* band
    edge, so noise chattering around a zero crossing does not create extra
    half-waves. Returns a list of (start, stop, sign) slices; samples before
    the signal first leaves the band belong to no lobe.
    """
    # A half-wave starts at each sample outside the band whose side differs from the previous such sample's
    # (the first such sample starts the first one), and ends where the next starts: the sign forward-filled
    # over the samples in the band, without filling it.
    above, below = x > band, x < -band
    outside = np.flatnonzero(above | below)
    if not outside.size:
        return []
    side = above[outside]   # True above the band, False below it
    starts = outside[np.concatenate(([0], np.flatnonzero(side[1:] != side[:-1]) + 1))]
    stops = np.concatenate((starts[1:], [x.size]))
    return [(a, b, 1 if up else -1) for a, b, up in zip(starts, stops, above[starts], strict=True)]


def _refine(t, x, i, points):
    """Vertex (time, value) of a parabola through the samples around index ``i``.

    Least squares over ``points`` samples centred on ``i`` (3 = exact
    three-point interpolation), in the real time axis so non-uniform sampling
    is handled. The vertex is accepted only if the parabola bends the right
    way and its vertex lies within the fitted samples; otherwise the
    three-point fit, and failing that the sample itself, is used. For the
    three-point fit around a sample maximum the vertex is always within one
    sample, so noise can at worst leave the sample time.
    """
    for half in dict.fromkeys((points // 2, 1)):
        lo, hi = i - half, i + half + 1
        if lo < 0 or hi > x.size:
            continue
        tc = t[lo:hi] - t[i]  # centred for conditioning
        a, b, c = _parabola(tc, x[lo:hi])
        if a * np.sign(x[i]) >= 0:
            continue
        tv = -b / (2 * a)
        if tc[0] <= tv <= tc[-1]:
            return t[i] + tv, c - b * b / (4 * a)
    return t[i], x[i]


def _parabola(x, y):
    """``numpy.polyfit(x, y, 2)`` of 1-D float arrays of at least 3 samples, bit for bit, without its overhead.

    The same scaled Vandermonde matrix, the same least-squares call
    (:func:`numpy.linalg.lstsq`, with polyfit's ``rcond``) and the same
    unscaling, hence the same coefficients; the same warning when the
    matrix is rank-deficient. A sweep case refines ~14 peaks, and polyfit's
    argument handling cost about as much as its solve.
    """
    x = x + 0.0   # as polyfit: no -0.0
    lhs = np.empty((x.size, 3))
    lhs[:, 0] = x * x   # np.vander(x, 3): x**2 as multiply.accumulate makes it, x, 1
    lhs[:, 1] = x
    lhs[:, 2] = 1.0
    scale = np.sqrt((lhs * lhs).sum(axis=0))
    lhs /= scale
    c, _, rank, _ = np.linalg.lstsq(lhs, y + 0.0, x.size * _EPS)
    if rank != 3:
        warnings.warn("Polyfit may be poorly conditioned", _RANK_WARNING, stacklevel=2)
    return c / scale


#: Machine epsilon of float64 (polyfit's ``rcond`` is the number of samples times it).
_EPS = float(np.finfo(float).eps)
#: polyfit's warning class (numpy.exceptions from NumPy 1.25 on).
_RANK_WARNING = getattr(np, "exceptions", np).RankWarning


def yaw_rate_peaks(t, signal, t_kick=0.0, threshold=0.08, *, hysteresis=None,
                   baseline=0.0, refine_points=3):
    """Successive alternating-sign peaks of a yaw-rate signal after a kick.

    Parameters
    ----------
    t, signal : array_like
        Strictly increasing time [s] (uniform or not) and the signal.
    t_kick : float
        Kick time [s]; only samples with ``t >= t_kick`` are searched.
    threshold : float
        Stop at the first peak whose magnitude is below ``threshold`` x the
        largest peak (thesis: 0.08). Leading peaks below it (a ripple before
        the response builds up) are skipped, so #1 is the first peak above it.
    hysteresis : float, optional
        Noise band, as a fraction of the largest ``|signal|`` after the kick,
        that the signal must leave on the opposite side to start a new
        half-wave. Default ``threshold / 2``: noise with peaks below 4 % of the
        largest response creates no spurious peaks, and any half-wave big
        enough to matter for the stopping rule is still seen.
    baseline : float or "pre_kick"
        Value subtracted before the search (signal units); ``"pre_kick"`` uses
        the mean of the samples before ``t_kick`` (e.g. a gyro bias).
    refine_points : int
        Odd number (>= 3) of samples in the least-squares parabola that
        refines each peak's time and value between samples. Raise it for noisy
        data that was not low-pass filtered.

    Returns
    -------
    PeakSeries
    """
    t, x = _as_series(t, signal, "yaw rate")
    return _peaks_of(t, x, t_kick, threshold, hysteresis, baseline, refine_points)


def _peaks_of(t, x, t_kick, threshold, hysteresis, baseline, refine_points):
    """:func:`yaw_rate_peaks` of the float arrays ``t``, ``x`` that :func:`_as_series` accepted."""
    threshold = check_range("threshold", threshold, 0.0, 1.0, "(fraction of largest peak)",
                            low_open=True, high_open=True)
    hysteresis = threshold / 2 if hysteresis is None else check_range(
        "hysteresis", hysteresis, 0.0, threshold, "(fraction of largest |signal|)")
    if isinstance(refine_points, bool) or int(refine_points) != refine_points \
            or refine_points < 3 or refine_points % 2 == 0:
        raise InputError(f"refine_points = {refine_points!r} must be an odd integer >= 3 (samples)")
    t_kick = float(t_kick)
    if not t[0] <= t_kick < t[-1]:
        raise InputError(f"t_kick = {t_kick:g} s is outside the record [{t[0]:g}, {t[-1]:g}) s")
    first = int(np.searchsorted(t, t_kick))
    if isinstance(baseline, str):
        if baseline != "pre_kick":
            raise InputError(f"baseline = {baseline!r} must be a number (signal units) or 'pre_kick'")
        if first == 0:
            raise InputError("baseline 'pre_kick' needs samples before t_kick; the record starts at the kick")
        baseline = float(np.mean(x[:first]))
    tw, xw = t[first:], x[first:] - float(baseline)

    def none_found(reason):
        return PeakSeries(np.empty(0), np.empty(0), np.empty(0, dtype=int), t_kick, 0.0,
                          threshold, reason)

    scale = float(np.max(np.abs(xw)))
    if scale == 0.0:
        return none_found("no_peaks")

    # One candidate per half-wave: the sample of largest magnitude in it. A
    # maximum on the window's first sample is only the signal at the kick and
    # one on the last sample is a half-wave cut by the end of the record:
    # neither is a turning point.
    cand, open_end = [], False
    for a, b, sign in _lobes(xw, hysteresis * scale):
        i = a + int(xw[a:b].argmax() if sign > 0 else xw[a:b].argmin())   # the first of equal extremes, as before
        if i == 0:
            continue
        if i == xw.size - 1:
            open_end = True
            break
        cand.append(_refine(tw, xw, i, int(refine_points)) + (i,))
    if not cand:
        return none_found("end_of_record" if open_end else "no_peaks")

    largest = max(abs(v) for _, v, _ in cand)
    limit = threshold * largest
    start = next(k for k, (_, v, _) in enumerate(cand) if abs(v) >= limit)
    kept, reason = [], None
    for tp, v, i in cand[start:]:
        if abs(v) < limit:
            reason = "below_threshold"
            break
        kept.append((tp, v, i))
    if reason is None:
        if open_end:
            reason = "end_of_record"
        else:
            # No further half-wave left the noise band. Trust that only if the
            # record goes on for a period after the last peak (a period being
            # twice the longest half-wave seen, or twice the kick-to-peak time).
            times = [k[0] for k in kept]
            half = max(np.diff(times), default=times[0] - t_kick)
            reason = "decayed" if tw[-1] - times[-1] >= 2 * half else "end_of_record"
    tp, v, i = (np.array(col) for col in zip(*kept, strict=True))
    return PeakSeries(tp, v, i.astype(int) + first, t_kick, largest, threshold, reason)


def last_peak_time(peaks):
    """Time of the last peak relative to the kick [s] (Tables 8.6-8.8, first row).

    The thesis calls it the recovery time; it is the time of the last peak
    above the stopping threshold (8 %), not a time from which the signal
    stays small (that is :func:`settling_time`).

    Raises
    ------
    MetricUnavailable
        No peaks, or the record ends before the peaks fall below the threshold.
    """
    if len(peaks) == 0:
        raise MetricUnavailable("no yaw-rate peak after the kick")
    if peaks.stop_reason == "end_of_record":
        raise MetricUnavailable(
            f"the record ends before the yaw-rate peaks fall below {peaks.threshold:.0%} of the largest")
    return float(peaks.times[-1] - peaks.t_kick)


def log_decrement(u0, un, n=1):
    """Logarithmic decrement, thesis eq. 8.2: ``delta = (1/n) ln(|U0| / |Un|)``.

    ``n`` is the number of periods between the two peaks. Negative when the
    oscillation grows.
    """
    u0, un = abs(float(u0)), abs(float(un))
    if not (u0 > 0 and un > 0 and math.isfinite(u0) and math.isfinite(un)):
        raise InputError(f"peak magnitudes must be finite and > 0, got U0={u0!r}, Un={un!r}")
    n = check_range("n (periods between peaks)", n, 0.0, None, "periods", low_open=True)
    return math.log(u0 / un) / n


def peak_pair_metrics(peaks, first, second):
    """Log decrement, damping ratio and period between peaks #first and #second.

    Peak numbers start at 1. The peaks must have the same sign, i.e.
    ``second - first`` even; ``n = (second - first) / 2`` periods.

    Returns
    -------
    dict
        ``log_decrement`` [-], ``damping_ratio`` [-], ``period`` [s] (time
        between the two peaks divided by ``n``).

    Raises
    ------
    MetricUnavailable
        Fewer than ``second`` peaks were found.
    """
    if not (isinstance(first, int) and isinstance(second, int) and 1 <= first < second
            and (second - first) % 2 == 0):
        raise InputError(
            f"peak pair #{first}-#{second} must be two same-sign peaks: integers 1 <= first < second, "
            "second - first even")
    if len(peaks) < second:
        raise MetricUnavailable(
            f"peak #{second} not found: only {len(peaks)} peaks above "
            f"{peaks.threshold:.0%} of the largest")
    n = (second - first) // 2
    delta = log_decrement(peaks.values[first - 1], peaks.values[second - 1], n)
    return {"log_decrement": delta, "damping_ratio": damping_ratio(delta),
            "period": float(peaks.times[second - 1] - peaks.times[first - 1]) / n}


# --------------------------------------------------------------------------
# settling and recovery
# --------------------------------------------------------------------------

@dataclass(frozen=True)
class Settling:
    """Result of :func:`settling_time`.

    Attributes
    ----------
    time : float or None
        Settling time [s from the kick], None when the signal does not settle in the record.
    first_peak : float or None
        ``|signal - baseline|`` at its first peak (signal units), None without a peak.
    reason : str or None
        Why ``time`` is None.
    """

    time: float | None
    first_peak: float | None
    reason: str | None


def settling_time(t, signal, t_kick=0.0, baseline=0.0, *, fraction=SETTLING_FRACTION,
                  first_peak_fraction=FIRST_PEAK_FRACTION, label="signal"):
    """Time after the kick from which ``|signal - baseline|`` stays within ``fraction`` of its first peak.

    The first peak is the first extremum of the deviation after the kick
    (:func:`yaw_rate_peaks` with ``threshold=first_peak_fraction``) that
    reaches ``first_peak_fraction`` of the largest. The settling time is the
    first sample time after the last sample outside the band, minus
    ``t_kick``; a signal still outside the band at the last sample has not
    settled in the record.

    Parameters
    ----------
    t, signal : array_like
        Strictly increasing time [s] and the signal.
    t_kick : float
        Kick time [s].
    baseline : float
        Steady value of the signal (signal units).
    fraction : float
        Half-width of the band, as a fraction of the first peak (default 5 %).
    first_peak_fraction : float
        See above (default 0.5).
    label : str
        Name of the signal in the reasons.

    Returns
    -------
    Settling

    Example
    -------
    >>> import numpy as np
    >>> t = np.arange(0.0, 6.0, 1e-3)
    >>> x = np.exp(-t) * np.sin(2 * np.pi * t)      # first peak 0.79 at 0.23 s
    >>> round(settling_time(t, x).time, 3)          # |x| <= 5 % of it from 2.877 s on
    2.877
    """
    t, x = _as_series(t, signal, label)
    return _settling(t, x, t_kick, baseline, fraction, first_peak_fraction, label)


def _settling(t, x, t_kick, baseline, fraction, first_peak_fraction, label):
    """:func:`settling_time` of the float arrays ``t``, ``x`` that :func:`_as_series` accepted."""
    fraction = check_range("settling band fraction", fraction, 0.0, 1.0, "(of the first peak)", low_open=True)
    if t[-1] <= t_kick:
        return Settling(None, None, f"the record ends before the kick (t = {t[-1]:.3f} s)")
    peaks = _peaks_of(t, x, t_kick, first_peak_fraction, None, baseline, 3)
    if len(peaks) == 0:
        return Settling(None, None, f"no {label} peak after the kick")
    peak = float(abs(peaks.values[0]))
    # The samples from the kick on are a run (time increases): the search looks at them only.
    first = int(np.searchsorted(t, t_kick))
    outside = np.flatnonzero(np.abs(x[first:] - baseline) > fraction * peak)
    if outside.size and outside[-1] == t.size - 1 - first:
        return Settling(None, peak, f"{label} still outside {fraction:.0%} of its first peak at the end "
                                    f"of the record ({t[-1] - t_kick:.3f} s after the kick)")
    j = first + outside[-1] + 1 if outside.size else first
    return Settling(float(t[j] - t_kick), peak, None)


def recovery(data, t_kick=0.0, baselines=None, *, ended=None):
    """Recovery after a kick: when yaw, roll and steer rates have all settled.

    Each signal of :data:`RECOVERY_SIGNALS` is judged by :func:`settling_time`
    (5 % of its own first peak); the recovery time is the latest of the
    three. This is the one definition of recovery the simulation summary,
    the sweep table, the pressure recommender and the command line use.

    Parameters
    ----------
    data : pandas.DataFrame or dict of arrays
        ``time`` and the :data:`RECOVERY_SIGNALS` columns (SI units).
    t_kick : float
        Kick time [s].
    baselines : dict, optional
        Steady value of each signal (default 0).
    ended : str, optional
        Why the record cannot show a recovery although it has peaks (e.g.
        "fell 1.345 s after the kick", "integration failed"): every settling
        time is then None with this reason.

    Returns
    -------
    dict
        ``definition``; ``time_s`` (latest settling time, or None) and
        ``reason``; ``last_to_settle`` (signal name or None); ``signals``:
        per signal ``first_peak_<unit>``, ``time_s``, ``reason``.

    Example
    -------
    >>> import numpy as np
    >>> t = np.arange(0.0, 6.0, 1e-3)
    >>> x = np.exp(-t) * np.sin(2 * np.pi * t)
    >>> rec = recovery({"time": t, "yaw_rate": x, "roll_rate": x, "steer_rate": 0.5 * x})
    >>> round(rec["time_s"], 3), rec["signals"]["steer_rate"]["time_s"] == rec["time_s"]
    (2.877, True)
    """
    baselines = dict(baselines or {})
    signals, t = {}, None
    for name, unit in RECOVERY_SIGNALS.items():
        if name not in data:
            raise InputError(f"column {name!r} ({unit}) is missing; recovery needs "
                             f"{', '.join(RECOVERY_SIGNALS)}")
        label = name.replace("_", " ")
        if t is None:   # the record's time, checked once with its first signal
            t, x = _as_series(data["time"], data[name], label)
        else:
            x = _as_signal(t, data[name], label)
        s = _settling(t, x, t_kick, float(baselines.get(name, 0.0)), SETTLING_FRACTION, FIRST_PEAK_FRACTION,
                      label)
        time, reason = (None, ended) if ended is not None else (s.time, s.reason)
        signals[name] = {f"first_peak_{unit.replace('/', '_')}": s.first_peak, "time_s": time, "reason": reason}
    unsettled = [name for name, v in signals.items() if v["time_s"] is None]
    if unsettled:
        time, last = None, None
        reason = ended if ended is not None else "not settled within the run: " + "; ".join(
            signals[name]["reason"] for name in unsettled)
    else:
        last = max(signals, key=lambda name: signals[name]["time_s"])
        time, reason = signals[last]["time_s"], None
    return {"definition": (f"time after the kick from which |signal - steady| stays within "
                           f"{SETTLING_FRACTION:.0%} of the signal's first peak, for each of "
                           f"{', '.join(RECOVERY_SIGNALS)}; recovered when all three have settled"),
            "time_s": time, "reason": reason, "last_to_settle": last, "signals": signals}


# --------------------------------------------------------------------------
# frequency domain
# --------------------------------------------------------------------------

def amplitude_spectrum(t, signal, f_max=25.0, *, window="boxcar"):
    """Single-sided FFT amplitude spectrum up to ``f_max``.

    Normalised so that a sinusoid ``A sin(2 pi f t)`` with ``f`` on an FFT bin
    shows amplitude ``A`` and a constant ``C`` shows ``C`` at 0 Hz:
    ``amp = 2 |X_k| / sum(w)`` for 0 < f < Nyquist and ``|X_k| / sum(w)`` at
    0 Hz and Nyquist, where ``X = FFT(w * x)``. For a transient (a kick
    response) the amplitude scales as 1/record length, so compare spectra
    only over windows of equal duration.

    Parameters
    ----------
    t, signal : array_like
        Strictly increasing time [s]; non-uniform input is first resampled
        linearly at the median interval (:func:`resample_uniform`).
    f_max : float
        Highest frequency returned [Hz] (thesis: 25 Hz); capped at Nyquist.
    window : str
        Any :func:`scipy.signal.get_window` name. Default ``"boxcar"`` (no
        window: the thesis does not mention one); ``"hann"`` reduces leakage
        and keeps bin-centred amplitudes exact through the ``sum(w)`` scaling.

    Returns
    -------
    freq, amp : ndarray
        Frequencies [Hz] and amplitudes (signal units).
    """
    from scipy.signal import get_window  # SciPy's signal package: 0.9 s of import a run does not need

    f_max = check_range("f_max", f_max, 0.0, None, "Hz", low_open=True)
    t, x = resample_uniform(t, signal)
    dt = (t[-1] - t[0]) / (t.size - 1)
    try:
        w = get_window(window, x.size)
    except ValueError as exc:
        raise InputError(f"window = {window!r} is not a scipy.signal window name: {exc}") from None
    spec = np.abs(np.fft.rfft(w * x)) / np.sum(w)
    # Every bin but DC and (for even N) Nyquist has a mirror image of equal size.
    spec[1:(x.size + 1) // 2] *= 2
    freq = np.fft.rfftfreq(x.size, dt)
    keep = freq <= f_max * (1 + 1e-12)
    return freq[keep], spec[keep]


def lowpass(t, signal, cutoff_hz=20.0, order=4):
    """Zero-phase Butterworth low-pass filter (thesis: 20 Hz on measured data).

    The thesis names the cut-off but not the filter; a forward-backward
    Butterworth (``sosfiltfilt``) is used so peaks are not shifted in time.
    Needs uniform sampling (resample with :func:`resample_uniform` first).
    """
    from scipy.signal import butter, sosfiltfilt  # SciPy's signal package: 0.9 s of import a run does not need

    t, x = _as_series(t, signal)
    if not _is_uniform(t):
        raise InputError("lowpass needs uniform sampling (interval spread > 0.1 %); "
                         "resample with resample_uniform() first")
    fs = (t.size - 1) / (t[-1] - t[0])
    cutoff_hz = check_range("cutoff_hz", cutoff_hz, 0.0, fs / 2, "Hz", low_open=True, high_open=True)
    if isinstance(order, bool) or int(order) != order or not 1 <= order <= 10:
        raise InputError(f"filter order = {order!r} must be an integer in [1, 10]")
    sos = butter(int(order), cutoff_hz, fs=fs, output="sos")
    try:
        return sosfiltfilt(sos, x)
    except ValueError as exc:  # series shorter than the filter's padding
        raise InputError(f"series of {x.size} samples is too short to low-pass filter: {exc}") from None


def as_recorded(t, signal, t_kick=0.0, rate_hz=100.0, cutoff_hz=20.0, order=4):
    """A signal as the thesis' IMU recorded and filtered it (Section 8.3, "Data analysis").

    Sampled at ``rate_hz`` on a grid through ``t_kick`` (linear
    interpolation, exact to the solution's own accuracy when the input is a
    fine simulation output), then low-passed at ``cutoff_hz`` without phase
    shift (:func:`lowpass`, so the peaks stay where they were).

    Parameters
    ----------
    t, signal : array_like
        Strictly increasing time [s] and the signal.
    t_kick : float
        A time [s] the grid passes through (the kick start).
    rate_hz : float
        Sampling rate [Hz] (thesis: 100 Hz).
    cutoff_hz : float
        Low-pass cut-off [Hz] (thesis: 20 Hz), below ``rate_hz / 2``.
    order : int
        Butterworth order (the thesis does not say; 4).

    Returns
    -------
    t_rec, x_rec : ndarray
        The recording's time grid [s] and the filtered signal on it.
    """
    t, x = _as_series(t, signal)
    rate_hz = check_range("recording rate", rate_hz, 0.0, None, "Hz", low_open=True)
    first = math.ceil((t[0] - t_kick) * rate_hz - 1e-9)
    last = math.floor((t[-1] - t_kick) * rate_hz + 1e-9)
    if last - first < 2:
        raise InputError(f"record of {t[-1] - t[0]:g} s is too short to sample at {rate_hz:g} Hz")
    t_rec = t_kick + np.arange(first, last + 1) / rate_hz
    x_rec = np.interp(t_rec, t, x)
    return t_rec, lowpass(t_rec, x_rec, cutoff_hz, order)


def dominant_frequency(t, signal, t_start, duration, f_min=0.0, f_max=25.0, *, baseline=0.0):
    """Frequency [Hz] of the largest local maximum of :func:`amplitude_spectrum` over a window.

    The window is ``[t_start, t_start + duration)`` (1 s gives the thesis'
    1 Hz bins). Only a bin larger than both its neighbours counts (a local
    maximum, as the thesis reads its spectra): the spectrum of a decaying
    pulse falls from 0 Hz without a peak, and its largest bin above
    ``f_min`` would only be the edge of that fall. Only frequencies in
    ``[f_min, f_max]`` compete.

    Raises
    ------
    MetricUnavailable
        No local maximum in ``[f_min, f_max]``.
    """
    t, x = _as_series(t, signal)
    window = (t >= t_start - 1e-9) & (t < t_start + duration - 1e-9)   # half-open: N samples, bins of 1/duration
    freq, amp = amplitude_spectrum(t[window], x[window] - baseline, f_max)
    inner = np.arange(1, freq.size - 1)
    peaks = inner[(amp[inner] > amp[inner - 1]) & (amp[inner] >= amp[inner + 1]) & (freq[inner] >= f_min - 1e-9)]
    if not peaks.size:
        raise MetricUnavailable(f"the amplitude spectrum over {t_start:g}-{t_start + duration:g} s has no local "
                                f"maximum between {f_min:g} and {f_max:g} Hz")
    return float(freq[peaks[np.argmax(amp[peaks])]])


def residual_ratio(t, signal, window, reference, baseline=0.0):
    """Largest ``|signal - baseline|`` within ``window = (t0, t1)`` [s] divided by ``|reference|``.

    E.g. how much of the first yaw-rate peak is left 0.5-1 s after the kick.

    Raises
    ------
    MetricUnavailable
        No sample in the window, or a zero reference.
    """
    t, x = _as_series(t, signal)
    inside = (t >= window[0] - 1e-9) & (t <= window[1] + 1e-9)
    if not np.any(inside):
        raise MetricUnavailable(f"no sample between {window[0]:g} and {window[1]:g} s")
    if reference == 0:
        raise MetricUnavailable("the reference peak is zero")
    return float(np.max(np.abs(x[inside] - baseline)) / abs(reference))


# --------------------------------------------------------------------------
# all metrics of one run
# --------------------------------------------------------------------------

def _columns(data):
    """Known columns of a DataFrame or mapping as float arrays of equal length."""
    if hasattr(data, "columns"):
        names = list(data.columns)
    elif hasattr(data, "keys"):
        names = list(data.keys())
    else:
        raise InputError(f"data must be a pandas DataFrame or a dict of arrays, got {type(data).__name__}")
    for need in ("time", "yaw_rate"):
        if need not in names:
            raise InputError(f"column {need!r} ({COLUMNS[need]}) is missing; columns present: {names}")
    cols = {}
    for name in COLUMNS:
        if name in names:
            try:
                cols[name] = np.asarray(data[name], dtype=float).ravel()
            except (TypeError, ValueError):
                raise InputError(f"column {name!r} ({COLUMNS[name]}) must be numeric") from None
    t = cols["time"]
    _as_series(t, t, "time")   # the time once; then each signal against it
    for name, arr in cols.items():
        if arr is not t:
            _as_signal(t, arr, name)
    return cols


def kick_metrics(data, t_kick=0.0, threshold=0.08, *, baseline=0.0, lowpass_hz=None,
                 fall_roll=math.radians(45.0), spectrum_duration=1.0, f_max=25.0,
                 include_spectra=True, hysteresis=None, refine_points=3):
    """All Section 8.3 metrics of one kick response.

    Parameters
    ----------
    data : pandas.DataFrame or dict of arrays
        Columns named as in :data:`COLUMNS` (SI units); ``time`` and
        ``yaw_rate`` are required, the others are used when present.
    t_kick : float
        Kick time [s]; all metrics look at ``t >= t_kick`` only and all times
        returned are relative to it.
    threshold, hysteresis, baseline, refine_points
        Passed to :func:`yaw_rate_peaks` (``baseline`` applies to the yaw rate).
    lowpass_hz : float, optional
        Low-pass every signal first (:func:`lowpass`, order 4); the thesis
        filtered measured data at 20 Hz. Default: no filtering.
    fall_roll : float
        ``|roll|`` [rad] above which the bicycle has fallen (default 45 deg,
        as in the simulation's fall event).
    spectrum_duration : float
        Length [s] of the window after the kick used for the spectra
        (shortened to the record if needed; see :func:`amplitude_spectrum`).
    f_max : float
        Highest spectrum frequency [Hz].
    include_spectra : bool
        Add ``"spectra"``: ``{"yaw_rate": (freq, amp), "roll_rate": ...}``.

    Returns
    -------
    dict
        Scalars keyed as in :data:`METRIC_UNITS` (``peak_times`` and
        ``peak_values`` are lists), ``"unavailable"``: {metric: reason} for
        each metric that is ``None``, and optionally ``"spectra"``.
    """
    cols = _columns(data)
    t = cols.pop("time")
    if lowpass_hz is not None:
        cols = {name: lowpass(t, x, lowpass_hz) for name, x in cols.items()}
    peaks = _peaks_of(t, cols["yaw_rate"], t_kick, threshold, hysteresis, baseline, refine_points)
    out = {"n_peaks": len(peaks),
           "peak_times": (peaks.times - peaks.t_kick).tolist(),
           "peak_values": peaks.values.tolist(),
           "peak_stop_reason": peaks.stop_reason}
    missing = {}

    def attempt(keys, compute):
        try:
            values = compute()
        except MetricUnavailable as exc:
            for key in keys:
                out[key], missing[key] = None, str(exc)
            return
        out.update(zip(keys, values, strict=True))

    attempt(["last_peak_time"], lambda: [last_peak_time(peaks)])
    for a, b in PEAK_PAIRS:
        suffix = f"_{a}_{b}"
        attempt(["log_decrement" + suffix, "damping_ratio" + suffix, "period" + suffix],
                lambda a=a, b=b: list(peak_pair_metrics(peaks, a, b).values()))
    out["period"] = out["period_1_3"]
    if out["period"] is None:
        missing["period"] = missing["period_1_3"]

    # The samples from the kick on: a run, as time increases (a view, not a masked copy).
    first = int(np.searchsorted(t, t_kick))
    for name in COLUMNS:
        if name == "time":
            continue
        key = f"max_abs_{name}"
        if name in cols:
            out[key] = float(np.max(np.abs(cols[name][first:])))
        else:
            out[key], missing[key] = None, f"no {name!r} column"

    if "roll" in cols:
        fall_roll = check_range("fall_roll", fall_roll, 0.0, math.pi / 2, "rad", low_open=True)
        over = first + np.flatnonzero(np.abs(cols["roll"][first:]) > fall_roll)
        out["fell"] = bool(over.size)
        if over.size:
            j = over[0]
            out["fall_time"] = float(t[j] - t_kick)
            if j > 0 and t[j - 1] >= t_kick:  # interpolate the crossing linearly
                r0, r1 = abs(cols["roll"][j - 1]), abs(cols["roll"][j])
                out["fall_time"] = float(t[j - 1] + (fall_roll - r0) / (r1 - r0) * (t[j] - t[j - 1]) - t_kick)
        else:
            out["fall_time"], missing["fall_time"] = None, "did not fall"
    else:
        for key in ("fell", "fall_time"):
            out[key], missing[key] = None, "no 'roll' column"

    if include_spectra:
        duration = check_range("spectrum_duration", spectrum_duration, 0.0, None, "s", low_open=True)
        window = (t >= t_kick) & (t <= t_kick + duration)
        out["spectra"] = {name: amplitude_spectrum(t[window], cols[name][window], f_max)
                          for name in ("yaw_rate", "roll_rate") if name in cols}
    out["unavailable"] = missing
    return out


def load_measurement_csv(path, *, rename=None, scale=None, required=("time", "yaw_rate"), sep=","):
    """Read a measured time series with named columns.

    Parameters
    ----------
    path : str or path-like
        Delimited text file with a header row; ``#`` starts a comment.
    rename : dict, optional
        ``{column in the file: name in COLUMNS}``, e.g. ``{"gyro_z": "yaw_rate"}``.
    scale : dict, optional
        ``{name in COLUMNS: factor}`` applied after renaming to reach SI units,
        e.g. ``{"yaw_rate": math.pi / 180}`` for deg/s.
    required : sequence of str
        Columns (after renaming) that must be present.
    sep : str
        Field separator (``"\\t"`` for tab-separated logs).

    Returns
    -------
    pandas.DataFrame
        All columns of the file, renamed and scaled, as floats.

    Raises
    ------
    InputError
        Missing or unreadable file, missing columns, non-numeric or missing
        values, time not strictly increasing.
    """
    path = pathlib.Path(path)
    try:
        df = pd.read_csv(path, sep=sep, comment="#", skipinitialspace=True)
    except FileNotFoundError:
        raise InputError(f"measurement file {path} does not exist") from None
    except (pd.errors.ParserError, pd.errors.EmptyDataError, UnicodeDecodeError) as exc:
        raise InputError(f"measurement file {path} is not a delimited table: "
                         f"{str(exc).splitlines()[0] if str(exc) else type(exc).__name__}") from None
    df.columns = [str(c).strip() for c in df.columns]
    df = df.rename(columns=rename or {})
    absent = [name for name in required if name not in df.columns]
    if absent:
        raise InputError(f"measurement file {path} lacks column(s) {absent}; columns present: {list(df.columns)}")
    for name in df.columns:
        values = pd.to_numeric(df[name], errors="coerce")
        bad = int(values.isna().sum())
        if bad:
            raise InputError(f"measurement file {path}: column {name!r} has {bad} empty or non-numeric values")
        df[name] = values.astype(float)
    for name, factor in (scale or {}).items():
        if name not in df.columns:
            raise InputError(f"scale given for column {name!r}, which is not in {path}")
        df[name] = df[name] * float(factor)
    if "time" in df.columns and np.any(np.diff(df["time"].to_numpy()) <= 0):
        raise InputError(f"measurement file {path}: time must be strictly increasing (s)")
    return df
