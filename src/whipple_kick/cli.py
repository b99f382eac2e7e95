"""Command-line entry points.

Every failure prints one line on stderr, without a traceback, and exits
with a status that says whose it is: 2 the user's input (an
:class:`~whipple_kick.errors.InputError`, an unwritable output folder, an
output folder in use by another run), 1 the machine's set-up or the
numerics (a C compiler that fails, an unusable cache folder, a run that
fails numerically), 130 interrupted (Ctrl-C, as shells report SIGINT),
143 terminated (SIGTERM, as schedulers and ``timeout`` send). An output
folder a command created and did not fill is removed, and no temporary
file is left behind.
"""
import argparse
import contextlib
import datetime
import math
import os
import pathlib
import re
import select
import shutil
import signal
import sys
import threading
import time
import warnings

import numpy as np
import pandas as pd

from whipple_kick.library import bicycleparameters, riders, thesis, tyres
from whipple_kick.library.inputs import DIRECTIONS
from whipple_kick.model import benchmark, classic
from whipple_kick.simulate import assembly, criteria, provenance, results, settings, simulation
from whipple_kick.simulate.criteria import CRITERIA
from whipple_kick.simulate.scenario import (
    DEFAULTS,
    LQR_MODELS,
    MAX_DURATION,
    SETTINGS,
    TYRE_TRANSIENTS,
    UNITS,
    Scenario,
    UnusedFieldError,
)

from . import __version__, fileio
from .errors import (
    BuildError,
    CacheError,
    CompilerNotFoundError,
    InputError,
    SimulationError,
    Terminated,
    WhippleKickWarning,
    terminate_raises,
)

#: Exit status of a command interrupted by Ctrl-C (128 + SIGINT, as shells report it).
EXIT_INTERRUPTED = 130
#: Exit status of a command ended by SIGTERM (128 + SIGTERM).
EXIT_TERMINATED = 143
#: Exit status of a command whose standard output was closed by its reader (``simulate | head``): 128 + SIGPIPE,
#: what the shell reports for any Unix tool the closed pipe ends. Not 0: the printed text was cut (a script
#: with ``set -o pipefail`` learns that, as from ``cat``); the results written are whole.
EXIT_BROKEN_PIPE = 141


@contextlib.contextmanager
def _warnings_as_lines(prog):
    """Within the block, each warning is printed once, as one line on stderr: ``<prog>: warning: <message>``.

    Python's own format (the file, the line, the source) is for programmers;
    the package's warnings (:class:`~whipple_kick.errors.WhippleKickWarning`)
    are for users. The filters and the printer are the caller's again after
    the block: nothing is changed process-wide.
    """
    shown = set()

    def show(message, category, filename, lineno, file=None, line=None):
        text = " ".join(str(message).split())   # one line
        if text not in shown:
            shown.add(text)
            print(f"{prog}: warning: {text}", file=sys.stderr)

    with warnings.catch_warnings():
        warnings.simplefilter("always", WhippleKickWarning)   # every one reaches show(), which prints each once
        warnings.showwarning = show
        yield


def _stdout_is_broken():
    """True when standard output is a pipe whose reader has gone (``poll`` reports an error on it)."""
    try:
        poller = select.poll()
        poller.register(sys.stdout.fileno(), select.POLLOUT)
        return any(events & select.POLLERR for _, events in poller.poll(0))
    except (OSError, ValueError, AttributeError):   # no file descriptor (a captured stdout), no poll
        return False


def _run(main, argv, prog="whipple_kick", kept="no results were kept"):
    """Run a command's ``main(argv)``, turning each kind of failure into one line and its exit status.

    ``kept`` says what an interrupted (Ctrl-C) or terminated (SIGTERM) command leaves behind.
    """
    try:
        with terminate_raises(), _warnings_as_lines(prog):
            status = main(argv)
            sys.stdout.flush()   # text still buffered for a closed pipe fails here, not at the interpreter's exit
            return status
    except BrokenPipeError:
        if not _stdout_is_broken():
            print(f"{prog}: cannot write the results: broken pipe", file=sys.stderr)
            return 2
        # The reader of the printed text closed it (``simulate | head``): what was to be written is written.
        # Standard output goes to /dev/null, so that Python's own flush at exit has nothing to complain about.
        with contextlib.suppress(OSError, ValueError):
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return EXIT_BROKEN_PIPE
    except InputError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    except CompilerNotFoundError as exc:   # the machine lacks a compiler: the user's to install (status 2)
        print(f"{prog}: cannot build the compiled model: {exc}", file=sys.stderr)
        return 2
    except BuildError as exc:
        print(f"{prog}: cannot build the compiled model: {exc}", file=sys.stderr)
        return 1
    except CacheError as exc:   # the machine's set-up, before "cannot write the results" below
        print(f"{prog}: cache error: {exc}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print(f"{prog}: interrupted; {kept}", file=sys.stderr)
        return EXIT_INTERRUPTED
    except Terminated:
        print(f"{prog}: terminated (SIGTERM); {kept}", file=sys.stderr)
        return EXIT_TERMINATED
    except OSError as exc:   # an unwritable output folder or a full disk: the user's to fix
        print(f"{prog}: cannot write the results: {exc}", file=sys.stderr)
        return 2


def _benchmark(argv):
    parser = _OneLineParser(
        prog="whipple-benchmark",
        description="Linearise the classic Carvallo-Whipple model of the Meijaard et al. (2007) "
                    "benchmark bicycle and print its eigenvalues [1/s] against forward speed [m/s].")
    parser.add_argument("--speeds", type=float, nargs="+", default=list(range(11)),
                        metavar="M/S", help="forward speeds in m/s (default 0..10)")
    args = parser.parse_args(argv)
    moore = benchmark.to_moore(benchmark.meijaard2007_parameters())
    speeds = [float(v) for v in args.speeds]
    eigs = classic.eigenvalues(moore, speeds)
    print("Benchmark bicycle (Meijaard et al. 2007), classic no-slip model, eigenvalues [1/s]")
    print(f"{'v [m/s]':>8}  " + "  ".join(f"{'eigenvalue ' + str(i + 1):>26}" for i in range(4)))
    for v, row in zip(speeds, eigs, strict=True):
        cells = [f"{e.real:+.10f}{e.imag:+.10f}j" for e in row]
        print(f"{v:8.3f}  " + "  ".join(f"{c:>26}" for c in cells))
    print(f"weave speed   {classic.weave_speed(moore):.10f} m/s (published {benchmark.WEAVE_SPEED:.10f})")
    print(f"capsize speed {classic.capsize_speed(moore):.10f} m/s (published {benchmark.CAPSIZE_SPEED:.10f})")
    return 0


def benchmark_main(argv=None):
    """Console script ``whipple-benchmark``."""
    np.set_printoptions(precision=10)
    sys.exit(_run(_benchmark, argv))


# ----------------------------------------------------------------- simulate

def _output_options(group, figure):
    """--out, --force, --no-plot and --quiet, the same for every command that writes a folder."""
    group.add_argument("--out", metavar="DIR",
                       help="output folder (default: a new folder under the current directory)")
    group.add_argument("--force", action="store_true",
                       help="write into an existing non-empty output folder, overwriting the files written")
    group.add_argument("--no-plot", action="store_true", help=f"do not write {figure}")
    group.add_argument("--quiet", action="store_true", help="print nothing on success")


class _OneLineParser(argparse.ArgumentParser):
    """Argument parser whose usage errors are one line on stderr (exit status 2), with ``--version``."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self.add_argument("--version", action="version", version=f"%(prog)s (whipple_kick {__version__})",
                          help="print the package version and exit")

    def error(self, message):
        print(f"{self.prog}: error: {message} (see {self.prog} --help)", file=sys.stderr)
        sys.exit(2)


def _number(unit):
    """argparse type: a finite float, the message naming the unit when it is not."""
    def parse(text):
        try:
            value = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{text!r} is not a number ({unit})") from None
        if not math.isfinite(value):
            raise argparse.ArgumentTypeError(f"{text!r} is not a finite number ({unit})")
        return value
    return parse


#: The ``--help`` sections of the scenario's flags (each field's declared ``section``), in order, with their texts.
SECTIONS = {
    "tyres": None,
    "bicycle and rider": None,
    "rider's body": "the Yeadon rider split into legs, forearms and a leaning upper body (a bicycle-only set such as "
                    "balanceassist_v1), arms and reflex. The reflex steer torque is T = -(gain x state), delayed: a "
                    "positive gain steers against its state (a positive --reflex-roll steers out of the lean, against "
                    "the roll, and the bicycle falls; steering into the lean takes a negative one). Not with "
                    "--controller off (no rider torque at all)",
    "riding and control": None,
    "kick": None,
    "run and output": None,
}


class _Shown:
    """A declared default as ``--help`` shows it: a number in ``g`` format unless the help text says otherwise."""

    def __init__(self, value):
        self.value = value

    def __format__(self, spec):
        if not spec and isinstance(self.value, float):
            spec = "g"
        return format(self.value, spec)


def _metavar(unit):
    """A flag's metavar from its unit: "N m s/rad" -> "N_M_S_PER_RAD"."""
    return unit.upper().replace("/", "_PER_").replace(" ", "_")


def _scenario_flags(p, command, scenario_class=None, **context):
    """Add the flag of every Scenario field declared for ``command`` (:mod:`whipple_kick.simulate.settings`).

    Each flag comes from its field's declaration: name, section, choices or a
    number in the field's unit, metavar, help (``{default}`` the declared
    default, other ``{names}`` from ``context``) and its mutually exclusive
    partner. A flag not given leaves its field at None in the parsed
    arguments (:func:`_scenario_fields` keeps the given ones), so that the
    Scenario's default is the only one. ``scenario_class`` (default
    :class:`~whipple_kick.simulate.scenario.Scenario`) may be a subclass with
    more fields. Returns the sections (argument groups) by title, for the
    command's own options.
    """
    declared = [s for s in settings.settings(scenario_class or Scenario).values() if command in s.commands]
    used = {s.section for s in declared}
    sections = {title: p.add_argument_group(title, text) for title, text in SECTIONS.items() if title in used}
    exclusive = {}
    for s in declared:
        if s.section not in sections:   # a section SECTIONS does not list (a subclass's field)
            sections[s.section] = p.add_argument_group(s.section)
        group = sections[s.section]
        if s.exclusive:
            if s.exclusive not in exclusive:
                exclusive[s.exclusive] = group.add_mutually_exclusive_group()
            group = exclusive[s.exclusive]
        _field_flag(group, s, help=s.help.format(default=_Shown(s.default), none_means=_Shown(s.none_means),
                                                 **context))
    return sections


def _field_flag(group, s, **overrides):
    """Add field ``s``'s flag (a :class:`~whipple_kick.simulate.settings.Setting`) to ``group``.

    Its name, destination, choices or number type in the declared unit and its metavar come from the
    declaration; ``overrides`` are argparse's keywords a command sets itself (``help``, a ``default`` of its
    own, fewer ``choices``). Without a ``default`` the flag's value is None when it is not given.
    """
    options = dict(dest=s.name, default=None)
    kinds = (s.type, *getattr(s.type, "__args__", ()))
    unit = s.unit.strip("()")
    if bool in kinds:
        options.update(action="store_true")
    elif s.choices:
        options.update(choices=s.choices)
    elif float in kinds:
        options.update(type=_number(unit), metavar=s.metavar or _metavar(unit))
    else:
        options.update(metavar=s.metavar or None)
    options.update(overrides)
    options["help"] = options.get("help", "").replace("%", "%%")
    group.add_argument(s.option, **options)


def _scenario_fields(args, command, scenario_class=None):
    """The Scenario fields whose flags (:func:`_scenario_flags`) were given, by name (pressures checked together)."""
    fields = {s.name: getattr(args, s.name) for s in settings.settings(scenario_class or Scenario).values()
              if command in s.commands and getattr(args, s.name, None) is not None}
    if not hasattr(args, "pressure_kpa"):
        return fields
    fronts = (args.pressure_front_kpa, args.pressure_rear_kpa)
    if args.pressure_kpa is not None and any(v is not None for v in fronts):
        raise InputError("--pressure sets both tyres; do not combine it with --pressure-front/--pressure-rear")
    if (fronts[0] is None) != (fronts[1] is None):
        raise InputError("give both --pressure-front KPA and --pressure-rear KPA (or --pressure KPA for both)")
    _check_loads(fields.get("bicycle", DEFAULTS["bicycle"]), [args.fz_n] if args.fz_n is not None else [],
                 fields.get("rider", DEFAULTS["rider"]))
    return fields


def _simulate_parser(scenario_class=None):
    """``simulate``'s parser; its scenario flags are those of ``scenario_class`` (default: :class:`Scenario`)."""
    p = _OneLineParser(
        prog="simulate", allow_abbrev=False,
        description="Kick-plate test on the nonlinear Carvallo-Whipple bicycle-rider model with "
                    "Magic-Formula tyres (Dell'Orto 2025, Chapter 8): steady running, then the plate "
                    "under the rear wheel jumps sideways; an LQR steer-torque rider recovers or the "
                    "bicycle falls. Writes trajectory.csv, summary.json, scenario.toml (the run's settings, to "
                    "rerun it with --scenario) and response.png (and, with --animate, animation.mp4 or .gif).",
        epilog="Time is measured from the kick start. Defaults: "
               f"{DEFAULTS['bicycle']} + Yeadon rider for {thesis.REFERENCE_LOAD_N:g} N on the rear tyre, "
               f"{DEFAULTS['tyre']} at {DEFAULTS['pressure_kpa']:g} kPa, {DEFAULTS['speed']:g} m/s, "
               "LQR designed at the run's speed (the thesis: 3 m/s), 150 mm kick in 0.150 s (13.3 m/s^2), "
               f"{DEFAULTS['duration']:g} s. See docs/simulate.md.")
    sections = _scenario_flags(p, "simulate", scenario_class, tyres=", ".join(t[0] for t in tyres.available()),
                               riders=", ".join(riders.available()),
                               design_default="the run's --speed")
    g = sections["run and output"]
    g.add_argument("--compat", choices=("authors-code",),
                   help="authors-code: the thesis authors' published code (bicycle-kickplate-model) as it ran: "
                        "balanceassist_635N, the Table 8.4 rider of the bicycle's load, T03 chapter8 with the thesis friction, force lag, "
                        "rtol 1e-12, camber sign reversed, upright start with the uncompressed pitch, kick at t = 0, "
                        "speeds kept at the plate stop, slip speed of the contact point; --pressure defaults to 500; "
                        "other flags given override its settings. For explaining "
                        "that code's runs, not for predictions")
    g.add_argument("--scenario", metavar="FILE",
                   help="rerun the scenario of a TOML file (every run folder has scenario.toml); flags given "
                        "override its values")
    _output_options(g, "response.png")
    g = p.add_argument_group("animation")
    g.add_argument("--animate", action="store_true",
                   help="also write animation.mp4 (animation.gif when no video encoder is installed: "
                        "pip install 'whipple_kick[video]' for mp4); see docs/animation.md")
    # No defaults here: an option given without --animate is refused rather than ignored.
    g.add_argument("--fps", type=_number("frames/s"), metavar="FPS",
                   help="frames per second of the animation (default 30)")
    g.add_argument("--slow-motion", type=_number("playback speed"), metavar="FACTOR",
                   help="playback speed during the kick and --slow-after seconds after it, in (0, 1] "
                        "(default 0.2; 1 = real time throughout)")
    g.add_argument("--slow-after", type=_number("s"), metavar="S",
                   help="simulated seconds after the kick's end still played slowed (default 1)")
    return p


_ANIMATION_DEFAULTS = {"fps": 30.0, "slow_motion": 0.2, "slow_after": 1.0}


def _animation_options(args):
    """The animation's options with defaults, or None without --animate (refusing options given alone)."""
    given = {name: getattr(args, name) for name in _ANIMATION_DEFAULTS if getattr(args, name) is not None}
    if not args.animate:
        if given:
            flag = "--" + next(iter(given)).replace("_", "-")
            raise InputError(f"{flag} sets the animation; add --animate")
        return None
    from whipple_kick.figures import animation
    options = {**_ANIMATION_DEFAULTS, **given}
    animation.check_options(**options)
    return options


#: Fields a flag's field replaces in a --scenario file or the --compat preset (their alternatives).
_REPLACED_FIELDS = {"fz_n": ("rider_mass_kg",), "rider_mass_kg": ("fz_n",), "kick_duration": ("kick_accel",),
                    "kick_accel": ("kick_duration",), "pressure_kpa": ("pressure_front_kpa", "pressure_rear_kpa")}


def _flag(field):
    """The flag that sets a Scenario field (its declaration's :attr:`~whipple_kick.simulate.settings.Setting.option`)."""
    return settings.settings(Scenario)[field].option


def _flag_value(field, value):
    """``field = value`` as flags give it: ``--hip-stiffness 500 N m/rad``, ``--plate-stop resolve``, ``--lqr-heading``."""
    if isinstance(value, bool):
        return _flag(field) if value else f"no {_flag(field)}"
    unit = UNITS.get(field)
    if unit is None or not isinstance(value, (int, float)):
        return f"{_flag(field)} {value}"
    return f"{_flag(field)} {value:g}" + (" (unit 1)" if unit == "1" else f" {unit}")


def _in_flags(words):
    """A mechanism's condition (:data:`whipple_kick.simulate.scenario.MECHANISM_FIELDS`) in flags: "rider_body
    'leaning'" -> "--rider-body leaning", "pressure_front_kpa" -> "--pressure-front"."""
    def quoted(match):
        if match[1] not in DEFAULTS:
            return match[0]
        return f"{_flag(match[1])} {match[2]}" + match[3].replace("'", "")

    words = re.sub(r"\b([a-z][a-z0-9_]*) '([^']*)'((?: or '[^']*')*)", quoted, words)
    return re.sub(r"(?<![-\w])([a-z0-9]+_[a-z0-9_]+)\b",
                  lambda m: _flag(m[1]) if m[1] in DEFAULTS else m[0], words)


def _preflight(scenario):
    """:func:`whipple_kick.simulate.assembly.preflight`, a field its mechanism does not read refused by its flag.

    The scenario's own refusal (:class:`~whipple_kick.simulate.scenario.UnusedFieldError`) names the Python
    field; a user of the command line gave a flag.
    """
    try:
        return assembly.preflight(scenario)
    except UnusedFieldError as exc:
        default = DEFAULTS[exc.field]
        leave = ("leave it out" if default is None or default is False
                 else f"leave it at its default ({_flag_value(exc.field, default)})")
        raise InputError(f"{_flag_value(exc.field, getattr(scenario, exc.field))} is read only by "
                         f"{_in_flags(exc.why)}, which this run does not use: {leave}; it would be ignored") from None


def _check_loads(bicycle, loads, rider=None):
    """Refuse a ``--fz`` no rider can put on ``bicycle``'s rear tyre, naming the real range in N.

    Checked here, before the scenario's own check (a load above 0 N), so that
    0 N and 10 N get the same message: the loads between the bicycle's own
    rear load and that with the heaviest rider.
    """
    if not loads:
        return   # nothing to check (the bicycle itself is checked with the scenario)
    bike = bicycleparameters.load_bicycle(bicycle, rider)
    if bike.includes_rider:
        return   # refused later in one line (the preset already includes its rider)
    low, high, per_kg = riders.rear_load_range(bike)
    for fz in loads:
        riders.within_rear_load_range(bike, fz, low, high, per_kg)


def _scenario_from_args(args, scenario_class=None):
    """The scenario of the parsed flags; with ``--compat`` or ``--scenario``, the preset or file with the given
    flags' fields changed. ``scenario_class`` (default :class:`Scenario`) is the parser's (:func:`_simulate_parser`)."""
    cls = scenario_class or Scenario
    fields = _scenario_fields(args, "simulate", cls)
    if args.kick_table is not None:
        profile = args.kick_profile
        if profile not in (None, "table"):
            raise InputError(f"--kick-table gives the plate motion; do not combine it with --kick-profile {profile}")
        for flag, value in (("--kick-accel", args.kick_accel), ("--kick-duration", args.kick_duration),
                            ("--kick-displacement", args.kick_displacement)):
            if value is not None:
                raise InputError(f"--kick-table gives the plate motion; do not combine it with {flag}")
        fields["kick_profile"] = "table"
    elif args.kick_profile == "table":
        raise InputError("--kick-profile table needs --kick-table FILE (CSV with columns time in s, y in m)")
    if args.compat is None and args.scenario is None:
        return cls(**fields)
    if args.compat is not None and args.scenario is not None:
        raise InputError("--scenario FILE gives the whole scenario; do not combine it with --compat")
    changes = dict(fields)
    for name in [n for n in fields if n in _REPLACED_FIELDS]:
        changes = {**dict.fromkeys(_REPLACED_FIELDS[name]), **changes}
    if args.scenario is not None:
        return cls.from_file(args.scenario).with_changes(**changes)
    return cls.authors_code(**changes)


#: Every file ``simulate`` may write (``--force`` removes them before a run).
_OUTPUT_FILES = ("trajectory.csv", "summary.json", "scenario.toml", "response.png", "animation.mp4", "animation.gif")
#: Every file ``stability`` may write.
_STABILITY_FILES = ("eigenvalues.csv", "summary.json", "stability.png")


def _discard(out, created, written):
    """Remove what an unfinished command left: the folder it created, else the files it wrote."""
    if created:
        shutil.rmtree(out, ignore_errors=True)
        return
    for name in written:
        (out / name).unlink(missing_ok=True)


class _Output:
    """The output folder a command writes into (:func:`_output_folder`).

    ``out`` is the folder the user named (what messages print); ``dir`` is
    where the command writes: ``out`` itself, or with ``--force`` on an
    existing folder a hidden staging folder inside it (:data:`STAGING_PREFIX`)
    whose files replace the earlier run's only when the command succeeds.
    ``written`` lists the files written so far (removed if the command
    fails); ``keep`` set to True keeps them (a partial result for the user).
    """

    def __init__(self, out, created):
        self.out, self.created, self.written, self.keep, self.lock = out, created, [], False, None
        self.dir, self.staging = out, None


def _default_out(scenario, prefix="kick"):
    """A new folder name under the current directory (never an existing one)."""
    rear, front = scenario.pressures
    p = f"{rear:g}kPa" if rear == front else f"{rear:g}-{front:g}kPa"
    load = f"_{scenario.fz_n:g}N" if scenario.fz_n is not None else ""
    return _new_folder(f"{prefix}_{scenario.tyre}_{p}{load}")


def _new_folder(name):
    """``<name>_<date-time>`` under the current directory, numbered if it exists (never an existing folder)."""
    stamp = datetime.datetime.now().strftime("%Y%m%d-%H%M%S")
    base = pathlib.Path.cwd() / f"{name}_{stamp}"
    out, k = base, 1
    while out.exists():
        k += 1
        out = base.with_name(f"{base.name}-{k}")
    return out


#: Held (flock, :func:`whipple_kick.fileio.take_lock`) by the command writing into an output folder; holds its pid.
OUT_LOCK_FILE = ".whipple_kick.lock"


#: Name stem of the hidden folder, inside an existing output folder, that ``--force`` writes the new run into
#: (``<stem>.<pid>``); its files replace the earlier run's at the end, so a run that stops leaves that run whole.
STAGING_PREFIX = ".whipple_kick.replacing"


@contextlib.contextmanager
def _output_folder(path, force, previous=()):
    """Create/check the output folder before the (longer) run and hold its lock; yields an :class:`_Output`.

    The lock (:data:`OUT_LOCK_FILE`) keeps a second command from writing
    into the same folder at the same time (it gets one line, exit status
    2); a lock left by a killed command is taken over. Hidden temporaries
    of ``previous`` left by a killed writer are removed. With ``force`` on
    an existing folder the command writes into a hidden staging folder
    inside it (``job.dir``); when it succeeds (or keeps a partial result),
    the files named in ``previous`` (what the command writes) are replaced
    by the new ones or removed, so no file of an earlier run (say its
    response.png beside a new ``--no-plot`` summary) is left to contradict
    the new one. Until then the earlier run stays whole.

    Whatever ends the command before it finishes (a failure, Ctrl-C,
    SIGTERM, from the folder's creation on) removes the folder it created,
    else the files it wrote (the staging folder), unless ``keep`` was set.
    """
    out = pathlib.Path(path)
    if out.exists() and not out.is_dir():
        raise InputError(f"output folder {str(out)!r} exists and is not a folder")
    job = _Output(out, created=not out.exists())
    try:
        _claim(job, force, previous)
        yield job
    except BaseException:
        if job.staging is not None and job.keep:
            _replace_from_staging(job, previous)   # a partial result the command keeps for the user
        elif job.staging is not None:
            shutil.rmtree(job.staging, ignore_errors=True)
        elif not job.keep:
            _discard(out, job.created, job.written)
        raise
    else:
        if job.staging is not None:
            _replace_from_staging(job, previous)
    finally:
        if job.lock is not None:
            # The lock file goes with the lock, so that the folder holds only the results.
            fileio.release_lock(job.lock, out / OUT_LOCK_FILE)


def _replace_from_staging(job, previous):
    """Move the staging folder's entries into ``job.out`` and remove the earlier run's other files of ``previous``.

    Ctrl-C and SIGTERM are held back meanwhile (a few renames), so the
    folder never mixes two runs' files.
    """
    main = threading.current_thread() is threading.main_thread()
    held = {signal.SIGINT, signal.SIGTERM}
    if main:
        signal.pthread_sigmask(signal.SIG_BLOCK, held)
    try:
        new = {entry.name: entry for entry in job.staging.iterdir()}
        for name in previous:
            if name not in new:
                (job.out / name).unlink(missing_ok=True)
        for name, entry in new.items():
            target = job.out / name
            if target.is_dir() and not target.is_symlink():
                shutil.rmtree(target)
            os.replace(entry, target)
        job.staging.rmdir()
    finally:
        if main:
            signal.pthread_sigmask(signal.SIG_UNBLOCK, held)


def _claim(job, force, previous):
    """Create ``job.out``, take its lock (into ``job.lock``) and clear it for the command (:func:`_output_folder`)."""
    out = job.out
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise InputError(f"output folder {str(out)!r} is not writable: {exc.strerror or exc}") from None
    try:
        job.lock = fileio.take_lock(out / OUT_LOCK_FILE,
                                    f"output folder {str(out)!r} is in use by another run (process {{pid}}); "
                                    "wait for it to finish or choose another --out")
    except InputError:
        job.keep = True   # the folder is the other run's: touch nothing
        raise
    except OSError as exc:
        raise InputError(f"output folder {str(out)!r} is not writable: {exc.strerror or exc}") from None
    # Holding the lock, any temporary of ours here is a killed writer's.
    for stale in fileio.stale_temporaries(out, previous):
        stale.unlink(missing_ok=True)
    for stale in out.glob(f"{STAGING_PREFIX}.*"):   # a killed writer's staging folder
        shutil.rmtree(stale, ignore_errors=True)
    if not force and any(p.name != OUT_LOCK_FILE for p in out.iterdir()):
        raise InputError(f"output folder {str(out)!r} exists and is not empty; "
                         "use --force to overwrite its files or choose another --out")
    if force and not job.created:
        job.staging = out / f"{STAGING_PREFIX}.{os.getpid()}"
        try:
            job.staging.mkdir()
        except OSError as exc:
            job.staging = None
            raise InputError(f"output folder {str(out)!r} is not writable: {exc.strerror or exc}") from None
        job.dir = job.staging


def _print_summary(result, out, files):
    s = result.summary
    sc, bike, ctl, kick, st = s["scenario"], s["bicycle"], s["controller"], s["kick"], s["steady_state"]
    deg = 180.0 / np.pi
    rider = f" (rider {bike['rider_mass_kg']:.1f} kg)" if bike["rider_mass_kg"] is not None else " (preset with rider)"
    gains = ", ".join(f"{k}={v:.4g}" for k, v in ctl["gains"].items())
    print(f"simulate: {sc['tyre']} {s['tyres']['pressure_rear_kpa']:g}/{s['tyres']['pressure_front_kpa']:g} kPa "
          f"rear/front ({sc['coefficient_set']}, friction {sc['friction']}, transient {sc['tyre_transient']}), "
          f"{bike['bicycle']}, rear load "
          f"{bike['static_load_rear_n']:.1f} N{rider}, {sc['speed']:g} m/s")
    design = f", designed at {ctl['design_speed_m_s']:g} m/s" if ctl["design_speed_m_s"] is not None else ""
    print(f"  controller {ctl['type']} x{ctl['gain_scale']:g}{design}: {gains}")
    if "table" in kick:
        tab = kick["table"]
        print(f"  kick: table {tab['file']} ({tab['rows']} rows), net {kick['displacement_m'] * 1e3:+.0f} mm "
              f"(+ right) in {kick['duration_s']:.3f} s from t = {kick['start_s']:g} s (spline peak "
              f"{kick['peak_acceleration_m_s2']:.1f} m/s^2, {tab['peak_velocity_m_s']:.2f} m/s)")
    else:
        print(f"  kick: {abs(kick['displacement_m']) * 1e3:.0f} mm {kick['direction']} in {kick['duration_s']:.3f} s "
              f"(peak {kick['peak_acceleration_m_s2']:.1f} m/s^2, {kick['profile']} profile) at t = 0 s")
    if sc["start"] == "upright":
        print("  start: upright straight running, no rear-wheel torque (not a steady motion: the tyres' "
              "zero-slip forces act from t = 0)")
        if sc["start_pitch"] == "uncompressed":
            print(f"  start pitch solved without the tyre compressions (the authors' code): the front contact is "
                  f"{st['front_contact_below_ground_m'] * 1e3:.1f} mm below the ground throughout")
    else:
        print(f"  steady state: roll {st['roll_rad'] * deg:.2f} deg, steer {st['steer_rad'] * deg:.2f} deg, "
              f"yaw rate {st['yaw_rate_rad_s']:.4f} rad/s, rear-wheel torque {st['rear_wheel_torque_n_m']:+.4f} N m "
              f"({st['rear_wheel_torque_role']})" + ("" if st["found_by"] == "direct" else f" (found by {st['found_by']})"))
    if sc["slip_speed"] == "contact_point":
        print("  slip angle and relaxation from the contact points' forward speeds (the authors' code)")
    if sc["camber_sign"] == "reversed":
        print("  camber sign reversed: camber thrust pushes a leaning wheel away from the lean (the authors' "
              "published code; not physical)")
    if s["fell"]:
        why = (f"|steer| reached {sc['steer_limit_deg']:g} deg: the fork turned over" if s.get("fall_reason") == "steer"
               else f"|roll| reached {sc['fall_angle_deg']:g} deg")
        when = (f"{s['fall_time_s']:.3f} s after the kick start" if s["fall_time_s"] >= 0.0 else
                f"{-s['fall_time_s']:.3f} s BEFORE the kick start: no response to the kick, its metrics are "
                "unavailable")
        print(f"  result: FELL ({why}) {when}")
    else:
        print(f"  result: no fall in {sc['duration']:g} s")
    m, rec = s["metrics"], s["recovery"]
    if m.get("yaw_rate_peaks_from_steady_rad_s"):
        print(f"  yaw rate: first peak from steady {m['yaw_rate_peaks_from_steady_rad_s'][0]:+.3f} rad/s "
              f"at {m['yaw_rate_peak_times_s'][0]:.3f} s")
    if not s["fell"]:
        settled = ", ".join(f"{name.replace('_', ' ')} {sig['time_s']:.2f} s" if sig["time_s"] is not None
                            else f"{name.replace('_', ' ')} not within the run"
                            for name, sig in rec["signals"].items())
        print(f"  within 5 % of their first peaks from: {settled}")
        print("  recovery time: " + (f"{rec['time_s']:.3f} s after the kick (all three settled)"
                                     if rec["time_s"] is not None else "none within the run"))
    pk = s["peaks"]
    print(f"  largest absolute values after the kick: |yaw rate| {pk['max_abs_yaw_rate_absolute_rad_s']:.3f} rad/s, "
          f"|roll rate| {pk['max_abs_roll_rate_absolute_rad_s']:.3f} rad/s, "
          f"|steer rate| {pk['max_abs_steer_rate_absolute_rad_s']:.3f} rad/s, |Fy rear| {pk['max_abs_fy_rear_absolute_n']:.0f} N, "
          f"|slip rear| {pk['max_abs_slip_rear_absolute_rad'] * deg:.1f} deg")
    e = s["energy"]
    jumps = "".join(f", plate stop ({e['plate_stop']}) {j['kinetic_energy_change_j']:+.3f} J kinetic"
                    for j in e["velocity_jumps"])
    print(f"  energy after the kick: plate work {e['plate_work_j']:+.2f} J, sliding {e['sliding_dissipation_j']:.2f} J, "
          f"dampers {e['damper_dissipation_j']:.2f} J{jumps}; balance residual {e['balance_residual_max_abs_j']:.1e} J")
    n = s["numerics"]
    extrapolated = results.extrapolation_line(s)
    if extrapolated:
        print(f"  {extrapolated}")
    print(f"  numerics: LSODA rtol {n['rtol']:g}, {n['evaluations']} evaluations ({n['njev']} Jacobians), "
          f"integration {n['integration_wall_s']:.2f} s, "
          f"run {n['wall_s']:.2f} s")
    print(f"  wrote {', '.join(files)} in {out}")


def _simulate(argv):
    args = _simulate_parser().parse_args(argv)
    if args.quiet:   # summary.json lists the tyre files' data warnings (tyres.data_warnings)
        warnings.filterwarnings("ignore", category=tyres.DataQualityWarning)   # within _run's warnings block only
    scenario = _preflight(_scenario_from_args(args))
    movie_options = _animation_options(args)
    with _output_folder(args.out or _default_out(scenario), args.force, _OUTPUT_FILES) as job:
        out = job.out
        result, files, note = _simulate_into(args, scenario, movie_options, job.dir, job.written)
        if not result.success:
            # What ran before the numerical failure is kept for the user to inspect; the command fails.
            job.keep = True
            raise SimulationError(f"{result.message}; the run up to t = {result.summary['end_time_s']:g} s is in {out}")
    if not args.quiet and result.summary["controller"]["warning"]:
        print(f"simulate: warning: {result.summary['controller']['warning']}", file=sys.stderr)
    if not args.quiet:
        _print_summary(result, out, files)
        if note:
            print(f"  note: {note}")
    return 0


def _simulate_into(args, scenario, movie_options, out, written):
    """Run ``scenario`` and write its files into ``out``, each name appended to ``written`` once it is there.

    Returns (result, files, note): the run's result, the written files'
    descriptions and a note for the user or None.
    """
    result = simulation.run(scenario)
    files = result.save(out)
    written.extend(files)
    if not result.success:   # a numerical failure: the data up to it, no figures of a broken run
        return result, files, None
    if not args.no_plot:
        from whipple_kick.figures import plotting
        plotting.response_figure([("", result)], out / "response.png", title=plotting.result_title(result),
                                 kick=plotting.kick_band(result))
        files.append("response.png")
        written.append("response.png")
    note = None
    if movie_options is not None:
        from whipple_kick.figures import animation
        suffix = "mp4" if animation.video_encoder() else "gif"
        if suffix == "gif":
            note = "no video encoder installed: wrote a GIF (pip install 'whipple_kick[video]' for mp4)"
        movie = animation.animate(result, out / f"animation.{suffix}", **movie_options)
        written.append(movie.path.name)
        files.append(f"{movie.path.name} ({movie.frames} frames, {movie.video_duration_s:.1f} s)")
    return result, files, note


def simulate_main(argv=None):
    """Console script ``simulate``: one kick-plate run (see ``simulate --help``)."""
    try:
        status = _run(_simulate, argv, "simulate")
    except SimulationError as exc:
        print(f"simulate: numerical failure: {exc}", file=sys.stderr)
        status = 1
    sys.exit(status)


# ------------------------------------------------------------ recommend-pressure

def _recommend(argv):
    from whipple_kick.studies import recommend
    p = _OneLineParser(
        prog="recommend-pressure",
        description="Recommend the tyre inflation pressure with the fastest recovery after a "
                    "kick-plate kick (Dell'Orto 2025, Section 8.3 and Table 8.9): runs the kick at each "
                    "pressure for each rear load, ranks the runs by the recovery time (yaw, roll and "
                    "steer rates all back within 5 % of their first peaks) and says by how much the "
                    "best beats the second best, against the spread of the model itself.",
        epilog="Both tyres get the same pressure, as in the experiment. Every other setting is the "
               "simulate default (3 m/s, LQR rider designed at that speed, 150 mm kick to the right in 0.150 s, 6 s). "
               "The default runs one direction and one tyre transient; --kick-direction both and "
               "--tyre-transient all say whether the answer depends on them. See docs/sweeps.md.")
    p.add_argument("--fz", type=_number("N"), nargs="+", metavar="N",
                   help=f"static rear-tyre load(s) in N, e.g. --fz {thesis.loads_text(' ')} (required but with "
                        "--posterior, where the thesis' loads are the default)")
    p.add_argument("--tyre", default=DEFAULTS["tyre"], metavar="NAME",
                   help=f"tyre on both wheels (default {DEFAULTS['tyre']}; available: %s)"
                        % ", ".join(t[0] for t in tyres.available()))
    p.add_argument("--pressures", type=_number("kPa"), nargs="+", metavar="KPA",
                   help="pressures to try in kPa (default: the tyre's measured ones)")
    p.add_argument("--fine", action="store_true",
                   help="also try a grid of interpolated pressures between the measured ones")
    p.add_argument("--step", type=_number("kPa"), default=10.0, metavar="KPA",
                   help="step of the --fine grid in kPa (default 10)")
    p.add_argument("--criterion", choices=tuple(k.replace("_", "-") for k in CRITERIA), default="settling",
                   help="; ".join(f"{k.replace('_', '-')}{' (default)' * (k == 'settling')}: "
                                  + c.text.replace("%", "%%") for k, c in CRITERIA.items()))
    p.add_argument("--duration", type=_number("s"), metavar="S",
                   help=f"simulated time after the kick in s (default {DEFAULTS['duration']:g}, at most "
                        f"{MAX_DURATION:g})")
    p.add_argument("--workers", type=int, metavar="N",
                   help="worker processes (default: one per CPU core)")
    p.add_argument("--out", metavar="DIR",
                   help="sweep folder keeping every run (re-running with it resumes)")
    p.add_argument("--extend", action="store_true",
                   help="with --out: add these runs to a folder that holds another sweep")
    p.add_argument("--kick-direction", choices=(*DIRECTIONS, "both"), default=DEFAULTS["kick_direction"],
                   help=f"direction the plate moves (default {DEFAULTS['kick_direction']}); both: run each direction and say whether "
                        "the best pressure depends on it (twice the runs)")
    p.add_argument("--tyre-transient", choices=(*TYRE_TRANSIENTS, "all"), default=Scenario.tyre_transient,
                   help=f"tyre transient form (default {Scenario.tyre_transient}); all: run each form and say "
                        "whether the best pressure depends on it")
    from whipple_kick.library import uncertain
    p.add_argument("--uncertain", nargs="?", const=uncertain.DEFAULT, metavar="FILE",
                   help="the uncertainty study: run every pressure on inputs sampled from FILE (default: the "
                        f"shipped {uncertain.DEFAULT}) and say how probable each pressure is to be best and "
                        "what that hinges on (docs/uncertainty.md)")
    p.add_argument("--samples", type=int, metavar="N",
                   help="with --uncertain: SALib's base sample count N (N (D + 2) rows for D inputs, each run at "
                        "every pressure and load; default 64)")
    p.add_argument("--seed", type=int, metavar="S", help="with --uncertain or --posterior: the seed (default 0)")
    p.add_argument("--posterior", metavar="DIR",
                   help="the answer under a calibration's posterior (calibrate --out DIR): P(best) per pressure "
                        "and load from DIR/p_best.csv, or run it (--samples M posterior rows, default 32, each "
                        "at every pressure and load; the runs kept in DIR/posterior_runs to resume)")
    p.add_argument("--prior-study", metavar="DIR",
                   help="with --posterior: a prior uncertainty study's folder (--uncertain --out DIR), its "
                        "P(best) beside")
    bar = p.add_mutually_exclusive_group()
    bar.add_argument("--progress", action="store_true", default=None,
                     help="show the progress bar (default: only when stderr is a terminal)")
    bar.add_argument("--no-progress", dest="progress", action="store_false", help="no progress bar")
    args = p.parse_args(argv)
    if args.posterior is not None:
        return _recommend_posterior(args)
    if args.prior_study is not None:
        raise InputError("--prior-study goes with --posterior DIR")
    if args.fz is None:
        p.error("the following arguments are required: --fz")
    if args.uncertain is not None:
        return _recommend_uncertain(args)
    if args.samples is not None or args.seed is not None:
        raise InputError("--samples and --seed belong to the uncertainty study: add --uncertain [FILE]")
    args.duration = DEFAULTS["duration"] if args.duration is None else args.duration
    directions = DIRECTIONS if args.kick_direction == "both" else (args.kick_direction,)
    forms = TYRE_TRANSIENTS if args.tyre_transient == "all" else (args.tyre_transient,)
    variants = {(d, f): Scenario(duration=args.duration, kick_direction=d, tyre_transient=f).validate()
                for d in directions for f in forms}
    _check_loads(next(iter(variants.values())).bicycle, args.fz)
    if args.out is not None and len(variants) > 1 and not args.extend:
        raise InputError("--out with --kick-direction both or --tyre-transient all keeps every variant in one "
                         "folder: add --extend")
    recs, verdicts = recommend.recommend_variants(
        args.fz, variants, tyre=args.tyre, pressures=args.pressures, fine=args.fine, step_kpa=args.step,
        criterion=args.criterion, workers=args.workers, folder=args.out, extend=args.extend,
        progress=sys.stderr.isatty() if args.progress is None else args.progress)
    first = True
    for (direction, form), by_load in recs.items():
        for rec in by_load:
            if not first:
                print()
            first = False
            if len(variants) > 1:
                print(f"kicks to the {direction}, {form} tyre transient:")
            print(recommend.format_recommendation(rec))
    if verdicts:
        print("\nwhat the best pressure depends on:")
        for line in verdicts:
            print(f"  {line}")
    if args.out is not None:
        from whipple_kick.figures import plotting
        metric = CRITERIA[recommend.criterion_key(args.criterion)].column
        for (direction, form), by_load in recs.items():
            name = SWEEP_FIGURE if len(variants) == 1 else SWEEP_FIGURE.replace(".png", f"_{direction}_{form}.png")
            plotting.sweep_figure(pd.concat([rec.table.assign(fz_n=rec.fz_n) for rec in by_load], ignore_index=True),
                                  x="pressure_kpa", y="fz_n", metric=metric, path=pathlib.Path(args.out) / name,
                                  title=f"{args.tyre} ({form}, kicks to the {direction}): {metric} against "
                                        "pressure, one line per rear load")
            print(f"\nwrote {name} beside the sweep's table in {args.out}")
    return 0


#: The figure ``recommend-pressure --out`` writes into its sweep folder.
SWEEP_FIGURE = "recommendation.png"
#: The figures ``recommend-pressure --uncertain --out DIR`` writes into DIR.
UNCERTAINTY_FIGURES = criteria.Listing(lambda: ("p_best.png", *(f"recovery_{key}.png" for key in CRITERIA),
                                                 *(f"paired_{key}.png" for key in CRITERIA),
                                                 *(f"sobol_{key}.png" for key in CRITERIA)))


def _study_flags_given(args):
    """The flags of a plain recommendation given on a command line of a study that sets them itself."""
    return [flag for flag, value in (("--fine", args.fine), ("--extend", args.extend),
                                     ("--duration", args.duration is not None),
                                     ("--kick-direction", args.kick_direction != DEFAULTS["kick_direction"]),
                                     ("--tyre-transient", args.tyre_transient != Scenario.tyre_transient))
            if value]


def _recommend_uncertain(args):
    """``recommend-pressure --uncertain``: the uncertainty study (whipple_kick.studies.uncertainty)."""
    from whipple_kick.figures import uncertainty as figures
    from whipple_kick.studies import recommend, uncertainty
    given = _study_flags_given(args)
    if given:
        raise InputError(f"{', '.join(given)} cannot go with --uncertain: the uncertainty file samples or fixes "
                         "the kick, the tyre transient and the run's duration")
    criterion = recommend.criterion_key(args.criterion)
    samples = 64 if args.samples is None else args.samples
    seed = 0 if args.seed is None else args.seed
    pressures = args.pressures if args.pressures is not None else recommend.tyre_pressures(args.tyre)
    _check_loads(Scenario().bicycle, args.fz)
    out = None if args.out is None else pathlib.Path(args.out)
    study = uncertainty.run_study(args.uncertain, samples=samples, seed=seed, loads=args.fz, pressures=pressures,
                                  base=Scenario(tyre=args.tyre), workers=args.workers,
                                  folder=None if out is None else out / "runs",
                                  progress=sys.stderr.isatty() if args.progress is None else args.progress)
    study.verdict = uncertainty.verdict_lines(study, criterion)
    print(uncertainty.format_study(study))
    if out is not None:
        study.write(out)
        figures.p_best_figure(study.p_best, out / UNCERTAINTY_FIGURES[0],
                              title=f"P(best), N = {samples} ({len(study.inputs)} rows), 95 % intervals")
        for crit in CRITERIA:
            figures.distribution_figure(study.outcomes, crit, out / f"recovery_{crit}.png")
            figures.paired_figure(study.outcomes, crit, out / f"paired_{crit}.png")
            figures.sobol_figure(study.sobol, crit, None, out / f"sobol_{crit}.png")   # every pair at every load
        print(f"\nwrote the tables (CSV), verdict.txt and {', '.join(UNCERTAINTY_FIGURES)} into {out} "
              f"(the runs in {out / 'runs'}: run again to resume)")
    return 0


def _recommend_posterior(args):
    """``recommend-pressure --posterior DIR``: P(best) under a calibration's posterior
    (whipple_kick.studies.posterior_study), read from DIR or run there."""
    from whipple_kick.studies import posterior_study
    given = ["--uncertain"] * (args.uncertain is not None) + _study_flags_given(args) + ["--out"] * (args.out is not None)
    if given:
        raise InputError(f"{', '.join(given)} cannot go with --posterior: the calibration's folder holds the "
                         "answer and its runs, and the calibration's settings and the uncertainty file set the "
                         "kick, the tyre transient and the run's duration")
    folder = pathlib.Path(args.posterior)
    posterior_study.read_calibration(folder)   # a bad folder: one line, before anything else
    done = posterior_study.from_folder(folder)
    if done is not None and args.samples is None and args.seed is None and args.prior_study is None \
            and args.fz is None and args.pressures is None:
        print((folder / "answer.txt").read_text().rstrip() if (folder / "answer.txt").is_file()
              else done.to_string(index=False))
        print(f"\n(read from {folder / 'p_best.csv'}; --samples M runs it again)")
        return 0
    study = posterior_study.run(folder, samples=32 if args.samples is None else args.samples,
                                seed=0 if args.seed is None else args.seed,
                                loads=args.fz or thesis.LOADS_N, pressures=args.pressures or thesis.PRESSURES_KPA,
                                prior_study=args.prior_study, tyre=args.tyre, workers=args.workers,
                                progress=sys.stderr.isatty() if args.progress is None else args.progress)
    _write_answer(study, folder)
    print(posterior_study.format_study(study))
    print(f"\nwrote {', '.join(posterior_study.FILES)}, {ANSWER_FIGURE} into {folder} (the runs in "
          f"{folder / posterior_study.RUNS}: run again to resume)")
    return 0


def _out_given(argv):
    """The ``--out`` folder of a command line (as argparse takes it: ``--out DIR``, ``--out=DIR``, an
    abbreviation), or None."""
    for k, arg in enumerate(argv):
        flag, eq, value = str(arg).partition("=")
        if len(flag) >= 3 and "--out".startswith(flag):
            return value if eq else (argv[k + 1] if k + 1 < len(argv) else None)
    return None


def recommend_main(argv=None):
    """Console script ``recommend-pressure`` (see ``recommend-pressure --help``)."""
    from whipple_kick.studies.sweep_engine import SweepFailed, SweepInterrupted
    words = sys.argv[1:] if argv is None else argv
    out = _out_given(words)
    kept = ("no results were kept (--out DIR keeps the finished cases, and a rerun on it resumes)" if out is None
            else f"the finished cases are kept in {out}: run again with --out {out} to resume")
    if any(str(w).startswith("--posterior") for w in words):
        kept = "the finished runs are kept in the calibration folder's posterior_runs: run again to resume"
    try:
        status = _run(_recommend, argv, "recommend-pressure", kept)
    except (SweepInterrupted, SweepFailed) as exc:   # lost workers, or every case failed: not the user's to fix
        print(f"recommend-pressure: {exc}", file=sys.stderr)
        status = 1
    sys.exit(status)


# ------------------------------------------------------------------ compare

#: Every file ``compare`` writes.
_COMPARE_FILES = ("compare.png", "compare.csv")


def _compare(argv):
    p = _OneLineParser(
        prog="compare", allow_abbrev=False,
        description="Overlay kick-plate runs (folders written by simulate or Result.save) in one figure, each "
                    "run's kick, fall, recovery time and 5 % bands marked (compare.png), and tabulate their "
                    "results side by side (compare.csv, printed).",
        epilog="From Python: wk.plotting.compare(results), wk.results.compare_table(results). See docs/workflow.md.")
    p.add_argument("runs", nargs="+", metavar="RUN_DIR", help="run folders (each with summary.json and trajectory.csv)")
    p.add_argument("--labels", nargs="+", metavar="LABEL", help="one legend entry per run (default: the folder names)")
    _output_options(p.add_argument_group("output"), "compare.png")
    args = p.parse_args(argv)
    from whipple_kick.figures import plotting
    runs = [results.Result.load(folder) for folder in args.runs]
    labels = args.labels or [pathlib.Path(folder).resolve().name for folder in args.runs]
    if args.labels is None and len(set(labels)) < len(labels):
        labels = results.run_labels(runs)
    table = results.compare_table(runs, labels)
    with _output_folder(args.out or _new_folder("compare"), args.force, _COMPARE_FILES) as job:
        out = job.out
        job.written.append("compare.csv")
        fileio.write_csv(table.reset_index(), job.dir / "compare.csv")
        if not args.no_plot:
            job.written.append("compare.png")
            plotting.compare(runs, job.dir / "compare.png", labels=labels,
                             title=f"{len(runs)} runs compared: " + "; ".join(labels))
    if not args.quiet:
        with pd.option_context("display.max_colwidth", 40, "display.width", 200):
            print(table.to_string(na_rep="-"))
        print(f"  wrote {', '.join(n for n in _COMPARE_FILES if (out / n).exists())} in {out}")
    return 0


def compare_main(argv=None):
    """Console script ``compare``: runs overlaid in one figure and their results side by side (``compare --help``)."""
    sys.exit(_run(_compare, argv, "compare"))


# ------------------------------------------------------------------ stability

def _stability_parser():
    from whipple_kick.studies import stability
    start, stop, step = stability.DEFAULT_SPEEDS
    p = _OneLineParser(
        prog="stability", allow_abbrev=False,
        description="Eigenvalues of the slip model (measured Magic-Formula tyres) linearised about its steady "
                    "motion, against speed, without and with the rider's control, beside the no-slip "
                    "(knife-edge) model of the same bicycle: weave, capsize, caster, wobble and the tyre modes, "
                    "named from their eigenvectors and followed across speed. Writes eigenvalues.csv, "
                    "stability.png and summary.json.",
        epilog=f"Defaults: {DEFAULTS['bicycle']} + Yeadon rider for {thesis.REFERENCE_LOAD_N:g} N, {DEFAULTS['tyre']} at "
               f"{DEFAULTS['pressure_kpa']:g} kPa with its zero-slip offsets "
               "removed (straight running; --tyre-offsets measured linearises about the steady turns the "
               "offsets cause), LQR rider designed at each speed. Speed is constant in the linear model "
               "(the forward-speed mode is left out, as in the no-slip model). See docs/stability.md.")
    g = _scenario_flags(p, "stability", tyres=", ".join(t[0] for t in tyres.available()),
                               riders=", ".join(riders.available()),
                        design_default="each speed of the sweep")["riding and control"]
    g.add_argument("--speeds", default=f"{start:g}:{stop:g}:{step:g}", metavar="START:STOP:STEP",
                   help=f"forward speeds in m/s: START:STOP:STEP (STOP included) or V1,V2,... "
                        f"(default {start:g}:{stop:g}:{step:g})")
    g = p.add_argument_group("tyre offsets")
    g.add_argument("--tyre-offsets", choices=("zero", "measured"), default="zero",
                   help="zero (default): the fits' zero-slip offsets removed, as simulate --symmetric-tyres, so "
                        "the steady motion is upright straight running; measured: about the steady motion with "
                        "the offsets (a turn, large where a real eigenvalue is near zero)")
    g = p.add_argument_group("output")
    _output_options(g, "stability.png")
    return p


def _stability(argv):
    from whipple_kick.studies import stability
    args = _stability_parser().parse_args(argv)
    started = time.perf_counter()
    speeds = stability.parse_speeds(args.speeds)
    scenario = Scenario(**_scenario_fields(args, "stability"), symmetric_tyres=args.tyre_offsets == "zero",
                                   speed=float(speeds[0]))
    _preflight(scenario)
    with _output_folder(args.out or _default_out(scenario, "stability"), args.force, _STABILITY_FILES) as job:
        out = job.out
        job.written.extend(_STABILITY_FILES)   # written together at the end: any of them may be there
        result = stability.analyse(scenario, speeds)
        result.summary["numerics"] = {"wall_s": time.perf_counter() - started}
        result.summary["provenance"] = provenance.record(provenance.input_files(scenario))
        files = stability.write(result, job.dir, plot=not args.no_plot)
    missing = {loop: m["speeds_without_steady_motion"] for loop, m in result.summary["steady_motion"].items()
               if m["speeds_without_steady_motion"]}
    for loop, count in missing.items():
        print(f"stability: warning: {loop} loop: no steady motion at {count} of {speeds.size} speeds (left out): "
              f"{result.summary['steady_motion'][loop]['first_reason']}", file=sys.stderr)
    if not args.quiet:
        print(f"stability: {result.summary['title']}; {speeds.size} speeds {speeds[0]:g}-{speeds[-1]:g} m/s")
        for line in stability.report_lines(result.summary):
            print(line)
        print(f"  wrote {', '.join(files)} in {out} ({time.perf_counter() - started:.1f} s)")
    return 0


def stability_main(argv=None):
    """Console script ``stability``: eigenvalues of the slip model against speed (see ``stability --help``)."""
    sys.exit(_run(_stability, argv, "stability"))


# ------------------------------------------------------------------ validate

#: Every file or folder ``validate`` writes (``--force`` removes them first).
_VALIDATE_FILES = ("validation.csv", "summary.json", "validation.png")


def _validate_parser():
    from whipple_kick.studies import validation
    p = _OneLineParser(
        prog="validate", allow_abbrev=False,
        description="The model against the thesis' kick-plate measurements (Dell'Orto 2025, Section 8.5, "
                    f"Tables 8.6-8.9): runs the nine measured cases (rear loads {thesis.loads_text('/')} N x "
                    f"{thesis.pressures_text('/')} kPa) "
                    "in both kick directions as the experiments ran, processes the yaw rate as the recordings "
                    "were (100 Hz, 20 Hz zero-phase low-pass, peaks until one is below 8 %) and compares. "
                    "Writes validation.csv, cases/<case>_<direction>/trajectory.csv, validation.png and "
                    "summary.json.",
        epilog="Defaults: 2 m/s, 150 mm smooth kick at 35 m/s^2 (0.157 s), LQR rider designed at the run's speed, "
               "both directions, 6 s after the kick; the loads and pressures are the measured ones (no --pressure, "
               "--fz). See docs/experiments.md.")
    g = _scenario_flags(p, "validate", tyres=", ".join(t[0] for t in tyres.available()),
                               riders=", ".join(riders.available()),
                        design_default="the run's --speed")["riding and control"]
    # The experiments' own speed, kick, duration and tolerance: the fields' flags with validate's defaults.
    _field_flag(g, SETTINGS["speed"], default=validation.SPEED,
                help=f"forward speed in m/s (default {validation.SPEED:g}, the measured 1.92-2 m/s)")
    g = p.add_argument_group("kick")
    _field_flag(g, SETTINGS["kick_accel"], default=validation.KICK_ACCEL,
                help=f"peak plate acceleration in m/s^2 (default {validation.KICK_ACCEL:g}, measured 30-35)")
    _field_flag(g, SETTINGS["kick_displacement"], default=validation.KICK_DISPLACEMENT,
                help=f"plate travel in m (default {validation.KICK_DISPLACEMENT:g})")
    _field_flag(g, SETTINGS["kick_profile"], choices=("smooth", "constant"), default="smooth",
                help="smooth (default: minimum jerk) or constant acceleration (the thesis' simulations)")
    g.add_argument("--directions", nargs="+", choices=validation.DIRECTIONS, default=list(validation.DIRECTIONS),
                   help="kick directions to run (default both: the thesis does not give one)")
    g = p.add_argument_group("comparison and output")
    g.add_argument("--time-origin", choices=validation.TIME_ORIGINS, default="first_peak",
                   help="origin of the last-peak time: first_peak (default, inferred from the printed times and "
                        "periods) or kick")
    g.add_argument("--compare-transients", action="store_true",
                   help="also run every tyre transient form and say whether the best pressure depends on it "
                        "(summary.json by_tyre_transient; 3x the runs)")
    _field_flag(g, SETTINGS["duration"], default=validation.DURATION,
                help=f"simulated time after the kick in s (default {validation.DURATION:g}, at most "
                     f"{MAX_DURATION:g})")
    _field_flag(g, SETTINGS["rtol"], default=SETTINGS["rtol"].default,
                help=f"LSODA relative tolerance (default {SETTINGS['rtol'].default:g})")
    g.add_argument("--workers", type=int, metavar="N", help="worker processes (default: one per CPU core)")
    _output_options(g, "validation.png")
    return p


def _validate(argv):
    from whipple_kick.studies import validation
    args = _validate_parser().parse_args(argv)
    started = time.perf_counter()
    if args.workers is not None and args.workers < 1:
        raise InputError(f"--workers = {args.workers} must be a whole number >= 1")
    base = validation.base_scenario(**_scenario_fields(args, "validate"), speed=args.speed, kick_accel=args.kick_accel,
                                    kick_displacement=args.kick_displacement, kick_profile=args.kick_profile,
                                    duration=args.duration, rtol=args.rtol)
    for case in validation.experiments.load().cases.values():   # every flag checked before any run or folder
        _preflight(base.with_changes(fz_n=case.fz_n, pressure_kpa=case.pressure_kpa))
    with _output_folder(args.out or _new_folder("validation"), args.force, _VALIDATE_FILES) as job:
        out = job.out
        job.written.extend(_VALIDATE_FILES)   # what a failure before the end removes
        if args.compare_transients:
            # Every form, the base one included: its validation is the result (not run a second time).
            forms, verdicts = validation.compare_transients(base, directions=args.directions, workers=args.workers,
                                                            time_origin=args.time_origin)
            result = forms[base.tyre_transient]
            result.summary["by_tyre_transient"] = validation.transient_summary(forms, verdicts)
        else:
            result = validation.validate(base, directions=args.directions, workers=args.workers,
                                         time_origin=args.time_origin)
        result.summary["wall_s"] = time.perf_counter() - started
        files = validation.write(result, job.dir, plot=not args.no_plot)
    if not args.quiet:
        print(f"validate: {len(result.runs)} model runs against the thesis' kick-plate measurements "
              f"(tyre transient {base.tyre_transient}, {base.speed:g} m/s, {base.kick_profile} kick at "
              f"{base.kick_accel:g} m/s^2)")
        for line in validation.report_lines(result):
            print("  " + line)
        for rule, by_direction in result.summary.get("by_tyre_transient", {}).get("verdicts", {}).items():
            for direction, text in by_direction.items():
                print(f"  tyre transient, {rule} rule, kicks to the {direction}: {text}")
        print(f"  wrote {', '.join(files)} in {out} ({time.perf_counter() - started:.1f} s)")
    return 0


def validate_main(argv=None):
    """Console script ``validate``: the model against the thesis' measurements (see ``validate --help``)."""
    sys.exit(_run(_validate, argv, "validate"))


#: The figure ``calibrate --out DIR`` writes: each feature's posterior predictive beside the measurement.
CALIBRATION_FIGURE = "predictive.png"


def _held_out(args, result, base, inputs, cells, progress, options):
    """``calibrate --held-out``: the checks' table (its rows also appended to ``result.checks``)."""
    from whipple_kick.studies import calibration

    def factory(prior_list, cells, features, direction):
        return calibration.ModelSimulator([p.field for p in prior_list], cells, features,
                                          base.with_changes(kick_direction=direction), args.workers, progress)

    frames = [calibration.held_out(mode, factory, spec=args.spec, inputs=inputs, cells=cells,
                                   direction=args.direction, draws=4 if args.quick else 8, fitted=result, **options)
              for mode in dict.fromkeys(args.held_out)]
    frame = pd.concat(frames, ignore_index=True)
    result.checks = pd.concat([result.checks, calibration.held_out_checks(frame)], ignore_index=True)
    return frame


def _screen(args, spec, inputs, cells, base, progress):
    """``calibrate --screen``: Morris screening of every prior the rider reads (the loaded calibration file
    ``spec``), into DIR/screening.csv."""
    from whipple_kick.studies import calibration
    candidates = [n for n in spec.priors if n != "hip_stiffness" or args.rider_body == "leaning"]
    frame = calibration.screen_inputs(spec, candidates, cells=cells, base=base, workers=args.workers,
                                      progress=progress, trajectories=4 if args.quick else 8, seed=args.seed,
                                      runs=pathlib.Path(args.out) / calibration.RUNS)
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    fileio.write_atomic(out / SCREENING_FILE, frame.to_csv(index=False))
    print(f"screening ({int(frame['rows'].iloc[0])} rows of Morris trajectories; active: mu* >= "
          f"{calibration.SCREEN_THRESHOLD:g} sd of some feature over the prior's range):")
    for _, r in frame.iterrows():
        print(f"  {r['input']}: mu* {r['mu_star_sd']:.2f} sd ({r['feature']}), sigma {r['sigma_sd']:.2f} sd: "
              + ("active" if r["active"] else "not seen by the features"))
    active = dict(zip(frame["input"], frame["active"], strict=True))
    unseen = [n for n in inputs if not active.get(n, True)]
    if unseen:
        print(f"  calibrated but not seen by the features: {', '.join(unseen)} (their posterior stays near the prior)")
    return frame


#: What ``calibrate --screen`` writes.
SCREENING_FILE = "screening.csv"


#: The figure of the answer under a posterior (P(best) per pressure and load), beside p_best.csv.
ANSWER_FIGURE = "p_best.png"


def _write_answer(study, folder):
    """The answer's tables and its figure (the uncertainty study's P(best) figure) into ``folder``."""
    from whipple_kick.figures import uncertainty as figures
    study.write(folder)
    c = study.settings["choices"]
    figures.p_best_figure(study.p_best, folder / ANSWER_FIGURE,
                          title=f"P(best) under the posterior, {study.samples} rows, 95 % intervals "
                                f"({c.get('rider_body')} rider, kicks to the {c.get('kick_direction')})")


def _stale_answer(folder):
    """Remove an earlier posterior's answer from a calibration folder (its runs stay: a rerun reuses them)."""
    from whipple_kick.studies import posterior_study
    for name in (*posterior_study.FILES, posterior_study.BESIDE_PRIOR, ANSWER_FIGURE):
        (folder / name).unlink(missing_ok=True)


def calibrate_main(argv=None):
    """Console script ``calibrate``: history matching and a posterior of the uncertain inputs against the thesis'
    measured kick responses (see ``calibrate --help`` and :mod:`whipple_kick.studies.calibration`)."""

    def main(argv):
        from whipple_kick.library import priors
        from whipple_kick.studies import calibration, validation
        p = _OneLineParser(
            prog="calibrate", allow_abbrev=False,
            description="Calibrate the model's uncertain inputs against the thesis' kick-plate measurements "
                        "(Tables 8.6-8.8): response features per measured cell (oscillation frequency, decay per "
                        "period, 8 % envelope time), Gaussian-process emulators, history matching in waves "
                        "(implausibility > 3 ruled out) and an emcee posterior. Writes posterior.csv, "
                        "features.csv, checks.csv and verdict.txt into --out.")
        p.add_argument("--out", required=True, metavar="DIR", help="output folder (created; files overwritten)")
        p.add_argument("--spec", default=priors.DEFAULT, metavar="NAME|PATH",
                       help=f"calibration file (default {priors.DEFAULT}: priors, errors, discrepancies)")
        p.add_argument("--inputs", nargs="+", metavar="NAME",
                       help="priors to calibrate (default gain_scale carcass_stiffness_scale carcass_damping "
                            "kick_accel)")
        p.add_argument("--rider-body", choices=("rigid", "leaning"), default="rigid",
                       help="the rider model (a modelling choice: calibrate per option; default rigid)")
        p.add_argument("--lqr-model", choices=LQR_MODELS, default=LQR_MODELS[0],
                       help="the model the rider's LQR gains are designed on (a modelling choice: calibrate per "
                            f"option, as the uncertainty file's rider options; default {LQR_MODELS[0]})")
        p.add_argument("--direction", choices=validation.DIRECTIONS, default="right",
                       help="kick direction (the thesis gives none: calibrate per option; default right)")
        p.add_argument("--quick", action="store_true",
                       help="three cells (570 N 300 kPa, 635 N 400 kPa, 701 N 500 kPa), 1000 sampler steps (else 9 "
                            "cells, 5000 steps: the full run's autocorrelation times were 60-80 steps)")
        p.add_argument("--waves", type=int, default=2, metavar="N", help="history-matching waves (default 2)")
        p.add_argument("--seed", type=int, default=0, metavar="N")
        p.add_argument("--workers", type=int, metavar="N", help="worker processes (default: one per CPU core)")
        p.add_argument("--held-out", nargs="+", choices=calibration.HELD_OUT, default=(), metavar="CHECK",
                       help="held-out checks, rows in checks.csv and held_out.csv: load (calibrate without each "
                            "rear load in turn and predict it; one calibration per load) and/or direction "
                            "(predict the measurements with the model kicked the other way)")
        p.add_argument("--screen", action="store_true",
                       help="first screen every prior the rider reads (Morris elementary effects, 4 trajectories "
                            "with --quick, else 8): screening.csv, and which calibrated inputs the features do "
                            "not see")
        p.add_argument("--samples", type=int, metavar="M",
                       help="posterior rows for the answer (P(best) per pressure and load, p_best.csv; each row "
                            "run at every pressure and load): default 24 with --quick, else 32; 0: no answer")
        p.add_argument("--prior-study", metavar="DIR",
                       help="a prior uncertainty study's folder (recommend-pressure --uncertain --out DIR): its "
                            "P(best) beside the posterior's (p_best_beside_prior.csv)")
        args = p.parse_args(argv)
        if args.workers is not None and args.workers < 1:
            raise InputError(f"--workers = {args.workers} must be a whole number >= 1")
        if args.waves < 1:
            raise InputError(f"--waves = {args.waves} must be a whole number >= 1")
        samples = (24 if args.quick else 32) if args.samples is None else args.samples
        if samples == 1 or samples < 0:
            raise InputError(f"--samples = {samples} must be 0 (no answer) or a whole number >= 2")
        started = time.perf_counter()
        base = validation.base_scenario(duration=calibration.FEATURE_DURATION, rider_body=args.rider_body,
                                        kick_direction=args.direction, lqr_model=args.lqr_model)
        cells = list(zip(thesis.LOADS_N, thesis.PRESSURES_KPA, strict=True)) if args.quick else None   # the diagonal
        inputs = args.inputs or (["gain_scale", "carcass_stiffness_scale", "carcass_damping", "kick_accel"]
                                 + (["hip_stiffness"] if args.rider_body == "leaning" else []))
        progress = sys.stderr.isatty()
        options = dict(waves=args.waves, steps=1000 if args.quick else 5000, seed=args.seed)
        spec = priors.load(args.spec)   # once, for the screening and the calibration alike
        if args.screen:
            _screen(args, spec, inputs, cells, base, progress)
        result = calibration.calibrate(spec=spec, inputs=inputs, cells=cells, base=base, workers=args.workers,
                                       progress=progress, check_runs=4 if args.quick else 8,
                                       runs=pathlib.Path(args.out) / calibration.RUNS, **options)
        if args.held_out:
            result.held_out = _held_out(args, result, base, inputs, cells, progress, options)
        out = pathlib.Path(args.out)
        files = result.write(out)
        from whipple_kick.figures import calibration as figures
        figures.predictive_figure(result.features, out / CALIBRATION_FIGURE)
        print(f"calibrate: {args.rider_body} rider (LQR on the {args.lqr_model} model), kicks to the {args.direction}, "
              f"{len(result.measured)} measured features")
        for line in result.verdict:
            print("  " + line)
        if result.held_out is not None:
            for _, r in result.checks[result.checks["check"].str.endswith("_share")].iterrows():
                print(f"  {r['check']}: {r['value']:.2f} ({r['detail']})")
        print(f"  wrote {', '.join(f.name for f in files)}, {CALIBRATION_FIGURE} in {args.out} "
              f"({time.perf_counter() - started:.0f} s)")
        _stale_answer(out)
        if samples and result.posterior is not None:
            from whipple_kick.studies import posterior_study
            study = posterior_study.run(out, samples=min(samples, len(result.posterior)), seed=args.seed,
                                       prior_study=args.prior_study, workers=args.workers, progress=progress)
            _write_answer(study, out)
            print(posterior_study.format_study(study))
            print(f"  wrote {', '.join(posterior_study.FILES)}, {ANSWER_FIGURE} in {args.out} (the runs in "
                  f"{out / posterior_study.RUNS}; total {time.perf_counter() - started:.0f} s)")
        elif samples:
            print("  no answer under the posterior: nothing in the prior matches the measurements")
        return 0

    sys.exit(_run(main, argv, "calibrate"))
