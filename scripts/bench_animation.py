"""Speed of the animation against matplotlib saving the same number of empty frames (medians, ratios).

The case of the performance bound: the default 6.5 s run (0.5 s steady
running + 6 s after the kick) animated at 30 frames per second in real time
(196 frames). Each repeat times, in the same process and back to back:

* ``animate``: ``whipple_kick.animation.animate(result, path, slow_motion=1)``,
  everything from the finished run to the closed file (scene, rider, figure,
  drawing, encoding);
* ``empty``: matplotlib's own writer (``FFMpegWriter`` for mp4, ``PillowWriter``
  for gif) saving the same number of frames of an empty figure of the same
  size and dpi, with the same ffmpeg, codec and output arguments.

Usage:
    python scripts/bench_animation.py              # mp4 and gif, 5 repeats
    python scripts/bench_animation.py --format mp4 --repeats 7
"""
import argparse
import pathlib
import statistics
import sys
import tempfile
import time


def _empty_frames(fmt, path, frames, size, fps, dpi):
    import matplotlib
    matplotlib.use("Agg")
    from matplotlib import animation as manim
    from matplotlib.figure import Figure
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    from whipple_kick import animation

    fig = Figure(figsize=(size[0] / dpi, size[1] / dpi), dpi=dpi)
    FigureCanvasAgg(fig)
    if fmt == "mp4":
        matplotlib.rcParams["animation.ffmpeg_path"] = animation.video_encoder()
        writer = manim.FFMpegWriter(fps=fps, codec=animation._h264_codec(animation.video_encoder()),
                                    extra_args=list(animation.FFMPEG_OUTPUT_ARGS))
    else:
        writer = manim.PillowWriter(fps=fps)
    t0 = time.perf_counter()
    with writer.saving(fig, str(path), dpi):
        for _ in range(frames):
            writer.grab_frame()
    return time.perf_counter() - t0


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--format", choices=("mp4", "gif", "both"), default="both")
    p.add_argument("--repeats", type=int, default=5)
    p.add_argument("--fps", type=float, default=30.0)
    args = p.parse_args(argv)

    import whipple_kick as wk
    from whipple_kick.simulation import Scenario, run

    result = run(Scenario())
    formats = ("mp4", "gif") if args.format == "both" else (args.format,)
    with tempfile.TemporaryDirectory() as tmp:
        for fmt in formats:
            if fmt == "mp4" and wk.animation.video_encoder() is None:
                print("mp4: no video encoder installed (pip install 'whipple_kick[video]'); skipped")
                continue
            size = wk.animation.DEFAULT_SIZE[fmt]
            out = pathlib.Path(tmp) / f"run.{fmt}"
            wk.animation.animate(result, out, fps=args.fps, slow_motion=1.0)   # warm-up (imports, caches)
            ours, empty, ratios = [], [], []
            for _ in range(args.repeats):
                t0 = time.perf_counter()
                info = wk.animation.animate(result, out, fps=args.fps, slow_motion=1.0)
                ours.append(time.perf_counter() - t0)
                empty.append(_empty_frames(fmt, pathlib.Path(tmp) / f"empty.{fmt}", info.frames, size,
                                           args.fps, 100))
                ratios.append(ours[-1] / empty[-1])
            print(f"{fmt} {size[0]}x{size[1]}, {info.frames} frames ({info.frames / args.fps:.2f} s at "
                  f"{args.fps:g} fps, real time), {args.repeats} repeats:")
            print(f"  animate:                       median {statistics.median(ours):6.2f} s "
                  f"({1e3 * statistics.median(ours) / info.frames:.1f} ms/frame)  runs "
                  + " ".join(f"{v:.2f}" for v in ours))
            print(f"  matplotlib, same empty frames: median {statistics.median(empty):6.2f} s "
                  f"({1e3 * statistics.median(empty) / info.frames:.1f} ms/frame)  runs "
                  + " ".join(f"{v:.2f}" for v in empty))
            print(f"  ratio animate / empty: median {statistics.median(ratios):.2f} (per repeat "
                  + " ".join(f"{v:.2f}" for v in ratios) + "; bound: at most 3)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
