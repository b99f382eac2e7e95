"""Free responses of the nonlinear model started on a mode, and the eigenvalue they show."""
import math

import numpy as np
from scipy.optimize import least_squares

from whipple_kick.model import slip
from whipple_kick.simulate import lsoda

# ------------------------------------------------------------------ free response

def perturbed_state(model, vector, amplitude):
    """The steady motion's full state moved by ``amplitude`` along the real part of an eigenvector.

    Parameters
    ----------
    model : LinearModel
    vector : ndarray, complex
        Right eigenvector of ``model.matrix`` (states ``model.states``).
    amplitude : float
        Largest change of roll or steer [rad] (the other states in proportion).

    Returns
    -------
    ndarray
        Full state (:data:`whipple_kick.model.slip.STATE_NAMES`), pitch re-solved
        so the front contact stays on the ground.

    Example
    -------
    >>> from whipple_kick import Scenario
    >>> from whipple_kick.studies.stability import linear_model
    >>> model = linear_model(Scenario(symmetric_tyres=True), 4.0)
    >>> lam, vec = np.linalg.eig(model.matrix)
    >>> x0 = perturbed_state(model, vec[:, 0], 1e-4)
    >>> x0.shape == model.steady.x.shape
    True
    """
    idx = {n: i for i, n in enumerate(model.states)}
    # Rotate the eigenvector so its largest roll/steer entry is real and positive.
    big = max((vector[idx["q4"]], vector[idx["q7"]]), key=abs)
    dz = (vector * (abs(big) / big)).real * (amplitude / abs(big))
    x = np.array(model.steady.x, dtype=float)
    for name, value in zip(model.states, dz, strict=True):
        x[slip.X[{"v_lat": "u2", "v_fwd": "u1"}.get(name, name)]] += value
    return slip.solve_pitch(slip.CompiledRHS(model.steady.params), x)


def free_response(model, vector, amplitude=1e-4, duration=2.0, rate=500.0, rtol=1e-11):
    """The nonlinear model's response from the steady motion displaced along an eigenvector (no input).

    Parameters
    ----------
    model : LinearModel
        Its loop's parameters (the rider's gains for ``"closed"``) are integrated.
    vector : ndarray, complex
        Right eigenvector of ``model.matrix``.
    amplitude : float
        Initial roll or steer displacement [rad] (:func:`perturbed_state`).
    duration, rate : float
        Time [s] and sample rate [Hz].
    rtol : float
        LSODA relative tolerance.

    Returns
    -------
    t : ndarray
        Times [s].
    deviation : ndarray (len(t), len(model.states))
        Heading-frame state minus its steady value.

    Example
    -------
    >>> from whipple_kick import Scenario
    >>> from whipple_kick.studies.stability import linear_model
    >>> model = linear_model(Scenario(symmetric_tyres=True), 3.0, "closed")
    >>> lam, vec = np.linalg.eig(model.matrix)
    >>> k = int(np.argmax(lam.imag))
    >>> t, dev = free_response(model, vec[:, k], duration=1.0, rate=2000.0)
    >>> fit = fit_eigenvalue(t, np.column_stack([modal_coordinate(model, k, dev).real,
    ...                                          modal_coordinate(model, k, dev).imag]))
    >>> bool(abs(fit - lam[k]) < 1e-3 * abs(lam[k]))    # the nonlinear response decays at the eigenvalue
    True
    """
    rhs = slip.CompiledRHS(model.steady.params)
    x0 = perturbed_state(model, vector, amplitude)
    traj = lsoda.integrate(rhs, x0, duration, rtol=rtol, output_rate=rate)
    if traj.failed or traj.fell:
        raise FloatingPointError(f"the free response did not complete: {traj.message}")
    names = list(slip.linear_states(rhs.transient))
    keep = [names.index(n) for n in model.states if n in names]
    body = [slip.X[n] for n in model.states if n not in names]   # the rider body's states follow

    def heading(x):
        return np.concatenate([slip.heading_state(x)[keep], np.asarray(x)[body]])
    deviation = np.array([heading(x) for x in traj.x]) - heading(model.steady.x)
    return traj.t, deviation


def modal_coordinate(model, index, deviation):
    """The amplitude of mode ``index`` in a response: row ``index`` of the inverse eigenvector matrix times it.

    The left eigenvector filters out every other mode of the linear model, so a
    fit of this coordinate measures one mode's growth rate and frequency
    (the response itself is the nonlinear model's).

    Parameters
    ----------
    model : LinearModel
    index : int
        Eigenvalue index in ``numpy.linalg.eig(model.matrix)``.
    deviation : ndarray (n_t, n)
        Heading-frame deviations (:func:`free_response`).

    Returns
    -------
    ndarray, complex (n_t,)

    Example
    -------
    Skipped as a doctest: a fragment of :func:`free_response`'s example, which runs it.

    >>> eta = modal_coordinate(model, k, dev)     # see free_response    # doctest: +SKIP
    """
    _, V = np.linalg.eig(model.matrix)
    return deviation @ np.linalg.inv(V)[index]


def fit_eigenvalue(t, signals, oscillatory=True):
    """Growth rate and frequency of a free response: ``e^(s t) (a cos(w t) + b sin(w t))`` per signal.

    Variable projection: for each (s, w) the amplitudes a, b of every signal
    come from linear least squares; (s, w) minimise the residual
    (``scipy.optimize.least_squares``), started from the data alone (the
    spectrum's peak and the growth of the RMS from the first to the second
    half), not from a prediction.

    Parameters
    ----------
    t : ndarray
        Times [s], uniform.
    signals : ndarray (len(t), m)
        Signals to fit together (each scaled to its largest magnitude).
    oscillatory : bool
        False fits ``a e^(s t)`` (a real eigenvalue).

    Returns
    -------
    complex
        ``s + i w`` [1/s].

    Example
    -------
    >>> t = np.linspace(0.0, 3.0, 601)
    >>> y = np.exp(-0.5 * t) * np.cos(4.0 * t)
    >>> lam = fit_eigenvalue(t, y[:, None])
    >>> round(lam.real, 6), round(lam.imag, 6)
    (-0.5, 4.0)
    """
    Y = np.asarray(signals, dtype=float)
    Y = Y / np.where(np.abs(Y).max(axis=0) > 0, np.abs(Y).max(axis=0), 1.0)
    half = len(t) // 2
    rms = lambda part: float(np.sqrt(np.mean(part ** 2)))
    s0 = math.log(rms(Y[half:]) / rms(Y[:half])) / (t[half] - t[0])
    if oscillatory:
        main = Y[:, np.argmax(np.var(Y, axis=0))]
        spectrum = np.abs(np.fft.rfft((main - main.mean()) * np.hanning(len(t)), n=8 * len(t)))
        w0 = 2 * math.pi * np.fft.rfftfreq(8 * len(t), t[1] - t[0])[np.argmax(spectrum[1:]) + 1]
    else:
        w0 = 0.0

    def basis(p):
        env = np.exp(p[0] * (t - t[0]))
        return np.column_stack([env * np.cos(p[1] * t), env * np.sin(p[1] * t)]) if oscillatory else env[:, None]

    def residual(p):
        B = basis(p)
        coef, *_ = np.linalg.lstsq(B, Y, rcond=None)
        return (B @ coef - Y).ravel()

    p = least_squares(residual, [s0, w0] if oscillatory else [s0], xtol=1e-14, ftol=1e-14, gtol=1e-14).x
    return complex(p[0], p[1] if oscillatory else 0.0)
