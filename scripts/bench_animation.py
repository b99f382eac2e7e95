"""Speed of the animation against matplotlib saving the same number of empty frames (medians, ratios).

The case of the performance bound: the default 6.5 s run (0.5 s steady
running + 6 s after the kick) animated at 30 frames per second in real time
(196 frames). Each repeat times, in the same process and back to back:

* ``animate``: ``whipple_kick.figures.animation.animate(result, path, slow_motion=1)``,
  everything from the finished run to the closed file (scene, rider, figure,
  drawing, encoding);
* ``empty``: matplotlib's own writer (``FFMpegWriter`` for mp4, ``PillowWriter``
  for gif) saving the same number of frames of an empty figure of the same
  size and dpi, with the same ffmpeg, codec and output arguments.

``--compare-3d`` also times drawing alone (no file), per frame: this
module's renderer against matplotlib's 3D axes (mpl_toolkits.mplot3d, what
symmeplot draws with) showing the same scene: wheel discs, the rider's
solids as their 3D convex hulls (triangles), the frame tubes and the ground
polygons, updated in place and redrawn each frame.

Usage:
    python scripts/bench_animation.py              # mp4 and gif, 5 repeats
    python scripts/bench_animation.py --format mp4 --repeats 7
    python scripts/bench_animation.py --format none --compare-3d
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
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    from whipple_kick.figures import animation

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


def _compare_3d(result, repeats, fps=30.0, size=(1280, 720), dpi=100):
    """Median ms per frame: this renderer vs mplot3d on the same scene (drawing only)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    from mpl_toolkits.mplot3d.art3d import Line3DCollection, Poly3DCollection
    import numpy as np
    from scipy.spatial import ConvexHull

    from whipple_kick.figures import animation

    t = result.trajectory["time"].to_numpy()
    times = animation.frame_times(float(t[0]), float(t[-1]), fps)
    frames = animation._frames(result, times, size, dpi, None, True, (0.0, 0.0), 1.0)
    scene = frames.scene
    fig = Figure(figsize=(size[0] / dpi, size[1] / dpi), dpi=dpi)
    canvas = FigureCanvasAgg(fig)
    ax = fig.add_subplot(projection="3d")
    faces = {item.name: ConvexHull(item.points[0]).simplices for item in scene.items if item.kind == "hull"}

    def polygons(k):
        out = [item.points[k] for item in scene.items if item.kind == "disc"]
        for item in scene.items:
            if item.kind == "hull":
                out += list(item.points[k][faces[item.name]])
        return out + [scene.plate[k]]

    def tubes(k):
        return [item.points[k] for item in scene.items if item.kind in ("tube", "arrow", "arc", "axis")]

    solids = ax.add_collection3d(Poly3DCollection(polygons(0), facecolor="0.7", edgecolor="k", linewidths=0.3))
    lines = ax.add_collection3d(Line3DCollection(tubes(0), colors="b", linewidths=2))
    ours, theirs = [], []
    for _ in range(repeats):
        t0 = time.perf_counter()
        for k in range(times.size):
            frames.render(k)
        ours.append(1e3 * (time.perf_counter() - t0) / times.size)
        t0 = time.perf_counter()
        for k in range(times.size):
            centre = scene.camera_target[k]
            solids.set_verts(polygons(k))
            lines.set_segments(tubes(k))
            ax.set_xlim(centre[0] - 1.5, centre[0] + 1.5)
            ax.set_ylim(centre[1] - 1.5, centre[1] + 1.5)
            ax.set_zlim(0.5, -2.0)
            canvas.draw()
            np.asarray(canvas.buffer_rgba())
        theirs.append(1e3 * (time.perf_counter() - t0) / times.size)
    print(f"drawing only, {times.size} frames {size[0]}x{size[1]}, {repeats} repeats:")
    print(f"  whipple_kick.figures.animation (NumPy projection, 2D artists): median {statistics.median(ours):.1f} ms/frame")
    print(f"  matplotlib 3D axes, same scene redrawn:               median {statistics.median(theirs):.1f} ms/frame"
          f"  (ratio {statistics.median(theirs) / statistics.median(ours):.1f})")


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--format", choices=("mp4", "gif", "both", "none"), default="both")
    p.add_argument("--compare-3d", action="store_true", help="also time matplotlib 3D axes drawing the same scene")
    p.add_argument("--repeats", type=int, default=5)
    p.add_argument("--fps", type=float, default=30.0)
    args = p.parse_args(argv)

    import whipple_kick as wk
    from whipple_kick.simulate.simulation import Scenario, run

    result = run(Scenario())
    formats = {"both": ("mp4", "gif"), "none": ()}.get(args.format, (args.format,))
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
    if args.compare_3d:
        _compare_3d(result, args.repeats, args.fps)
    return 0


if __name__ == "__main__":
    sys.exit(main())
