"""The package's kinds of failure: the user's mistake, numerical trouble, and a broken build environment.

Command-line entry points catch :class:`InputError`, print its one-line
message and exit with status 2 (no traceback). Library code raises it for
every user mistake: a value outside its allowed range, an unknown name, a
malformed parameter file. Numerical trouble is *not* an InputError: a run
that fails numerically raises :class:`SimulationError`, carrying what was
computed before the failure. A C compiler that cannot build the model is
:class:`BuildError` (the machine's set-up, not the user's input: exit
status 1); no C compiler at all is its :class:`CompilerNotFoundError` (one
line saying to install one, exit status 2). A cache folder that cannot be used is :class:`CacheError` (also
the machine's set-up: exit status 1). SIGTERM inside :func:`terminate_raises`
raises :class:`Terminated`, which the command-line entry points turn into one
line and exit status 143, as Ctrl-C's KeyboardInterrupt into 130.
"""
import contextlib
import math
import signal
import threading


class InputError(ValueError):
    """A user-supplied value, name or file is invalid.

    The message is one line and names the value, the allowed range or
    choices, and the unit.
    """


def check_range(name, value, low, high, unit, *, low_open=False, high_open=False):
    """Return ``float(value)`` or raise :class:`InputError` naming the range.

    Parameters
    ----------
    name : str
        What the value is, as the user knows it (e.g. ``"pressure"``).
    value : float
        The value to check; must be finite.
    low, high : float or None
        Allowed bounds (``None`` for unbounded).
    unit : str
        Unit shown in the message (e.g. ``"kPa"``).
    low_open, high_open : bool
        Exclude the bound itself.
    """
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise InputError(f"{name} must be a number in {unit}, got {value!r}") from None
    lo_txt = "-inf" if low is None else f"{low:g}"
    hi_txt = "inf" if high is None else f"{high:g}"
    bracket = ("(" if low_open else "[") + f"{lo_txt}, {hi_txt}" + (")" if high_open else "]")
    bad = not math.isfinite(x)
    if low is not None:
        bad = bad or (x <= low if low_open else x < low)
    if high is not None:
        bad = bad or (x >= high if high_open else x > high)
    if bad:
        raise InputError(f"{name} = {value!r} {unit} is outside the allowed range {bracket} {unit}")
    return x


class SimulationError(RuntimeError):
    """Numerical trouble with nothing to return (not a user mistake).

    A run whose integration fails part-way is not an exception: ``wk.run``
    returns its :class:`~whipple_kick.simulate.results.Result` with
    ``success`` False, as :func:`scipy.integrate.solve_ivp` does. This is
    raised only where no result exists: the compiled model failed at the
    start state, or no finite summary could be made.
    """


class BuildError(RuntimeError):
    """The compiled model could not be built (the C compiler failed).

    The message is one line naming the compiler and where its full output
    was saved.
    """


class CompilerNotFoundError(BuildError):
    """No C compiler to build the model with (none on PATH, or ``$CC`` names none): the machine's set-up.

    A :class:`BuildError` (the model cannot be built), but one the user fixes by
    installing a compiler: the message is one line saying so, and the
    command-line entry points exit with status 2, as for an input error,
    without a traceback.
    """


class CacheError(OSError):
    """The cache of generated code cannot be used (:mod:`whipple_kick.model.cache`).

    The message is one line naming the folder, what is wrong with it and how
    to fix it (e.g. set ``WHIPPLE_KICK_CACHE`` to a private writable folder).
    """


class WhippleKickWarning(UserWarning):
    """Base class of the package's warnings: a library caller filters them all, or one kind, as usual.

    Example
    -------
    >>> import warnings
    >>> with warnings.catch_warnings():
    ...     warnings.simplefilter("ignore", WhippleKickWarning)   # or one subclass, e.g. UnstableRiderWarning
    ...     warnings.warn("not shown", UnstableRiderWarning)

    The command-line tools print each warning once, as one line on stderr
    (``simulate: warning: ...``).
    """


class UnstableRiderWarning(WhippleKickWarning):
    """The rider in use is linearly unstable at the run's speed (a closed-loop pole with positive real part).

    Issued before the integration (:func:`whipple_kick.simulate.simulation.run`);
    the run goes on, since an unstable closed loop is a valid experiment
    (no controller, the thesis' fixed design speed), and its summary's
    ``linear_stability`` holds the same message.
    """


class ConvergenceWarning(WhippleKickWarning):
    """An optimiser stopped away from a stationary point (its gradient above the stated tolerance)."""


class DefaultValueWarning(WhippleKickWarning):
    """Values the input does not give were taken from the project's defaults (each named with its source)."""


class PerformanceWarning(WhippleKickWarning):
    """Results are unaffected, but a slower path is taken (e.g. the ctypes call into the compiled model)."""


class Terminated(BaseException):
    """SIGTERM reached the process (within :func:`terminate_raises`).

    A BaseException, like KeyboardInterrupt, so that no ``except Exception``
    (say a sweep recording a failing case) swallows it, and every ``finally``
    on the way out (temporary files, folder locks) still runs.
    """


def _raise_terminated(signum, frame):
    raise Terminated("terminated (SIGTERM)")


@contextlib.contextmanager
def terminate_raises():
    """Within the block, SIGTERM raises :class:`Terminated` (main thread only; elsewhere a no-op).

    Schedulers and ``timeout`` send SIGTERM; its default action kills the
    process at once, leaving temporary files and printing nothing.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGTERM, _raise_terminated)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)
