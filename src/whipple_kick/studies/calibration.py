"""What the measurements say: history matching and a posterior of the model's uncertain inputs.

Three steps, each a function of its own:

1. **Features the model and the measurement share** (:func:`measured_features`,
   :func:`model_features`), per measured cell (rear load x pressure, thesis
   Tables 8.6-8.8; the thesis gives no kick direction, so the direction is a
   setting of the model runs, reported per option):

   * ``frequency_hz``: measured ``1 / period`` (peaks #1-#3); model: the
     frequency of the damped sinusoid fitted from peak #1 over the thesis'
     0.5 s peak window on a quadratic trend (:mod:`whipple_kick.simulate.oscillation`).
     Error: a stated prior on the period (0.02 s, no trial spread printed), by ``sd_T / T^2``.
   * ``log_decrement``: measured the mean of the printed log decrements of
     the cell (#1-#3, #2-#4, #3-#5: each is one decay per period);
     model: the fitted ``sigma T``. Error: the standard error of the
     printed ones (their spread in the cell), floored by a stated prior.
   * ``last_peak_time_s``: the time after peak #1 at which the oscillation
     falls below 8 % of peak #1. Measured: the last peak above 8 % at ``L``
     (printed, read from peak #1; docs/experiments.md) puts the crossing in
     ``[L, L + T/2)``, so ``z = L + T/4`` with variance ``(T/2)^2 / 12``
     plus a stated trial-to-trial prior; model: the fitted envelope's 8 %
     time (:attr:`~whipple_kick.simulate.oscillation.OscillationFit.envelope_time`),
     capped at the 1 s record. Measured from the oscillation, not the kick
     spike (peak #1 alone) and not the closed loop's slow swing at 0.9 s that
     the raw 8 % rule ends on (31 % and 68 % of the prior study's runs).

2. **History matching in waves** (:func:`history_match`): a Latin hypercube
   over the uniform priors (:mod:`whipple_kick.library.priors`), the
   simulator run on it, one Gaussian-process emulator per feature and cell
   (:class:`Emulators`, scikit-learn), and the implausibility

       ``I = |z - E[f(x)]| / sqrt(Var_emulator + Var_measurement + Var_discrepancy)``

   per feature; an input is ruled out when the ``rank``-th largest ``I`` over
   the features exceeds :data:`CUTOFF` (3, Pukelsheim's three-sigma rule for
   unimodal distributions). ``rank`` is 2 by default (the second-largest: one
   feature may be off from an emulator's local misfit without ruling an input
   out; Vernon, Goldstein & Bower 2010, Bayesian Anal. 5(4), use the second and
   third maxima for many outputs), 1 (the maximum) with fewer than three features.
   Each wave's design is drawn inside what the earlier waves left; its
   emulators are fitted to the runs inside it. Where the simulator reports
   the rider's linear stability (``last_margin``: the slowest closed-loop
   pole's real part), it is emulated too and inputs whose rider is surely
   unstable (emulated real part more than 3 sd above 0.001 1/s) are ruled
   out: the features end 1 s after the kick and cannot see a rider that would
   not recover.

3. **The posterior inside what is left** (:func:`posterior`): emcee's affine-
   invariant ensemble on the last wave's emulators, with the same Gaussian
   likelihood (its variance the emulator's + measurement + discrepancy), the
   uniform prior, and zero density where any wave rules the input out. Its
   diagnostics: the integrated autocorrelation time per input (emcee), the
   effective sample size, and a split R-hat over the walkers' half-chains
   (Gelman et al. 2013; walkers of one ensemble are not independent chains,
   so it is a symptom check, not a proof).

4. **Checks of the posterior against the measurement**: the posterior
   predictive per feature and cell, from the emulators (400 draws) and from
   the simulator run at ``check_runs`` posterior draws (``features.csv``'s
   ``simulator_*`` columns: each run plus the measurement's and the
   discrepancy's noise); and the held-out checks (:func:`held_out`):
   calibrate without one rear load and predict it, or calibrate with the
   model kicked one way and predict the measurements kicked the other.

The answer under the posterior (P(best) per pressure and load) is
:mod:`whipple_kick.studies.posterior_study`.

If nothing survives, the result says so, with the features no input
matches at once (each feature's smallest implausibility over the candidates):
a finding, not a failure.

The simulator is any callable ``simulator(X) -> Y`` (rows of inputs in the
priors' units, columns of :func:`feature_keys`; NaN where a run gives no
value): :class:`ModelSimulator` runs the kick model through the sweep engine,
:class:`ToySimulator` is an analytic stand-in of the same interface for the
fast known-answer test.

Example
-------
>>> from whipple_kick.studies import calibration
>>> m = calibration.measured_features(features=["frequency_hz"], cells=[(635.0, 400.0)])
>>> round(float(m["measured"].iloc[0]), 3), m["unit"].iloc[0]
(5.263, 'Hz')
"""
import contextlib
import dataclasses
import json
import math
import pathlib
import tempfile
import warnings

import numpy as np
import pandas as pd
import scipy.linalg  # noqa: F401 -- loaded before calibrate()'s thread limit, so that its OpenBLAS is limited too
from scipy.linalg import solve_triangular
from scipy.stats import qmc
from threadpoolctl import threadpool_limits

from whipple_kick import fileio
from whipple_kick.errors import InputError
from whipple_kick.library import experiments, priors
from whipple_kick.simulate import analysis, oscillation

from . import validation
from .sweep_engine import make_cases, sweep
from .sweep_store import load_trajectory
from .validation import DIRECTIONS

#: Feature units (their definitions: the module docstring).
FEATURE_UNITS = {"frequency_hz": "Hz", "log_decrement": "-", "last_peak_time_s": "s"}
#: Implausibility above which an input is ruled out (Pukelsheim 1994's three-sigma rule).
CUTOFF = 3.0
#: Printed rounding of the tables' two-decimal values, as a standard deviation: +-0.005 uniform.
ROUNDING_SD = experiments.PRINT_HALF_STEP / math.sqrt(3.0)
#: A closed-loop pole with a larger real part [1/s] makes the rider unstable (the project's limit,
#: whipple_kick.simulate.assembly.UNSTABLE_REAL_PART: slower growth is below 1 % over a 10 s run).
UNSTABLE_REAL_PART = 1e-3
#: A posterior "piles at a bound" when more than EDGE_PILE of it lies within EDGE_SHARE of the prior's width
#: of one bound (a uniform posterior would put EDGE_SHARE there): reported, since the data then ask for values
#: at or beyond that bound (beyond may be unphysical, e.g. a negative damping: the model lacks something).
EDGE_SHARE, EDGE_PILE = 0.05, 0.25
#: The features' cap on the model's envelope time [s]: the thesis' 1 s records (Section 8.5.3).
ENVELOPE_CAP = 1.0
#: Simulated time after the kick [s] for the features: the 1 s record and the fit's 0.5 s window after
#: peak #1 (at 0.1 s) fit in it with room for the low-pass filter's ends.
FEATURE_DURATION = 1.5
#: The modelling choices a posterior is conditional on (discrete: reported per option, never pooled).
CHOICE_FIELDS = ("rider_body", "lqr_model", "kick_direction", "friction", "tyre_transient")
#: What :meth:`Calibration.write` calls the settings file, and its format line.
SETTINGS_FILE, SETTINGS_FORMAT = "settings.json", "whipple_kick calibration settings, version 1"
#: The held-out checks (:func:`held_out`): leave one rear load out, or predict the other kick direction.
HELD_OUT = ("load", "direction")


def _check_features(features):
    features = list(FEATURE_UNITS) if features is None else list(features)
    bad = [f for f in features if f not in FEATURE_UNITS]
    if bad or not features:
        raise InputError(f"feature(s) {', '.join(map(repr, bad)) or '(none)'} unknown: the experiments give "
                         f"{', '.join(FEATURE_UNITS)}")
    return features


def _check_cells(exp, cells):
    if cells is None:
        return [(c.fz_n, c.pressure_kpa) for c in exp.cases.values()]
    out = []
    for fz, p in cells:
        exp.case(float(fz), float(p))   # InputError naming the measured loads and pressures
        out.append((float(fz), float(p)))
    if not out:
        raise InputError("no measured cell chosen; the experiment has " + ", ".join(exp.cases))
    return out


def feature_keys(cells, features):
    """Column keys ``"<cell>:<feature>"`` in the order a simulator returns them (cell-major)."""
    return [f"{experiments.case_name(fz, p)}:{f}" for fz, p in cells for f in features]


def measured_features(spec=priors.DEFAULT, experiment=None, features=None, cells=None, discrepancy=None):
    """The measured value of each feature per cell, with its measurement error and discrepancy.

    Parameters
    ----------
    spec : str, path or CalibrationSpec
        The calibration file (errors and discrepancies).
    experiment : Experiment, optional
        Default: the file's experiment.
    features : list of str, optional
        Subset of :data:`FEATURE_UNITS` (default all).
    cells : list of (load [N], pressure [kPa]), optional
        Default: every measured case.
    discrepancy : dict, optional
        ``{feature: sd}`` overriding the file's (checked: > 0).

    Returns
    -------
    pandas.DataFrame
        ``key, cell, fz_n, pressure_kpa, feature, unit, measured, sd_measurement,
        sd_discrepancy, how``, in :func:`feature_keys` order.
    """
    spec = _spec(spec)
    exp = experiments.load(spec.experiment) if experiment is None else experiment
    features = _check_features(features)
    cells = _check_cells(exp, cells)
    disc = {f: s.sd for f, s in spec.discrepancy.items()}
    for f, sd in (discrepancy or {}).items():
        disc[f] = priors.discrepancy(f, sd, FEATURE_UNITS.get(f, "")).sd
    rows = []
    for fz, p in cells:
        case = exp.case(fz, p)
        v = case.values
        T = v["period"]
        for f in features:
            if f == "frequency_hz":
                z = 1.0 / T
                sd = math.hypot(spec.errors[f].sd, ROUNDING_SD) / T ** 2
                how = f"1 / period #1-#3 ({T:g} s); sd from a period sd of {spec.errors[f].sd:g} s (prior)"
            elif f == "log_decrement":
                deltas = [v[k] for k in ("log_dec_13", "log_dec_24", "log_dec_35") if k in v]
                if not deltas:
                    raise InputError(f"{case.case}: the experiment prints no log decrement: feature {f} unavailable")
                z = float(np.mean(deltas))
                spread = float(np.std(deltas, ddof=1)) / math.sqrt(len(deltas)) if len(deltas) > 1 else 0.0
                sd = max(spread, spec.errors[f].sd)
                how = (f"mean of the printed log decrements {', '.join(f'{d:g}' for d in deltas)}; "
                       f"sd their standard error {spread:.3g} (floor {spec.errors[f].sd:g})")
            else:
                L = v["last_peak_time"]
                z = L + T / 4.0
                sd = math.sqrt(spec.errors[f].sd ** 2 + (T / 2.0) ** 2 / 12.0 + ROUNDING_SD ** 2)
                how = (f"last peak {L:g} s (from peak #1) + T/4: the 8 % crossing lies in [L, L + T/2); sd: "
                       f"trial prior {spec.errors[f].sd:g} s and the half-period quantisation")
            rows.append({"key": f"{case.case}:{f}", "cell": case.case, "fz_n": fz, "pressure_kpa": p, "feature": f,
                         "unit": FEATURE_UNITS[f], "measured": z, "sd_measurement": sd,
                         "sd_discrepancy": disc[f], "how": how})
    return pd.DataFrame(rows)


def model_features(t, yaw_rate, steady=0.0, t_kick=0.0, processing=None):
    """The features of one model run, from its yaw rate processed as the recordings were.

    Parameters
    ----------
    t, yaw_rate : array_like
        Time [s] and yaw rate [rad/s] of the run.
    steady : float
        Steady yaw rate before the kick [rad/s].
    t_kick : float
        Kick start [s].
    processing : dict, optional
        The experiment's ``processing`` (100 Hz, 20 Hz low-pass, 8 %, 0.5 s peak window).

    Returns
    -------
    dict
        ``frequency_hz``, ``log_decrement``, ``last_peak_time_s`` (None if the
        run has no peak), and ``first_peak_time_s`` (from the kick), ``fit``
        (the :class:`~whipple_kick.simulate.oscillation.OscillationFit`),
        ``raw_last_peak_time_s`` (the thesis' 8 % rule on the raw signal, from peak #1) and
        ``detrended_peaks`` (the rule on the signal less the fitted trend, over the fit's window:
        :class:`~whipple_kick.simulate.analysis.PeakSeries` on the input clock).
    """
    proc = experiments.load().processing if processing is None else processing
    t_rec, y_rec = analysis.as_recorded(t, yaw_rate, t_kick, proc["imu_rate"], proc["lowpass_cutoff"])
    y = y_rec - steady
    peaks = analysis.yaw_rate_peaks(t_rec, y, t_kick, proc["peak_threshold"])
    out = dict.fromkeys(FEATURE_UNITS)
    out.update(first_peak_time_s=None, fit=None, raw_last_peak_time_s=None, detrended_peaks=None)
    if not len(peaks):
        return out
    fit = oscillation.fit(t_rec, y, peaks.times[0], peaks.values[0], proc["peak_window"])
    out.update(frequency_hz=fit.frequency_hz, log_decrement=fit.log_decrement,
               last_peak_time_s=min(fit.envelope_time, ENVELOPE_CAP), fit=fit,
               first_peak_time_s=float(peaks.times[0] - t_kick),
               raw_last_peak_time_s=float(peaks.times[-1] - peaks.times[0]))
    # from the sample before peak #1 (the search skips a maximum on its first sample) to the window's end
    inside = (t_rec >= fit.t0 - 1.5 / proc["imu_rate"]) & (t_rec <= fit.t0 + proc["peak_window"] + 1e-9)
    tw = t_rec[inside]
    out["detrended_peaks"] = analysis.yaw_rate_peaks(tw, y[inside] - fit.trend(tw), tw[0], proc["peak_threshold"])
    return out


# ------------------------------------------------------------------------------------------------ simulators

#: The folder of a ``calibrate --out DIR`` that keeps the simulator's runs (a rerun resumes from it).
RUNS = "calibration_runs"


class ModelSimulator:
    """The kick model as a calibration simulator: ``sim(X) -> Y``.

    Each row of ``X`` (values of ``names``, the priors' fields) is run at every
    cell (load, pressure) through :func:`whipple_kick.studies.sweep_engine.sweep`
    (in parallel), with ``base`` (default :func:`whipple_kick.studies.validation.base_scenario`:
    2 m/s, the smooth 35 m/s^2 kick, cut to :data:`FEATURE_DURATION`) for the rest;
    ``Y`` holds :func:`model_features` in :func:`feature_keys` order, NaN where a
    run failed, fell or gave no peak. ``last_unstable`` says per row of the last
    call whether the rider was linearly unstable in any cell (the features look at
    the first second only and cannot see a rider that would not recover), and
    ``last_margin`` the largest real part of the slowest closed-loop pole over the
    cells [1/s] (:func:`whipple_kick.simulate.assembly.linear_stability`), which
    :func:`history_match` emulates to rule out surely unstable riders.
    """

    def __init__(self, fields, cells, features, base=None, workers=None, progress=False, folder=None):
        self.fields = list(fields)
        self.cells = [(float(a), float(b)) for a, b in cells]
        self.features = _check_features(features)
        self.base = validation.base_scenario(duration=FEATURE_DURATION) if base is None else base
        self.workers, self.progress = workers, progress
        # A sweep folder that keeps every run (one folder for every call: extended, never refused), so a
        # stopped calibration resumes without rerunning them; None: a temporary folder per call.
        self.folder = folder
        self.runs = 0

    def __call__(self, X):
        X = np.atleast_2d(np.asarray(X, dtype=float))
        cases = [{**dict(zip(self.fields, map(float, x), strict=True)), "fz_n": fz, "pressure_kpa": p}
                 for x in X for fz, p in self.cells]
        ids = [cid for _, _, cid in make_cases(cases=cases, base=self.base)]
        proc = experiments.load().processing
        Y = np.full((len(X), len(self.cells) * len(self.features)), np.nan)
        self.last_unstable = np.zeros(len(X), bool)
        self.last_margin = np.full(len(X), -np.inf)
        with contextlib.ExitStack() as stack:
            folder = self.folder if self.folder is not None else stack.enter_context(
                tempfile.TemporaryDirectory(prefix="whipple_kick_calibrate_"))
            table = sweep(cases=cases, base=self.base, folder=folder, workers=self.workers, progress=self.progress,
                          trajectory_columns=("time", "yaw_rate"), trajectory_dtype="float64", trajectory_rate=None,
                          extend=True)
            ok = {row["case_id"]: row["status"] == "ok" for _, row in table.iterrows()}
            for k, cid in enumerate(ids):
                if not ok.get(cid):
                    continue
                frame, summary = load_trajectory(folder, cid)
                i, c = divmod(k, len(self.cells))
                stability = summary.get("linear_stability", {})
                if not stability.get("stable", True):
                    self.last_unstable[i] = True
                if stability.get("slowest_pole_1_s"):
                    self.last_margin[i] = max(self.last_margin[i], float(stability["slowest_pole_1_s"][0]))
                if summary.get("fell"):
                    continue
                m = model_features(frame["time"].to_numpy(), frame["yaw_rate"].to_numpy(),
                                   float(summary["steady_state"]["yaw_rate_rad_s"]), processing=proc)
                for j, f in enumerate(self.features):
                    if m[f] is not None:
                        Y[i, c * len(self.features) + j] = m[f]
        self.last_margin[~np.isfinite(self.last_margin)] = np.nan
        self.runs += len(cases)
        return Y


class ToySimulator:
    """An analytic stand-in for the model with the same interface (for the fast known-answer test).

    Inputs: the first two or three priors' fields, mapped to the unit cube;
    per cell a smooth, monotone-enough response that depends on load and
    pressure, so that the features pin the inputs as the model's would:
    ``frequency = 4 + 3 u1 + 1.5 u2 (p/400) - 0.5 u3``,
    ``log_decrement = 0.4 + 1.2 u2 + 0.3 u1 u3 + 0.2 (fz - 635)/66``,
    ``last_peak = 0.25 + 0.3 (1 - u1) + 0.15 u3^2 + 0.05 (p - 400)/100``.
    With ``unstable_below`` its ``last_margin`` (the model's slowest pole, 1/s)
    is ``unstable_below - u1``: a rider unstable at low gains.
    """

    def __init__(self, prior_list, cells, features, unstable_below=None):
        self.priors = list(prior_list)
        self.cells = [(float(a), float(b)) for a, b in cells]
        self.features = _check_features(features)
        self.unstable_below = unstable_below
        self.runs = 0

    def __call__(self, X):
        X = np.atleast_2d(np.asarray(X, dtype=float))
        u = np.column_stack([(X[:, k] - p.low) / p.width for k, p in enumerate(self.priors)])
        u1, u2 = u[:, 0], u[:, 1]
        u3 = u[:, 2] if u.shape[1] > 2 else np.full(len(u), 0.5)
        cols = []
        for fz, p in self.cells:
            values = {"frequency_hz": 4 + 3 * u1 + 1.5 * u2 * (p / 400) - 0.5 * u3,
                      "log_decrement": 0.4 + 1.2 * u2 + 0.3 * u1 * u3 + 0.2 * (fz - 635) / 66,
                      "last_peak_time_s": 0.25 + 0.3 * (1 - u1) + 0.15 * u3 ** 2 + 0.05 * (p - 400) / 100}
            cols += [values[f] for f in self.features]
        self.runs += len(X) * len(self.cells)
        if self.unstable_below is not None:   # a stand-in for the rider's slowest pole: unstable where u1 is low
            self.last_margin = self.unstable_below - u1
            self.last_unstable = self.last_margin > UNSTABLE_REAL_PART
        return np.column_stack(cols)


# ------------------------------------------------------------------------------------------------ emulators

class Emulators:
    """One Gaussian-process emulator per output column (scikit-learn), on inputs scaled to the unit cube.

    Kernel: a constant times an anisotropic squared exponential (one length
    scale per input) plus a white-noise nugget, on standardised outputs
    (``normalize_y``); hyperparameters by maximum marginal likelihood with
    ``restarts`` restarts. A column with fewer than ``min_points`` finite
    values gets no emulator (its predictions are NaN and it drops out of
    the implausibility, with a note).
    """

    def __init__(self, restarts=1, seed=0, min_points=5):
        self.restarts, self.seed, self.min_points = restarts, seed, min_points
        self.models = []

    def fit(self, U, Y):
        """Fit every column of ``Y`` (n, m) on unit inputs ``U`` (n, d); returns self."""
        from sklearn.gaussian_process import GaussianProcessRegressor
        from sklearn.gaussian_process.kernels import RBF, ConstantKernel, WhiteKernel

        U, Y = np.asarray(U, float), np.asarray(Y, float)
        d = U.shape[1]
        self.models = []
        for j in range(Y.shape[1]):
            good = np.isfinite(Y[:, j])
            if np.count_nonzero(good) < self.min_points:
                self.models.append(None)
                continue
            kernel = (ConstantKernel(1.0, (1e-3, 1e3)) * RBF(np.full(d, 0.5), (1e-2, 1e2))
                      + WhiteKernel(1e-4, (1e-9, 1e-1)))
            gp = GaussianProcessRegressor(kernel, normalize_y=True, n_restarts_optimizer=self.restarts,
                                          random_state=self.seed)

            from sklearn.exceptions import ConvergenceWarning
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", ConvergenceWarning)
                gp.fit(U[good], Y[good, j])
            self.models.append(gp)
        return self

    def predict(self, U):
        """Means and variances (n, m) at unit inputs ``U`` (n, d).

        The fitted GP's own formulas (``GaussianProcessRegressor.predict`` with
        ``return_std``: the variance includes the nugget), without its input
        validation, which cost 0.2 ms a call, most of a sampler step.
        """
        U = np.atleast_2d(np.asarray(U, float))
        mean = np.full((len(U), len(self.models)), np.nan)
        var = np.full_like(mean, np.nan)
        for j, gp in enumerate(self.models):
            if gp is None:
                continue
            # kernel_ is constant * RBF(length scales) + White(noise): evaluated here in NumPy
            c, ls = gp.kernel_.k1.k1.constant_value, gp.kernel_.k1.k2.length_scale
            d2 = (((U[:, None, :] - gp.X_train_[None, :, :]) / ls) ** 2).sum(-1)
            K = c * np.exp(-0.5 * d2)
            v = solve_triangular(gp.L_, K.T, lower=True, check_finite=False)
            k_var = np.maximum(c + gp.kernel_.k2.noise_level - np.einsum("ij,ij->j", v, v), 0.0)
            mean[:, j] = gp._y_train_std * (K @ gp.alpha_) + gp._y_train_mean
            var[:, j] = gp._y_train_std ** 2 * k_var
        return mean, var


def held_out_errors(U, Y, emulators, folds=5, seed=0):
    """Standardised errors of emulators on runs they were not fitted to (k-fold).

    Each fold refits the GP to the other runs with the hyperparameters of
    ``emulators`` (fitted to all) held fixed, as Bastos & O'Hagan (2009,
    Technometrics 51(4)) do for their leave-one-out checks: re-optimising
    them per fold costs a marginal-likelihood search per fold and column.

    Returns
    -------
    ndarray (n, m)
        ``(y - E[f]) / sd_emulator`` for each run in its held-out fold (NaN where
        the run has no value or the column no emulator).
    """
    from sklearn.base import clone

    U, Y = np.asarray(U, float), np.asarray(Y, float)
    rng = np.random.default_rng(seed)
    order = rng.permutation(len(U))
    out = np.full(Y.shape, np.nan)
    for k in range(folds):
        test = order[k::folds]
        train = np.setdiff1d(order, test)
        for j, gp in enumerate(emulators.models):
            good = train[np.isfinite(Y[train, j])]
            if gp is None or len(good) < 2:
                continue
            fixed = clone(gp).set_params(kernel=gp.kernel_, optimizer=None)
            fixed.fit(U[good], Y[good, j])
            m, sd = fixed.predict(U[test], return_std=True)
            out[test, j] = (Y[test, j] - m) / sd
    return out


def implausibility(mean, var_emulator, z, var_observation):
    """``|z - E[f]| / sqrt(Var_emulator + Var_measurement + Var_discrepancy)`` per input and feature (n, m)."""
    return np.abs(z - mean) / np.sqrt(var_emulator + var_observation)


def ranked(I, rank):
    """The ``rank``-th largest implausibility per row, ignoring NaN columns (1 = the maximum)."""
    filled = np.where(np.isfinite(I), I, -np.inf)
    k = min(rank, I.shape[1])
    return np.sort(filled, axis=1)[:, -k]


# ------------------------------------------------------------------------------------------------ history matching

@dataclasses.dataclass
class Wave:
    """One wave of history matching."""

    number: int
    design: np.ndarray          # unit inputs run in this wave
    outputs: np.ndarray
    emulators: Emulators
    trained_on: int             # runs its emulators were fitted to
    held_out: np.ndarray        # standardised errors (k-fold) of its emulators
    nroy_fraction: float        # share of the prior volume not ruled out after this wave
    candidates: int             # prior-volume sample the fraction is estimated on
    stability: Emulators = None  # of the slowest closed-loop pole's real part, where the simulator gives it
    unstable_runs: int = 0      # runs of this wave whose rider was linearly unstable


class _Matcher:
    def __init__(self, z, var_obs, rank, cutoff):
        self.z, self.var_obs, self.rank, self.cutoff = z, var_obs, rank, cutoff
        self.waves = []

    def implausible(self, U, upto=None):
        """Boolean (n,): ruled out by any wave so far."""
        out = np.zeros(len(U), bool)
        for w in self.waves[:upto]:
            m, v = w.emulators.predict(U)
            out |= self.ruled_out(w, U, m, v)
        return out

    def ruled_out(self, wave, U, m, v):
        """Ruled out by one wave, given its feature emulators' predictions: implausible, or surely unstable
        (the emulated slowest pole's real part more than 3 emulator sd above the unstable limit)."""
        out = ranked(implausibility(m, v, self.z, self.var_obs), self.rank) > self.cutoff
        if wave.stability is not None:
            ms, vs = wave.stability.predict(U)
            out |= ms[:, 0] - 3.0 * np.sqrt(vs[:, 0]) > UNSTABLE_REAL_PART
        return out


def _lhs(n, d, rng):
    return qmc.LatinHypercube(d=d, seed=rng).random(n)


def _inside(matcher, d, want, rng, pool=None, tries=40):
    """``want`` unit points not ruled out: drawn in the box around ``pool`` (or the cube), rejected by the waves."""
    lo, hi = np.zeros(d), np.ones(d)
    if pool is not None and len(pool):
        pad = 0.1 * np.maximum(pool.max(0) - pool.min(0), 0.05)
        lo, hi = np.clip(pool.min(0) - pad, 0, 1), np.clip(pool.max(0) + pad, 0, 1)
    kept = []
    for _ in range(tries):
        U = lo + _lhs(max(4 * want, 2000), d, rng) * (hi - lo)
        U = U[~matcher.implausible(U)]
        kept.append(U)
        if sum(len(k) for k in kept) >= want:
            break
    U = np.concatenate(kept) if kept else np.empty((0, d))
    return U[:want] if len(U) > want else U


def history_match(simulator, prior_list, z, var_observation, waves=2, first=None, per_wave=None, rank=None,
                  cutoff=CUTOFF, candidates=20000, seed=0):
    """History matching in waves (module docstring, step 2).

    Parameters
    ----------
    simulator : callable
        ``simulator(X) -> Y``, X in the priors' units.
    prior_list : list of Prior
    z, var_observation : ndarray (m,)
        Measured features and their measurement + discrepancy variances.
    waves : int
    first, per_wave : int, optional
        Runs of the first wave (default ``10 d``, Loeppky et al. 2009's rule of
        thumb) and of each later wave (default ``5 d``).
    rank : int, optional
        Which largest implausibility decides (default 2; 1 with fewer than 3 features).
    cutoff : float
    candidates : int
        Uniform prior sample on which the non-implausible fraction is estimated.

    Returns
    -------
    list of Wave, the matcher (``.implausible(U)``), all unit inputs run, all outputs, and the
    non-implausible candidates (unit) after the last wave.
    """
    d = len(prior_list)
    rng = np.random.default_rng(seed)
    rank = (2 if len(z) >= 3 else 1) if rank is None else int(rank)
    first = 10 * d if first is None else int(first)
    per_wave = 5 * d if per_wave is None else int(per_wave)
    low = np.array([p.low for p in prior_list])
    width = np.array([p.width for p in prior_list])
    matcher = _Matcher(np.asarray(z, float), np.asarray(var_observation, float), rank, cutoff)
    probe = _lhs(candidates, d, rng)
    U_all, Y_all, G_all = np.empty((0, d)), np.empty((0, len(z))), np.empty(0)
    survivors = probe
    for k in range(waves):
        if k == 0:
            design = _lhs(first, d, rng)
        else:
            design = _inside(matcher, d, per_wave, rng, pool=survivors)
            if len(design) < max(2, d):
                break
        Y = np.atleast_2d(simulator(low + design * width))
        margin = getattr(simulator, "last_margin", None)
        G_all = np.concatenate([G_all, np.full(len(design), np.nan) if margin is None else margin])
        U_all, Y_all = np.vstack([U_all, design]), np.vstack([Y_all, Y])
        train = ~matcher.implausible(U_all) if k else np.ones(len(U_all), bool)
        if np.count_nonzero(train) < 2 * d + 2:
            train = np.ones(len(U_all), bool)
        em = Emulators(seed=seed).fit(U_all[train], Y_all[train])
        held = held_out_errors(U_all[train], Y_all[train], em, folds=min(5, int(np.count_nonzero(train))), seed=seed)
        stab = (Emulators(seed=seed).fit(U_all[train], G_all[train, None])
                 if np.count_nonzero(np.isfinite(G_all[train])) >= 5 else None)
        unstable = int(np.count_nonzero(G_all[-len(design):] > UNSTABLE_REAL_PART))
        matcher.waves.append(Wave(k + 1, design, Y, em, int(np.count_nonzero(train)), held, math.nan, candidates,
                                  stab, unstable))
        survivors = probe[~matcher.implausible(probe)]
        matcher.waves[-1].nroy_fraction = len(survivors) / len(probe)
        if not len(survivors):
            break
    return matcher.waves, matcher, U_all, Y_all, survivors


# ------------------------------------------------------------------------------------------------ posterior

def split_rhat(chain):
    """Split R-hat per parameter of ``chain`` (steps, walkers, d) (Gelman et al. 2013, BDA3 eq. 11.4)."""
    n = chain.shape[0] // 2
    halves = np.concatenate([chain[:n], chain[n:2 * n]], axis=1)   # (n, 2 walkers, d)
    means = halves.mean(0)
    B = n * means.var(0, ddof=1)
    W = halves.var(0, ddof=1).mean(0)
    var = (n - 1) / n * W + B / n
    return np.sqrt(var / W)


def posterior(matcher, emulators, z, var_observation, d, start, walkers=32, steps=2000, burn=None, seed=0):
    """Sample the posterior on the emulators inside the non-implausible region (module docstring, step 3).

    Parameters
    ----------
    matcher : the history match's (rules out what any wave rules out)
    emulators : Emulators
        The last wave's.
    z, var_observation : ndarray (m,)
    d : int
        Number of inputs (unit cube).
    start : ndarray (k, d)
        Non-implausible unit points to start the walkers from.
    walkers, steps, burn : int
        Ensemble size, steps, and steps discarded (default a quarter).

    Returns
    -------
    dict
        ``samples`` (unit, (n, d), after burn-in, thinned by half the largest
        autocorrelation time), ``tau`` (d,), ``rhat`` (d,), ``ess`` (d,),
        ``acceptance``, ``chain`` (steps, walkers, d).
    """
    import emcee

    z, var_obs = np.asarray(z, float), np.asarray(var_observation, float)
    rng = np.random.default_rng(seed)
    walkers = max(int(walkers), 2 * d + 2)
    burn = steps // 4 if burn is None else int(burn)

    def log_prob(U):
        U = np.atleast_2d(U)
        out = np.full(len(U), -np.inf)
        inside = np.all((U >= 0) & (U <= 1), axis=1)
        if np.any(inside):
            ok = np.flatnonzero(inside)
            ok = ok[~matcher.implausible(U[ok], upto=-1)]   # the earlier waves; the last one below
            m, v = emulators.predict(U[ok])
            keep = ~matcher.ruled_out(matcher.waves[-1], U[ok], m, v)
            ok, m, v = ok[keep], m[keep], v[keep]
            if len(ok):
                V = v + var_obs
                r2 = (z - m) ** 2 / V
                use = np.isfinite(r2)
                out[ok] = -0.5 * np.sum(np.where(use, r2 + np.log(np.where(use, V, 1.0)), 0.0), axis=1)
        return out

    p0 = start[rng.choice(len(start), walkers, replace=len(start) < walkers)]
    p0 = np.clip(p0 + 1e-3 * rng.standard_normal(p0.shape), 1e-6, 1 - 1e-6)
    sampler = emcee.EnsembleSampler(walkers, d, log_prob, vectorize=True)
    # emcee draws its moves from a NumPy RandomState: seeded, the chain repeats
    sampler.random_state = np.random.RandomState(seed).get_state()
    sampler.run_mcmc(p0, steps, progress=False)
    chain = sampler.get_chain()[burn:]
    tau = np.asarray(emcee.autocorr.integrated_time(chain, quiet=True))
    thin = max(1, int(np.nanmax(tau) / 2))
    samples = chain[::thin].reshape(-1, d)
    return {"samples": samples, "tau": tau, "rhat": split_rhat(chain),
            "ess": chain.shape[0] * chain.shape[1] / tau, "acceptance": float(np.mean(sampler.acceptance_fraction)),
            "chain": chain, "steps": steps, "burn": burn, "walkers": walkers, "thin": thin}


# ------------------------------------------------------------------------------------------------ the calibration

@dataclasses.dataclass
class Calibration:
    """Result of :func:`calibrate`.

    Attributes
    ----------
    priors : list of Prior
    measured : pandas.DataFrame
        :func:`measured_features`' rows (or the synthetic ones).
    waves : list of Wave
    posterior : pandas.DataFrame or None
        Samples of the inputs (priors' units); None when nothing survives.
    features : pandas.DataFrame
        Per feature key: measured, errors, the posterior predictive (emulator) mean and 5-95 %,
        the implausibility at the posterior mean, the smallest implausibility over the candidates.
    checks : pandas.DataFrame
        ``check, name, value, detail``: emulator held-out errors, non-implausible fractions, chain
        diagnostics, unsourced values, the finding when nothing survives.
    verdict : list of str
    chain : dict
        :func:`posterior`'s, or None.
    settings : dict
        What the posterior is conditional on (:func:`settings`; ``settings.json``).
    held_out : pandas.DataFrame or None
        :func:`held_out`'s rows (``held_out.csv``), where asked for.
    """

    priors: list
    measured: object
    waves: list
    posterior: object
    features: object
    checks: object
    verdict: list
    chain: dict = None
    settings: dict = None
    held_out: object = None

    def interval(self, name, level=0.90):
        """Central credible interval of one input (priors' units)."""
        q = (1 - level) / 2
        x = self.posterior[name].to_numpy()
        return float(np.quantile(x, q)), float(np.quantile(x, 1 - q))

    def write(self, folder):
        """``posterior.csv``, ``features.csv``, ``checks.csv`` and ``verdict.txt`` into ``folder``; the paths."""
        folder = pathlib.Path(folder)
        folder.mkdir(parents=True, exist_ok=True)
        post = self.posterior if self.posterior is not None else pd.DataFrame(columns=[p.name for p in self.priors])
        paths = []
        tables = [("posterior", post), ("features", self.features), ("checks", self.checks)]
        if self.held_out is not None:
            tables.append(("held_out", self.held_out))
        for name, frame in tables:
            path = folder / f"{name}.csv"
            fileio.write_atomic(path, frame.to_csv(index=False))
            paths.append(path)
        if self.settings is not None:
            path = folder / SETTINGS_FILE
            fileio.write_atomic(path, json.dumps(self.settings, indent=1) + "\n")
            paths.append(path)
        path = folder / "verdict.txt"
        fileio.write_atomic(path, "\n".join(self.verdict) + "\n")
        return paths + [path]


#: Screening: an input is active when changing it over its whole prior range moves some feature, on average
#: over the Morris trajectories (mu*), by at least this many of that feature's standard deviations (measurement
#: and discrepancy): below, the measurements cannot tell its values apart, and calibrating it adds a dimension
#: the data do not inform.
SCREEN_THRESHOLD = 0.5


def screen(simulator, prior_list, sd, keys, trajectories=4, levels=4, seed=0):
    """Morris elementary-effects screening of the inputs on the features (SALib), before history matching.

    Parameters
    ----------
    simulator : callable
        ``simulator(X) -> Y`` as for :func:`calibrate`, its columns ``keys``.
    prior_list : list of Prior
        The candidate inputs and their ranges (the design is on their unit cube).
    sd : array
        Each feature's standard deviation (measurement and discrepancy), in ``keys`` order.
    trajectories, levels, seed : int
        Morris' trajectories ``r`` (``r (D + 1)`` simulator rows), grid levels and seed.

    Returns
    -------
    pandas.DataFrame
        Per input: ``input``, ``mu_star_sd`` (the largest over the features of mu* / sd: the mean absolute
        change of a feature across the input's whole range, in that feature's sd), ``feature`` (where it is
        largest), ``sigma_sd`` (that feature's spread of the effects, in sd: interactions or nonlinearity),
        ``active`` (``mu_star_sd >= SCREEN_THRESHOLD``), ``rows`` (simulator rows), ``rows_without_value`` (rows where some
        feature had no value; their cells take the feature's mean over the design so the effects stay defined).
    """
    from SALib.analyze import morris as morris_analyze
    from SALib.sample import morris as morris_sample

    names = [p.name for p in prior_list]
    problem = {"num_vars": len(names), "names": names, "bounds": [[0.0, 1.0]] * len(names)}
    U = morris_sample.sample(problem, int(trajectories), num_levels=int(levels), seed=int(seed))
    low = np.array([p.low for p in prior_list])
    width = np.array([p.width for p in prior_list])
    Y = np.asarray(simulator(low + U * width), float)
    missing = ~np.isfinite(Y)
    best = dict.fromkeys(names, (0.0, None, 0.0))
    for j, key in enumerate(keys):
        y = Y[:, j]
        if missing[:, j].all():
            continue
        y = np.where(missing[:, j], np.nanmean(y), y)
        res = morris_analyze.analyze(problem, U, y, num_levels=int(levels), seed=int(seed))
        for n, mu_star, sigma in zip(names, res["mu_star"], res["sigma"], strict=True):
            value = float(mu_star) / float(sd[j])
            if value > best[n][0]:
                best[n] = (value, key, float(sigma) / float(sd[j]))
    return pd.DataFrame([{"input": n, "mu_star_sd": v, "feature": k, "sigma_sd": sig,
                          "active": bool(v >= SCREEN_THRESHOLD), "rows": int(len(U)),
                          "rows_without_value": int(missing.any(axis=1).sum())}
                         for n, (v, k, sig) in best.items()])


def screen_inputs(spec=priors.DEFAULT, inputs=None, cells=None, features=None, base=None, workers=None,
                  progress=False, trajectories=4, seed=0, runs=None, simulator=None):
    """:func:`screen` on the kick model (or ``simulator``) for the file's priors ``inputs`` (default every
    prior the rigid rider reads: all but ``hip_stiffness``); the features' sd from the file."""
    spec = _spec(spec)
    names = [n for n in spec.priors if n != "hip_stiffness"] if inputs is None else list(inputs)
    prior_list, table, _, _, simulator = _problem(spec, names, None, features, cells, None, simulator, base, workers,
                                                  progress, runs)
    sd = np.sqrt(table["sd_measurement"].to_numpy() ** 2 + table["sd_discrepancy"].to_numpy() ** 2)
    return screen(simulator, prior_list, sd, list(table["key"]), trajectories=trajectories, seed=seed)


def _spec(spec):
    """``spec`` as a :class:`~whipple_kick.library.priors.CalibrationSpec` (a path or name is loaded)."""
    return spec if isinstance(spec, priors.CalibrationSpec) else priors.load(spec)


def _problem(spec, inputs, bounds, features, cells, discrepancy, simulator, base, workers, progress, runs):
    """What screening and calibrating share: the priors of ``inputs`` (:func:`choose_priors`), the measured
    features' table (:func:`measured_features`), its cells and features in order, and the simulator over them
    (default a :class:`ModelSimulator` on ``base``): ``(priors, table, cells, features, simulator)``."""
    prior_list = choose_priors(spec, inputs, bounds)
    table = measured_features(spec, features=features, cells=cells, discrepancy=discrepancy)
    cells = list(dict.fromkeys(zip(table["fz_n"], table["pressure_kpa"], strict=True)))
    features = list(dict.fromkeys(table["feature"]))
    if simulator is None:
        simulator = ModelSimulator([p.field for p in prior_list], cells, features, base, workers, progress, runs)
    return prior_list, table, cells, features, simulator


def _with_measured(table, measured):
    """``table`` with its measured values replaced by ``measured`` (in its row order; None: as it is)."""
    if measured is None:
        return table
    measured = np.asarray(measured, float)
    if measured.shape != (len(table),):
        raise InputError(f"measured values: {measured.size} given, {len(table)} features expected")
    return table.assign(measured=measured)


def choose_priors(spec, inputs=None, bounds=None):
    """The priors of ``inputs`` (names in the file; default all but ``hip_stiffness`` and ``speed``), with
    ``bounds = {name: (low, high)}`` overriding (checked; an override is marked unsourced)."""
    spec = _spec(spec)
    names = [n for n in spec.priors if n not in ("hip_stiffness", "speed")] if inputs is None else list(inputs)
    unknown = [n for n in names if n not in spec.priors]
    if unknown or not names:
        raise InputError(f"input(s) {', '.join(map(repr, unknown)) or '(none)'} have no prior in {spec.path}; "
                         f"it has {', '.join(spec.priors)}")
    out = []
    for n in names:
        p = spec.priors[n]
        if bounds and n in bounds:
            lo, hi = bounds[n]
            p = priors.prior(n, p.field, lo, hi, p.unit, "given (override of the file's range)", sourced=False)
        out.append(p)
    return out


def calibrate(simulator=None, spec=priors.DEFAULT, inputs=None, bounds=None, features=None, cells=None,
              discrepancy=None, measured=None, base=None, waves=2, first=None, per_wave=None, rank=None,
              walkers=32, steps=2000, candidates=20000, seed=0, workers=None, progress=False, check_runs=0,
              runs=None):
    """History-match and calibrate (module docstring).

    Parameters
    ----------
    simulator : callable, optional
        ``simulator(X) -> Y``; default :class:`ModelSimulator` on ``base``.
    spec : str, path or CalibrationSpec
    inputs : list of str, optional
        Prior names to calibrate (:func:`choose_priors`).
    bounds : dict, optional
        ``{name: (low, high)}`` overriding the file's ranges (checked).
    features, cells : optional
        :func:`measured_features`' (default every feature and measured cell).
    discrepancy : dict, optional
        ``{feature: sd}`` (checked: > 0).
    measured : array_like, optional
        Values replacing the measured ones (e.g. synthetic), in :func:`feature_keys` order.
    waves, first, per_wave, rank, candidates : see :func:`history_match`.
    walkers, steps : see :func:`posterior`.
    check_runs : int
        Posterior draws run on the simulator itself (``posterior_runs_*`` rows of the checks).
    runs : path, optional
        A sweep folder that keeps the default simulator's runs: a stopped calibration run again with the
        same arguments reruns none of them (calibrate --out DIR keeps them in DIR/calibration_runs).

    Returns
    -------
    Calibration
    """
    import sklearn.gaussian_process  # noqa: F401

    # One BLAS thread: the GP matrices are at most a few hundred rows; on a shared 2-core machine OpenBLAS'
    # threads made each Cholesky solve 2-3 ms instead of well under 1 ms (the sweep engine limits its runs alike).
    with threadpool_limits(limits=1):
        return _calibrate(simulator, spec, inputs, bounds, features, cells, discrepancy, measured, base, waves,
                          first, per_wave, rank, walkers, steps, candidates, seed, workers, progress, check_runs,
                          runs)


def _calibrate(simulator, spec, inputs, bounds, features, cells, discrepancy, measured, base, waves, first,
               per_wave, rank, walkers, steps, candidates, seed, workers, progress, check_runs, runs=None):
    spec = _spec(spec)
    prior_list, table, cells, features, simulator = _problem(spec, inputs, bounds, features, cells, discrepancy,
                                                             simulator, base, workers, progress, runs)
    table = _with_measured(table, measured)
    z = table["measured"].to_numpy()
    var_obs = table["sd_measurement"].to_numpy() ** 2 + table["sd_discrepancy"].to_numpy() ** 2
    wave_list, matcher, U_all, Y_all, survivors = history_match(
        simulator, prior_list, z, var_obs, waves, first, per_wave, rank, CUTOFF, candidates, seed)
    d = len(prior_list)
    low = np.array([p.low for p in prior_list])
    width = np.array([p.width for p in prior_list])
    names = [p.name for p in prior_list]
    checks = _checks(spec, prior_list, wave_list, table)
    last = wave_list[-1]
    probe_m, probe_v = last.emulators.predict(_lhs(min(candidates, 5000), d, np.random.default_rng(seed + 1)))
    min_I = np.nanmin(implausibility(probe_m, probe_v, z, var_obs), axis=0)
    post, chain, verdict = None, None, []
    feats = table[["key", "cell", "feature", "unit", "measured", "sd_measurement", "sd_discrepancy"]].copy()
    feats["min_implausibility_prior"] = min_I
    if len(survivors) >= 2:
        chain = posterior(matcher, last.emulators, z, var_obs, d, survivors, walkers, steps, seed=seed)
        U = chain["samples"]
        post = pd.DataFrame(low + U * width, columns=names)
        m, v = last.emulators.predict(U[np.random.default_rng(seed).choice(len(U), min(len(U), 400), replace=False)])
        draw = m + np.sqrt(v + var_obs) * np.random.default_rng(seed + 2).standard_normal(m.shape)
        feats["predicted_mean"] = np.nanmean(m, axis=0)
        feats["predictive_5"] = np.nanquantile(draw, 0.05, axis=0)
        feats["predictive_95"] = np.nanquantile(draw, 0.95, axis=0)
        mm, vv = last.emulators.predict(U.mean(0, keepdims=True))
        feats["implausibility_at_posterior_mean"] = implausibility(mm, vv, z, var_obs)[0]
        for k, n in enumerate(names):
            checks.append(("mcmc_tau", n, float(chain["tau"][k]), f"integrated autocorrelation time [steps]; "
                                                                   f"{chain['steps']} steps, {chain['walkers']} walkers, burn {chain['burn']}"))
            checks.append(("mcmc_rhat", n, float(chain["rhat"][k]), "split R-hat over half-chains of the walkers"))
            checks.append(("mcmc_ess", n, float(chain["ess"][k]), "effective samples after burn-in"))
        checks.append(("mcmc_acceptance", "", chain["acceptance"], "mean acceptance fraction (0.2-0.5 is healthy)"))
        if check_runs:
            rows, Y_runs = _posterior_runs(simulator, U, low, width, last.emulators, z, var_obs, matcher.rank,
                                           int(check_runs), seed)
            checks += rows
            feats = feats.assign(**_simulator_predictive(Y_runs, z, var_obs, seed))
        short = chain["steps"] - chain["burn"] < 50 * float(np.max(chain["tau"]))
        if short:
            checks.append(("mcmc_warning", "", float(np.max(chain["tau"])),
                           "chain shorter than 50 autocorrelation times after burn-in (emcee's advice)"))
        for k, n in enumerate(names):
            lo, hi = np.quantile(post[n], [0.05, 0.95])
            p = prior_list[k]
            edge = {"low": float(np.mean(U[:, k] < EDGE_SHARE)), "high": float(np.mean(U[:, k] > 1 - EDGE_SHARE))}
            side = max(edge, key=edge.get)
            piled = edge[side] > EDGE_PILE
            if piled:
                checks.append(("posterior_at_bound", n, edge[side],
                               f"share of the posterior within {EDGE_SHARE:.0%} of the prior's {side} bound "
                               f"({p.low if side == 'low' else p.high:g} {p.unit}): the data ask for values at or "
                               "beyond it"))
            verdict.append(f"{n}: 90 % credible interval {lo:.4g}-{hi:.4g} {p.unit} (prior {p.low:g}-{p.high:g})"
                           + (f"; {edge[side]:.0%} of it within {EDGE_SHARE:.0%} of the {side} bound: the data "
                              "ask for values at or beyond it" if piled else ""))
    else:
        bad = [f"{k} (min I {i:.1f})" for k, i in zip(table["key"], min_I, strict=True) if i > CUTOFF]
        verdict.append("no input in the prior reproduces the measured features at once "
                       f"(rank-{_rank(rank, len(z))} implausibility > {CUTOFF:g} everywhere after wave {last.number}); "
                       f"unmatched features: {', '.join(bad) or 'none alone: only in combination'}")
        checks.append(("finding", "no_plausible_input", 0.0, verdict[-1]))
    verdict.insert(0, "non-implausible share of the prior after each wave: "
                      + ", ".join(f"{w.nroy_fraction:.3g}" for w in wave_list)
                      + f" ({sum(len(w.design) for w in wave_list)} simulator points)")
    frame = pd.DataFrame(checks, columns=["check", "name", "value", "detail"])
    return Calibration(prior_list, table, wave_list, post, feats, frame, verdict, chain,
                       settings(prior_list, base, cells, features, spec))


def settings(prior_list, base, cells, features, spec):
    """What a posterior is conditional on, as plain data (``settings.json``): each posterior column's scenario
    field, the modelling choices of the runs (:data:`CHOICE_FIELDS`, never pooled: the posterior of one rider
    model or kick direction is not another's), the cells and features, the calibration file."""
    base = validation.base_scenario(duration=FEATURE_DURATION) if base is None else base
    return {"format": SETTINGS_FORMAT, "fields": {p.name: p.field for p in prior_list},
            "choices": {f: getattr(base, f) for f in CHOICE_FIELDS},
            "cells": [list(c) for c in cells], "features": list(features), "spec": str(spec.path)}


def _posterior_runs(simulator, U, low, width, emulators, z, var_obs, rank, n, seed):
    """Run the simulator itself at ``n`` posterior draws: is the emulator right there, and do the runs match?"""
    pick = U[np.random.default_rng(seed + 3).choice(len(U), min(n, len(U)), replace=False)]
    Y = np.atleast_2d(simulator(low + pick * width))
    m, v = emulators.predict(pick)
    err = (Y - m) / np.sqrt(v)
    finite = np.isfinite(err)
    I_run = ranked(np.abs(z - Y) / np.sqrt(var_obs), rank)
    rows = [("posterior_runs_emulator", "", float(np.mean(np.abs(err[finite]) <= 3)) if finite.any() else math.nan,
             f"share of the simulator's features at {len(pick)} posterior draws within +-3 emulator sd of the "
             f"emulator ({int(finite.sum())} values)"),
            ("posterior_runs_non_implausible", "", float(np.mean(I_run <= CUTOFF)),
             f"share of {len(pick)} posterior draws whose simulator runs pass the implausibility cut "
             f"(rank {rank}, without emulator variance)")]
    unstable = getattr(simulator, "last_unstable", None)
    if unstable is not None:
        rows.append(("posterior_runs_unstable_rider", "", float(np.mean(unstable)),
                     f"share of {len(pick)} posterior draws with a linearly unstable rider in some cell (the "
                     "features cannot see it: they end 1 s after the kick)"))
    return rows, Y


def _simulator_predictive(Y, z, var_obs, seed):
    """Columns of the posterior predictive from the simulator's own runs at posterior draws ``Y`` (n, m).

    Each run's feature plus the measurement's and the discrepancy's noise (the predictive of a new
    measurement); the standardised error ``(z - mean) / sqrt(Var_runs + Var_measurement + Var_discrepancy)``.
    A feature no run gives (every run fell or had no peak) keeps ``simulator_runs`` 0 and no interval (the
    feature is left out, not set to a number).
    """
    Y = np.atleast_2d(np.asarray(Y, float))
    rng = np.random.default_rng(seed + 4)
    out = {k: np.full(Y.shape[1], np.nan) for k in ("simulator_mean", "simulator_5", "simulator_95",
                                                   "simulator_standardised_error")}
    runs = np.isfinite(Y).sum(axis=0)
    for j in np.flatnonzero(runs):
        y = Y[np.isfinite(Y[:, j]), j]
        # 200 noise draws per run: the interval's quantiles from the mixture, not from a handful of runs
        draw = (y[:, None] + math.sqrt(var_obs[j]) * rng.standard_normal((len(y), 200))).ravel()
        out["simulator_mean"][j] = y.mean()
        out["simulator_5"][j], out["simulator_95"][j] = np.quantile(draw, [0.05, 0.95])
        var_runs = y.var(ddof=1) if len(y) > 1 else 0.0
        out["simulator_standardised_error"][j] = (z[j] - y.mean()) / math.sqrt(var_runs + var_obs[j])
    return {"simulator_runs": pd.array(runs, dtype="int64"), **out}


def _rank(rank, m):
    return (2 if m >= 3 else 1) if rank is None else int(rank)


def _checks(spec, prior_list, wave_list, table):
    rows = []
    for w in wave_list:
        errs = w.held_out
        finite = np.isfinite(errs)
        share = float(np.mean(np.abs(errs[finite]) <= 3)) if finite.any() else math.nan
        rows.append(("emulator_held_out", f"wave {w.number}", share,
                     f"share of k-fold held-out standardised errors within +-3 ({int(finite.sum())} errors, "
                     f"{w.trained_on} runs)"))
        per = np.nanmean(np.abs(errs) <= 3, axis=0) if finite.any() else []
        for key, s in zip(table["key"], per, strict=False):
            rows.append(("emulator_held_out_feature", f"wave {w.number} {key}", float(s), "share within +-3"))
        if w.stability is not None:
            rows.append(("unstable_runs", f"wave {w.number}", w.unstable_runs,
                         f"of {len(w.design)} design points had a linearly unstable rider in some cell; surely "
                         "unstable inputs (emulated slowest pole's real part - 3 sd > 0.001 1/s) are ruled out"))
        rows.append(("non_implausible_fraction", f"wave {w.number}", w.nroy_fraction,
                     f"share of {w.candidates} uniform prior points not ruled out by waves 1-{w.number}"))
    for kind, name, reason in spec.unsourced():
        if kind != "prior" or name in [p.name for p in prior_list]:
            rows.append(("unsourced", f"{kind} {name}", math.nan, reason))
    for p in prior_list:
        if p.name not in spec.priors:
            rows.append(("unsourced", f"prior {p.name}", math.nan, p.reason))
    return rows


def known_answer(simulator_factory, prior_list, truth_unit, noise_scale=1.0, seed=0, **options):
    """Synthesise measurements at a known input and calibrate on them.

    Parameters
    ----------
    simulator_factory : callable
        ``factory(prior_list, cells, features) -> simulator``.
    prior_list : list of Prior
    truth_unit : array_like (d,)
        The true input on the unit cube.
    noise_scale : float
        Noise added to the synthetic measurement, in units of the stated
        measurement standard deviation (1: the stated noise).
    **options
        Passed to :func:`calibrate` (``features``, ``cells``, ``discrepancy``, ``waves`` ...).

    Returns
    -------
    (Calibration, truth in the priors' units, covered: dict name -> bool of the 90 % interval)
    """
    spec = priors.load(options.pop("spec", priors.DEFAULT))
    table = measured_features(spec, features=options.get("features"), cells=options.get("cells"),
                              discrepancy=options.get("discrepancy"))
    features = list(dict.fromkeys(table["feature"]))
    cells = list(dict.fromkeys(zip(table["fz_n"], table["pressure_kpa"], strict=True)))
    sim = simulator_factory(prior_list, cells, features)
    truth = np.array([p.low + u * p.width for p, u in zip(prior_list, truth_unit, strict=True)])
    clean = sim(truth[None, :])[0]
    rng = np.random.default_rng(seed + 1000)
    synthetic = clean + noise_scale * table["sd_measurement"].to_numpy() * rng.standard_normal(len(clean))
    bounds = {p.name: (p.low, p.high) for p in prior_list
              if (p.low, p.high) != (spec.priors[p.name].low, spec.priors[p.name].high)}
    result = calibrate(sim, spec, [p.name for p in prior_list], bounds or None, measured=synthetic, seed=seed,
                       **options)
    covered = {}
    if result.posterior is not None:
        for p, x in zip(prior_list, truth, strict=True):
            lo, hi = result.interval(p.name)
            covered[p.name] = bool(lo <= x <= hi)
    return result, truth, covered


# ------------------------------------------------------------------------------------------------ held-out checks

def held_out(mode, simulator_factory, spec=priors.DEFAULT, inputs=None, bounds=None, features=None, cells=None,
             discrepancy=None, measured=None, direction="right", draws=8, seed=0, fitted=None, **options):
    """Calibrate on part of the measurements and predict the rest with the simulator at posterior draws.

    Parameters
    ----------
    mode : {"load", "direction"}
        ``load``: per measured rear load, calibrate on the cells of the other loads and predict that
        load's cells. ``direction``: calibrate with the model kicked to ``direction`` and predict every
        cell with the model kicked the other way (the thesis gives no direction: the measurements are
        the same, the model's runs are not).
    simulator_factory : callable
        ``factory(prior_list, cells, features, direction) -> simulator``.
    spec, inputs, bounds, features, cells, discrepancy, measured
        As :func:`calibrate` (``measured`` in the order of every cell's features).
    direction : str
        The kick direction the calibration runs with.
    draws : int
        Posterior draws run on the simulator at the predicted cells.
    fitted : Calibration, optional
        A calibration on every cell at ``direction`` (``mode="direction"`` predicts from it instead of
        calibrating again).
    **options
        Passed to :func:`calibrate` (``waves``, ``steps`` ...).

    Returns
    -------
    pandas.DataFrame
        One row per predicted feature: ``mode, held_out, key, cell, feature, unit, measured, sd_observation``
        (measurement and discrepancy), ``predicted_mean, predictive_5, predictive_95`` (the runs plus the
        observation noise), ``standardised_error`` (``(measured - mean) / sqrt(Var_runs + sd_observation^2)``),
        ``runs`` (draws that gave the feature). A calibration that leaves nothing plausible predicts nothing:
        its rows say so in ``held_out`` with ``runs`` 0.
    """
    if mode not in HELD_OUT:
        raise InputError(f"held-out check {mode!r} unknown: choose {' or '.join(HELD_OUT)}")
    if direction not in DIRECTIONS:
        raise InputError(f"kick direction {direction!r} unknown: choose {' or '.join(DIRECTIONS)}")
    draws = int(draws)
    if draws < 2:
        raise InputError(f"held-out draws = {draws} must be a whole number >= 2 (a predictive spread needs two)")
    spec = _spec(spec)
    prior_list = choose_priors(spec, inputs, bounds)
    table = _with_measured(measured_features(spec, features=features, cells=cells, discrepancy=discrepancy), measured)
    features = list(dict.fromkeys(table["feature"]))
    cells = list(dict.fromkeys(zip(table["fz_n"], table["pressure_kpa"], strict=True)))
    if mode == "load":
        loads = list(dict.fromkeys(fz for fz, _ in cells))
        if len(loads) < 2:
            raise InputError(f"held-out load: the cells hold one load ({loads[0]:g} N); leaving it out leaves "
                             "nothing to calibrate on")
        groups = [(f"without {fz:g} N", [c for c in cells if c[0] != fz], [c for c in cells if c[0] == fz],
                   direction) for fz in loads]
    else:
        other = next(d for d in DIRECTIONS if d != direction)
        groups = [(f"calibrated kicking {direction}, predicted kicking {other}", cells, cells, other)]
    names = [p.name for p in prior_list]
    file_bounds = {p.name: (p.low, p.high) for p in prior_list
                   if p.name in spec.priors and (p.low, p.high) != (spec.priors[p.name].low, spec.priors[p.name].high)}
    rows = []
    for label, train, test, predict_direction in groups:
        in_train = table["cell"].isin([experiments.case_name(*c) for c in train]).to_numpy()
        if fitted is not None and train == cells:
            result = fitted
        else:
            result = calibrate(simulator_factory(prior_list, train, features, direction), spec, names,
                               file_bounds or None, features, train, discrepancy,
                               measured=table["measured"].to_numpy()[in_train], seed=seed, **options)
        te = table[table["cell"].isin([experiments.case_name(*c) for c in test])]
        var_obs = te["sd_measurement"].to_numpy() ** 2 + te["sd_discrepancy"].to_numpy() ** 2
        base = {"mode": mode, "held_out": label}
        if result.posterior is None:
            rows += [{**base, "key": k, "runs": 0, "held_out": f"{label}: nothing plausible to predict from"}
                     for k in te["key"]]
            continue
        post = result.posterior[names].to_numpy()
        pick = post[np.random.default_rng(seed + 5).choice(len(post), min(draws, len(post)), replace=False)]
        Y = np.atleast_2d(simulator_factory(prior_list, test, features, predict_direction)(pick))
        pred = _simulator_predictive(Y, te["measured"].to_numpy(), var_obs, seed)
        for j, (_, r) in enumerate(te.iterrows()):
            rows.append({**base, "key": r["key"], "cell": r["cell"], "feature": r["feature"], "unit": r["unit"],
                         "measured": r["measured"], "sd_observation": math.sqrt(var_obs[j]),
                         "predicted_mean": pred["simulator_mean"][j], "predictive_5": pred["simulator_5"][j],
                         "predictive_95": pred["simulator_95"][j],
                         "standardised_error": pred["simulator_standardised_error"][j],
                         "runs": int(pred["simulator_runs"][j])})
    return pd.DataFrame(rows, columns=["mode", "held_out", "key", "cell", "feature", "unit", "measured",
                                       "sd_observation", "predicted_mean", "predictive_5", "predictive_95",
                                       "standardised_error", "runs"])


def held_out_checks(frame):
    """``checks.csv`` rows of :func:`held_out`'s table: one per predicted feature (its standardised error) and,
    per mode, the share within +-3."""
    rows = []
    for _, r in frame.iterrows():
        if not r["runs"]:
            rows.append((f"held_out_{r['mode']}", f"{r['key']} ({r['held_out']})", math.nan, "no run gave it"))
            continue
        rows.append((f"held_out_{r['mode']}", f"{r['key']} ({r['held_out']})", float(r["standardised_error"]),
                     f"standardised error; predicted 5-95 % {r['predictive_5']:.3g}-{r['predictive_95']:.3g} "
                     f"{r['unit']} (mean {r['predicted_mean']:.3g}, {int(r['runs'])} runs), measured "
                     f"{r['measured']:.3g} +- {r['sd_observation']:.2g} (measurement and discrepancy)"))
    for mode, part in frame[frame["runs"] > 0].groupby("mode", sort=False):
        e = part["standardised_error"].to_numpy(float)
        rows.append((f"held_out_{mode}_share", "", float(np.mean(np.abs(e) <= CUTOFF)),
                     f"share of {len(e)} held-out features whose standardised error is within +-{CUTOFF:g}"))
    return pd.DataFrame(rows, columns=["check", "name", "value", "detail"])
