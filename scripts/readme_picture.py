"""Redraw the README's picture: docs/kick.gif, the kick of the default run in slow motion.

    python scripts/readme_picture.py            # writes docs/kick.gif (about 0.9 MB)

The default case (``simulate --pressure 400 --fz 635``: T03 at 400 kPa, LQR
rider, 150 mm kick in 0.150 s), from 0.2 s before the kick to 1.4 s after
its start, the kick and 0.6 s after it at quarter speed; 640 x 360 pixels at
10 frames per second, a GIF so that any README viewer plays it.
"""
import pathlib
import sys

HERE = pathlib.Path(__file__).resolve().parent


def main(argv=None):
    import whipple_kick as wk
    from whipple_kick.simulate.simulation import Scenario, run

    path = pathlib.Path(argv[0]) if argv else HERE.parent / "docs" / "kick.gif"
    result = run(Scenario(pressure_kpa=400.0, fz_n=635.0))
    movie = wk.animation.animate(result, path, fps=10, slow_motion=0.25, slow_after=0.6, time_range=(-0.2, 1.4),
                                 size=(640, 360), dpi=60)
    print(f"{movie.path}: {movie.frames} frames, {movie.video_duration_s:.1f} s, "
          f"{movie.path.stat().st_size / 1e6:.2f} MB")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
