"""The yaw rate's oscillation after a kick as one damped sinusoid on a slow trend: frequency, decay, envelope.

The thesis reduces each recording to peak times and magnitudes (peaks #1-#6
above 8 % of the largest, Section 8.3). On the model the same peak rule is
fragile: the closed loop's slow swing (0.25-0.3 of peak #1 0.5-1 s after the
kick, docs/experiments.md) lifts the late half-waves off zero, so the rule
ends on the kick spike alone (one peak) or runs on to the swing at 0.9 s.
:func:`fit` describes the same event continuously instead: from peak #1 on,
over ``window`` seconds, the recorded yaw rate (baseline removed) is fitted
by

    ``y(tau) = exp(-sigma tau) (a cos(w tau) + b sin(w tau)) + c0 + c1 tau + c2 tau^2``

(``tau`` the time since peak #1): a damped sinusoid, the oscillation the
peaks sample, on a quadratic trend, the slow swing over the window. The fit
is a variable projection: for each ``(sigma, w)`` the five coefficients are
linear least squares; ``(sigma, w)`` come from a grid and are refined by
:func:`scipy.optimize.least_squares`.

For a damped sinusoid the thesis' metrics follow exactly: the period is
``2 pi / w``, the log decrement between peaks one period apart (eq. 8.2)
is ``sigma T``, and peaks stay above 8 % of peak #1 until the envelope
``A exp(-sigma tau)`` (``A = hypot(a, b)``) falls to ``0.08 |peak #1|``,
at ``tau_8 = ln(A / (0.08 |peak #1|)) / sigma`` (:attr:`OscillationFit.envelope_time`).
"""
from dataclasses import dataclass
import math

import numpy as np
from scipy.optimize import least_squares

from whipple_kick.errors import InputError, check_range

#: Fitted window after peak #1 [s]: the thesis analysed the peaks over 0.5 s (Sections 8.5.1-8.5.2: the
#: oscillation disappears in less than 0.5 s; the experiment file's ``processing.peak_window``).
WINDOW = 0.5
#: Frequencies the oscillation may have [Hz]: below 2.5 Hz a 0.5 s window holds less than 1.25 cycles and a
#: damped sinusoid trades off against the quadratic trend; above 15 Hz is past the model's 8-10 Hz and the
#: measured 5-6 Hz (docs/experiments.md) with room, below the 20 Hz low-pass.
FREQUENCY_RANGE_HZ = (2.5, 15.0)
#: Decay rates searched [1/s]: a growing oscillation (negative) is allowed; 60 1/s halves it in 12 ms.
SIGMA_RANGE = (-10.0, 60.0)
#: The thesis' stopping fraction: peaks are counted until one is below 8 % of the largest (Section 8.3).
PEAK_FRACTION = 0.08


@dataclass(frozen=True)
class OscillationFit:
    """Result of :func:`fit`.

    Attributes
    ----------
    t0 : float
        Start of the fit, the time of peak #1 [s, on the input clock].
    frequency_hz, sigma : float
        Damped frequency [Hz] and decay rate [1/s] of the fitted oscillation.
    amplitude : float
        Envelope at ``t0`` (``hypot(a, b)``, signal units).
    first_peak : float
        ``|peak #1|`` (signal units, baseline removed).
    coefficients : ndarray
        ``a, b, c0, c1, c2``.
    rms, r2 : float
        Residual RMS (signal units) and the share of the window's variance explained.
    """

    t0: float
    frequency_hz: float
    sigma: float
    amplitude: float
    first_peak: float
    coefficients: np.ndarray
    rms: float
    r2: float

    @property
    def period(self):
        """Damped period [s]."""
        return 1.0 / self.frequency_hz

    @property
    def log_decrement(self):
        """Log decrement per period, ``sigma T`` (thesis eq. 8.2 with n = 1, peaks one period apart)."""
        return self.sigma * self.period

    @property
    def envelope_time(self):
        """Time after peak #1 at which the envelope falls to 8 % of ``|peak #1|`` [s] (inf if it never does)."""
        ratio = self.amplitude / (PEAK_FRACTION * self.first_peak)
        if ratio <= 1.0:
            return 0.0
        return math.log(ratio) / self.sigma if self.sigma > 0 else math.inf

    def evaluate(self, t):
        """The fitted curve at times ``t`` [s] (input clock)."""
        tau = np.asarray(t, dtype=float) - self.t0
        return _basis(tau, self.sigma, 2 * math.pi * self.frequency_hz) @ self.coefficients

    def trend(self, t):
        """The fitted quadratic trend alone (the slow swing over the window) at times ``t`` [s]."""
        tau = np.asarray(t, dtype=float) - self.t0
        return self.coefficients[2] + self.coefficients[3] * tau + self.coefficients[4] * tau * tau

    def oscillation(self, t):
        """The fitted damped sinusoid alone (trend removed) at times ``t`` [s]."""
        tau = np.asarray(t, dtype=float) - self.t0
        return _basis(tau, self.sigma, 2 * math.pi * self.frequency_hz)[:, :2] @ self.coefficients[:2]


def _basis(tau, sigma, w):
    e = np.exp(-sigma * tau)
    return np.column_stack([e * np.cos(w * tau), e * np.sin(w * tau), np.ones_like(tau), tau, tau * tau])


def _solve(tau, y, sigma, w):
    A = _basis(tau, sigma, w)
    coef, *_ = np.linalg.lstsq(A, y, rcond=None)
    return coef, A @ coef - y


def fit(t, signal, t_first_peak, first_peak, window=WINDOW):
    """Fit the damped sinusoid on a quadratic trend from peak #1 over ``window`` seconds.

    Parameters
    ----------
    t, signal : array_like
        Time [s] (strictly increasing) and the signal with its baseline removed (e.g. the
        recorded yaw rate minus the steady yaw rate).
    t_first_peak : float
        Time of peak #1 [s] (the start of the fit).
    first_peak : float
        Value of peak #1 (signal units; its magnitude scales the envelope time).
    window : float
        Length of the fit [s] (default :data:`WINDOW`).

    Returns
    -------
    OscillationFit

    Raises
    ------
    InputError
        Fewer than 12 samples in the window, or a zero peak.
    """
    window = check_range("oscillation window", window, 0.0, None, "s", low_open=True)
    t = np.asarray(t, dtype=float)
    y = np.asarray(signal, dtype=float)
    inside = (t >= t_first_peak - 1e-9) & (t <= t_first_peak + window + 1e-9)
    if np.count_nonzero(inside) < 12:
        raise InputError(f"the oscillation window {t_first_peak:g}-{t_first_peak + window:g} s holds "
                         f"{np.count_nonzero(inside)} samples; at least 12 are needed")
    if first_peak == 0:
        raise InputError("peak #1 is zero: no oscillation to fit")
    tau, yw = t[inside] - t_first_peak, y[inside]
    scale = float(np.max(np.abs(yw)))
    yn = yw / scale
    best = (math.inf, None, None)
    for f in np.arange(FREQUENCY_RANGE_HZ[0], FREQUENCY_RANGE_HZ[1] + 1e-9, 0.25):
        for s in np.arange(SIGMA_RANGE[0], SIGMA_RANGE[1] + 1e-9, 2.0):
            _, r = _solve(tau, yn, s, 2 * math.pi * f)
            cost = float(r @ r)
            if cost < best[0]:
                best = (cost, s, f)
    lo = [SIGMA_RANGE[0], FREQUENCY_RANGE_HZ[0]]
    hi = [SIGMA_RANGE[1], FREQUENCY_RANGE_HZ[1]]
    sol = least_squares(lambda p: _solve(tau, yn, p[0], 2 * math.pi * p[1])[1], [best[1], best[2]],
                        bounds=(lo, hi), x_scale=[5.0, 1.0])
    sigma, f = (float(v) for v in sol.x)
    coef, r = _solve(tau, yn, sigma, 2 * math.pi * f)
    coef = coef * scale
    rms = float(np.sqrt(np.mean(r * r))) * scale
    var = float(np.var(yw))
    r2 = 1.0 - rms ** 2 / var if var > 0 else 0.0
    return OscillationFit(float(t_first_peak), f, sigma, float(math.hypot(coef[0], coef[1])), abs(float(first_peak)),
                          coef, rms, r2)
