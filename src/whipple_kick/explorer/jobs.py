"""The work a page's request hands to the sweeps' process pool, and the run's outcome in words.

Each function here runs in a worker of the pool :func:`whipple_kick.studies.sweep_engine.sweep` uses
(:func:`pool`), so that the server's own process only serves pages: a run never holds up another
user's request. A run goes through the sweeps' own worker function
(:func:`whipple_kick.studies.sweep_engine.run_case`: one BLAS thread, a failing run recorded, not raised)
and its folder gets the files ``simulate`` writes (:meth:`whipple_kick.simulate.results.Result.save` and
response.png), so that ``compare`` and :meth:`~whipple_kick.simulate.results.Result.load` read it.
"""
import contextlib
import json
import math
import os
import pathlib
import signal
import threading

import pandas as pd

from whipple_kick.figures import animation, plotting
from whipple_kick.simulate import results
from whipple_kick.simulate.results import Result, run_labels
from whipple_kick.studies import stability, sweep_engine

#: What :func:`~whipple_kick.studies.sweep_engine.run_case` returns of the trajectory: all of it, unthinned,
#: in double precision (the run folder's trajectory.csv is the run's, as ``simulate`` writes it).
WHOLE_TRAJECTORY = {"columns": "all", "dtype": "float64", "rate_hz": None}
#: The animation the page makes (``simulate --animate`` without a video encoder writes the same file):
#: a GIF, which every browser shows without a codec, at the format's default size.
ANIMATION = "animation.gif"
#: The overlay of runs the page draws (``compare``'s figure).
OVERLAY = "compare.png"


def pool(workers=None):
    """The sweeps' default process pool (:func:`whipple_kick.studies.sweep_engine._default_pool`), one worker
    per core unless ``workers`` is given: the one a sweep in this process would use."""
    return sweep_engine._default_pool(workers or os.cpu_count() or 1)


@contextlib.contextmanager
def _ctrl_c_ignored():
    """Within the block SIGINT is ignored, so that the pool's workers forked in it ignore Ctrl-C.

    Ctrl-C in a terminal reaches the server and its workers alike; the server says one line and ends its
    workers, which would otherwise each print a KeyboardInterrupt traceback. (A fork inherits the
    handler; in the main thread only, where the server submits.)
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)


def submit(function, *args, workers=None):
    """``function(*args)`` submitted to :func:`pool` (a future); workers it starts ignore Ctrl-C."""
    with _ctrl_c_ignored():   # the pool forks its workers at a submit
        return pool(workers).submit(function, *args)


def start_pool(workers=None):
    """:func:`pool` with its workers started and warm (imports, the compiled model): forked here, before the
    server has threads of its own (a fork copies one thread only, and any lock another thread held)."""
    for future in [submit(sweep_engine._preload, workers=workers) for _ in range(workers or os.cpu_count() or 1)]:
        future.result()


def discard_pool(end_workers=False):
    """Drop the pool (a broken one: a worker died); the next :func:`pool` starts a fresh one.
    ``end_workers`` also ends its workers (SIGTERM), as the server does when it stops."""
    sweep_engine._discard_default_pool(end_workers=end_workers)


def run_into(scenario, folder):
    """Run ``scenario`` and write ``simulate``'s files into ``folder``; returns what the page shows of it.

    Returns
    -------
    dict
        ``outcome`` ("completed", "fell", "failed"), ``words`` (sentences: :func:`words`), ``files`` (written),
        ``recovery_s`` (None where it has none), ``figure`` (whether response.png was drawn).
    """
    folder = pathlib.Path(folder)
    record = sweep_engine.run_case(scenario, folder.name, WHOLE_TRAJECTORY)
    if record["summary"] is None:   # nothing ran (the model could not start): the record says why
        return {"outcome": "failed", "words": [f"The run failed before it started: {record['error']}."],
                "files": [], "recovery_s": None, "figure": False}
    result = Result(scenario=scenario, trajectory=pd.DataFrame(record["trajectory"]),
                    summary=json.loads(record["summary"]))
    files = result.save(folder)
    if result.success:   # as simulate: no figure of a run that failed numerically
        plotting.response_figure([("", result)], folder / "response.png", title=plotting.result_title(result),
                                 kick=plotting.kick_band(result))
        files.append("response.png")
    return {"outcome": result.summary["outcome"], "words": words(result.summary), "files": files,
            "recovery_s": result.summary["recovery"]["time_s"] if not result.summary["fell"] else None,
            "figure": result.success}


def words(summary):
    """The run's outcome in sentences: fall or recovery, the last yaw-rate peak, what to be wary of.

    Example
    -------
    >>> words({"outcome": "fell", "fell": True, "fall_time_s": 1.536, "fall_reason": "steer",
    ...        "scenario": {"steer_limit_deg": 90.0, "fall_angle_deg": 45.0}, "message": "lost",
    ...        "metrics": {}, "recovery": {}, "controller": {}, "linear_stability": {}})[0]
    'The bicycle FELL 1.536 s after the kick start (|steer| reached 90 deg: the fork turned over).'
    """
    sc, out = summary["scenario"], []
    if summary["outcome"] == "failed":
        out.append(f"The run FAILED numerically: {summary['message']} (the download holds the run up to then).")
    elif summary["fell"]:
        why = (f"|steer| reached {sc['steer_limit_deg']:g} deg: the fork turned over"
               if summary.get("fall_reason") == "steer" else f"|roll| reached {sc['fall_angle_deg']:g} deg")
        t = summary["fall_time_s"]
        when = f"{t:.3f} s after the kick start" if t >= 0.0 else f"{-t:.3f} s BEFORE the kick start"
        out.append(f"The bicycle FELL {when} ({why}).")
    else:
        rec = summary["recovery"]
        out.append(f"Recovered {rec['time_s']:.3f} s after the kick (yaw, roll and steer rates all back within 5 % "
                   "of their first peaks)." if rec.get("time_s") is not None else
                   f"Not recovered within the run's {sc['duration']:g} s (yaw, roll and steer rates not all back "
                   "within 5 % of their first peaks).")
    m = summary.get("metrics", {})
    if m.get("last_peak_time_s") is not None:
        out.append(f"Last yaw-rate peak above 8 % of the largest at {m['last_peak_time_s']:.3f} s (the thesis' "
                   f"measure), {m.get('n_peaks', 0)} peaks.")
    peaks = m.get("yaw_rate_peaks_from_steady_rad_s") or []
    if peaks and not math.isnan(peaks[0]):
        out.append(f"First yaw-rate peak {peaks[0]:+.3f} rad/s from the steady turn at "
                   f"{m['yaw_rate_peak_times_s'][0]:.3f} s.")
    for note in (summary.get("controller", {}).get("warning"), summary.get("linear_stability", {}).get("message")):
        if note:
            out.append(f"Note: {note}.")
    extrapolated = results.extrapolation_line(summary) if "peaks" in summary else None
    if extrapolated:
        out.append(f"Note: {extrapolated}.")
    return out


def overlay(folders, numbers, path):
    """Draw ``compare``'s figure of the run folders (at most four on the page) into ``path``, each run labelled
    by its number on the page and the fields in which the runs differ
    (:func:`whipple_kick.simulate.results.run_labels`, as ``compare``)."""
    runs = [Result.load(f) for f in folders]
    differ = run_labels(runs)
    same = differ == [f"run {k + 1}" for k in range(len(runs))]   # no field tells them apart
    labels = [f"run {n}" if same else f"run {n}: {text}" for n, text in zip(numbers, differ, strict=True)]
    plotting.compare(runs, path, labels=labels, title=f"{len(runs)} runs compared: " + "; ".join(labels))
    return str(path)


def stability_into(scenario, speeds, folder):
    """The ``stability`` command's analysis of ``scenario`` against ``speeds``, its files written into
    ``folder`` (eigenvalues.csv, summary.json, stability.png); returns the printed lines."""
    result = stability.analyse(scenario, speeds)
    stability.write(result, pathlib.Path(folder), plot=True)
    return [result.summary["title"], *stability.report_lines(result.summary)]


def animate_into(folder, **options):
    """The animation of the run in ``folder`` (:data:`ANIMATION`; ``simulate --animate``'s defaults unless
    ``options`` of :func:`whipple_kick.figures.animation.animate` say otherwise)."""
    movie = animation.animate(Result.load(folder), pathlib.Path(folder) / ANIMATION, **options)
    return {"frames": movie.frames, "video_s": movie.video_duration_s, "wall_s": movie.wall_s}
