"""The animation: its timeline, what the scene puts where, and the files it writes (read back)."""
import copy
import math

import imageio_ffmpeg  # the test extra installs it: the mp4 path is tested, not skipped
import numpy as np
import pytest

import whipple_kick as wk
from whipple_kick.errors import InputError
from whipple_kick.figures import animation
from whipple_kick.simulate import simulation


@pytest.fixture(scope="module")
def short():
    """The default case, 0.5 s before and 1 s after the kick start."""
    return simulation.run(simulation.Scenario(duration=1.0))


@pytest.fixture(scope="module")
def fall():
    """Controller off, thesis force-lag tyre, no steer limit (a violent fall within 2 s): falls by roll at 1.35 s."""
    result = simulation.run(simulation.Scenario(controller="off", duration=2.0, tyre_transient="force_lag",
                                                 steer_limit_deg=None))
    assert result.summary["fell"]
    return result


# ------------------------------------------------------------------ timeline

def test_real_time_frames():
    """A 6.5 s run at 30 frames/s in real time: 196 frames, 1/30 s apart, the last at the end exactly."""
    t = animation.frame_times(-0.5, 6.0, fps=30)
    assert t.size == 196
    np.testing.assert_allclose(np.diff(t), 1 / 30, rtol=1e-12)
    assert t[0] == -0.5 and t[-1] == 6.0


def test_slow_motion_frames():
    """0.2x inside the window: simulated time advances 0.2/fps per frame there, 1/fps outside.

    -0.5..0 real time (5 frames at 10/s), 0..1 s slowed (5 video s, 50
    frames): 56 frames in all, ending exactly at 1 s.
    """
    t = animation.frame_times(-0.5, 1.0, fps=10, slow_motion=0.2, slow_window=(0.0, 1.15))
    assert t.size == 56 and t[-1] == 1.0
    step = np.diff(t)
    np.testing.assert_allclose(step[t[:-1] < -1e-12], 0.1, rtol=1e-9)
    np.testing.assert_allclose(step[t[:-1] >= -1e-12], 0.02, rtol=1e-9)


def test_last_frame_is_the_end_when_it_falls_between_frames():
    t = animation.frame_times(0.0, 0.35, fps=10)
    np.testing.assert_allclose(t, [0.0, 0.1, 0.2, 0.3, 0.35], atol=1e-15)


# --------------------------------------------------------------------- scene

def test_lane_is_the_steady_path(short):
    """Before the kick the rear contact runs on the lane's centre line (the steady motion's circle).

    Measured: 4.6e-12 m over the 0.5 s of steady running (the steady state
    does not drift); bound 1e-9 m. After the kick the contact leaves it by
    0.32 m within 1 s, which is what the lane is there to show.
    """
    df = short.trajectory
    t = df["time"].to_numpy()
    first = {key: values[0] for key, values in animation._sample(df, t[:1]).items()}
    speed = math.hypot(first["velocity_x"], first["velocity_y"])
    before = t <= 0.0
    path, _ = animation._steady_path(first, speed * (t[before] - t[0]))
    contact = np.c_[df["x_rear"].to_numpy()[before], df["y_rear"].to_numpy()[before]]
    assert np.max(np.hypot(*(path - contact).T)) < 1e-9
    after = t >= 0.9
    path, _ = animation._steady_path(first, speed * (t[after] - t[0]))
    contact = np.c_[df["x_rear"].to_numpy()[after], df["y_rear"].to_numpy()[after]]
    assert np.min(np.hypot(*(path - contact).T)) > 0.1


def test_plate_moves_with_the_run_and_carries_the_rear_wheel(short):
    """The drawn plate moves as plate_y, and the rear contact is on it for the whole kick (as the model assumes).

    Plate displacement equals plate_y - plate_y(kick start) to 1e-15 m;
    the contact stays >= 0.05 m inside the plate's ends and >= 0.24 m
    inside its sides (measured 0.050 and 0.245; the plate is 0.5 m wide).
    """
    t = short.trajectory["time"].to_numpy()
    times = t[(t >= 0.0) & (t <= 0.15)][::5]
    scene = animation.build_scene(short, times)
    contact = next(item for item in scene.items if item.name == "rear lateral force").points[:, 0, :]
    plate = scene.plate
    moved = plate[:, 0, 1] - plate[0, 0, 1]
    np.testing.assert_allclose(moved, scene.samples["plate_y"] - scene.samples["plate_y"][0], atol=1e-15)
    assert np.all(contact[:, 0] - plate[:, 0, 0] >= 0.05 - 1e-9)
    assert np.all(plate[:, 1, 0] - contact[:, 0] >= 0.05 - 1e-9)
    assert np.all(contact[:, 1] - plate[:, 0, 1] >= 0.2)
    assert np.all(plate[:, 2, 1] - contact[:, 1] >= 0.2)


def test_force_arrows_are_the_tyre_forces_at_one_scale(short):
    """Arrow vector = force x (0.5 m / static rear load), lateral along the wheel's lateral axis, load up.

    Exact to round-off (1e-12 m): the arrows are drawn from the trajectory's
    applied forces, not from a second computation.
    """
    t = short.trajectory["time"].to_numpy()
    times = t[::100]
    scene = animation.build_scene(short, times)
    scale = animation.FORCE_ARROW_M / short.summary["bicycle"]["static_load_rear_n"]
    items = {item.name: item.points for item in scene.items}
    for wheel in ("rear", "front"):
        lateral = items[f"{wheel} lateral force"]
        length = np.linalg.norm(lateral[:, 1] - lateral[:, 0], axis=1)
        np.testing.assert_allclose(length, np.abs(scene.samples[f"fy_{wheel}"]) * scale, rtol=0, atol=1e-12)
        assert np.all(np.abs(lateral[:, 1, 2] - lateral[:, 0, 2]) < 0.05 * length + 1e-12)   # nearly level
        load = items[f"{wheel} load"]
        np.testing.assert_allclose(load[:, 0, 2] - load[:, 1, 2], scene.samples[f"fz_{wheel}"] * scale, atol=1e-12)


def _placed(scene, params, point, k=0):
    """A benchmark-frame point of the nominal bicycle carried with the rear frame to the scene's frame ``k``."""
    steady = wk.geometry.evaluate({q: scene.samples[q] for q in wk.geometry.COORDINATES}, params)
    body = wk.geometry.benchmark_to_body(point, params)
    return steady.points["rear_wheel_centre"][k] + steady.frames["C"][k] @ body


def test_rider_is_drawn_on_the_bicycle(short):
    """The Yeadon rider sits where the run seated it: hands at the grips, feet at the crank axle.

    The summary's posture is riders.place's (the seating points to 1e-12 m). At the steady state the mesh
    point nearest each seating point is within 6 cm of it (the solids' radii: measured 3.5 cm hand, 4.7 cm
    foot) and the seated rider's mass centre lies inside the mesh's bounding box.
    """
    bike = wk.bicycles.load("balanceassist_v1")
    rider = wk.riders.yeadon_rider("jason", mass_kg=short.summary["bicycle"]["rider_mass_kg"])
    seated = wk.riders.place(bike, rider)
    posture = short.summary["bicycle"]["rider_posture"]
    for name in ("seat", "bottom_bracket", "left_grip"):
        np.testing.assert_allclose(posture[f"{name}_m"], getattr(seated, name), rtol=0, atol=1e-12)
    scene = animation.build_scene(short, short.trajectory["time"].to_numpy()[:1])
    params = animation._model_parameters(short, None)
    rider_points = np.concatenate([item.points[0] for item in scene.items if item.kind == "hull"])
    for target in (seated.left_grip, seated.left_grip * [1, -1, 1], seated.bottom_bracket):
        assert np.min(np.linalg.norm(rider_points - _placed(scene, params, target), axis=1)) < 0.06
    com = _placed(scene, params, seated.com)
    assert np.all(rider_points.min(axis=0) < com) and np.all(com < rider_points.max(axis=0))


def test_the_rider_drawn_is_the_runs_not_seated_again(monkeypatch):
    """A rider shifted for a rear load share (0.70: about -0.1 m) is drawn where the run had it, from the summary.

    Before, the animation seated the rider again with riders.place, without the shift: the hands were drawn
    a shift away from the grips the model's rider held. Seating is refused here, and the drawn hands are
    within 6 cm of the shifted grip (a hand's radius, as above); every point of the rider is drawn the shift
    ahead of the same posture unshifted (1e-12 m: round-off).
    """
    result = simulation.run(simulation.Scenario(fz_n=635.0, rear_load_share=0.70, duration=0.3))
    shift = result.summary["bicycle"]["rider_shift_m"]
    assert shift < -0.08

    def refuse(*args, **kwargs):
        raise AssertionError("the animation seated the rider again")
    monkeypatch.setattr(wk.riders, "place", refuse)
    monkeypatch.setattr(wk.riders, "for_load_share", refuse)
    scene = animation.build_scene(result, result.trajectory["time"].to_numpy()[:1])
    params = animation._model_parameters(result, None)
    hands = np.concatenate([item.points[0] for item in scene.items if item.name.endswith("left hand")])
    grip = np.array(result.summary["bicycle"]["rider_posture"]["left_grip_m"])
    assert np.min(np.linalg.norm(hands - _placed(scene, params, grip), axis=1)) < 0.06
    # The same posture without the shift: every point of the rider is drawn the shift further forward.
    unshifted = copy.deepcopy(result)
    posture = unshifted.summary["bicycle"]["rider_posture"]
    for name in ("seat_m", "bottom_bracket_m", "left_grip_m"):
        posture[name][0] -= shift
    before = {item.name: item.points[0] for item in animation.build_scene(unshifted, scene.times).items}
    forward = _placed(scene, params, [1.0, 0.0, 0.0]) - _placed(scene, params, [0.0, 0.0, 0.0])
    for item in scene.items:
        if item.kind == "hull":
            np.testing.assert_allclose(item.points[0] - before[item.name], np.tile(shift * forward, (len(before[item.name]), 1)), atol=1e-12)


def test_a_leaning_rider_is_drawn_leaning_with_the_hands_on_the_bar():
    """rider_body "leaning", arms "on": the upper body turns with the run's lean about the hip axis, the
    forearms and hands turn with the bar, the legs stay in the rear frame.

    In the rear frame's axes, each upper-body point moves on a circle about the hip axis: its distance from
    the axis is kept and its chord is 2 r sin(|lean|/2) (to 1e-9 m: round-off), and the head moves to the
    side the lean is positive to (q11 > 0: lean right, C.y right). The hands keep their place in the front
    frame (1e-9 m); the legs theirs in the rear frame.
    """
    result = simulation.run(simulation.Scenario(rider_body="leaning", arms="on", lqr_model="simulated", duration=1.0))
    lean = result.trajectory["upper_body_lean"].to_numpy()
    k = int(np.argmax(np.abs(lean)))
    assert abs(lean[k]) > math.radians(0.5)
    times = result.trajectory["time"].to_numpy()[[k, k]]
    scene = animation.build_scene(result, times)
    items = {item.name: item.points for item in scene.items}
    assert {"G chest", "G head", "E left hand", "E right forearm", "C left shank"} <= set(items)
    assert not any(name.startswith("C chest") for name in items)
    params = animation._model_parameters(result, None)
    pose = wk.geometry.evaluate({q: scene.samples[q] for q in wk.geometry.COORDINATES}, params)
    rot_c, origin_c = pose.frames["C"][0], pose.points["rear_wheel_centre"][0]
    bodies = {body.frame: body for body in animation._bicycle_bodies(result.scenario, result.summary, params)}
    body = result.summary["bicycle"]["body"]
    axis = np.array([math.cos(body["hip_tilt"]), 0.0, -math.sin(body["hip_tilt"])])
    hinge = np.array([body["lh1"], 0.0, body["lh3"]])
    for name in ("chest", "head"):
        drawn = (items[f"G {name}"][0] - origin_c) @ rot_c            # in C's axes
        rest = bodies["G"].solids[name]
        radial = lambda p: (p - hinge) - np.outer((p - hinge) @ axis, axis)
        r = np.linalg.norm(radial(rest), axis=1)
        np.testing.assert_allclose(np.linalg.norm(radial(drawn), axis=1), r, atol=1e-9)
        np.testing.assert_allclose(np.linalg.norm(drawn - rest, axis=1), 2 * r * abs(math.sin(lean[k] / 2)),
                                   atol=1e-9)
    head_side = np.mean((items["G head"][0] - origin_c) @ rot_c, axis=0)[1] - np.mean(bodies["G"].solids["head"],
                                                                                        axis=0)[1]
    assert np.sign(head_side) == np.sign(lean[k])
    np.testing.assert_allclose((items["C left shank"][0] - origin_c) @ rot_c, bodies["C"].solids["left shank"],
                               atol=1e-9)
    rot_e, origin_e = pose.frames["E"][0], pose.points["front_wheel_centre"][0]
    np.testing.assert_allclose((items["E left hand"][0] - origin_e) @ rot_e, bodies["E"].solids["left hand"],
                               atol=1e-9)


def test_camera_looks_at_its_target():
    """The followed point projects to the image centre; far level ground approaches the horizon."""
    target = np.array([[2.0, 0.5, -0.75]])
    camera = animation.Camera(target, np.array([0.3]))
    xy, depth = camera.project(0, target[0])
    np.testing.assert_allclose(xy, [0.0, 0.0], atol=1e-12)
    assert depth == pytest.approx(animation._CAMERA_DISTANCE_M)
    heading = 0.3 + animation._CAMERA_AZIMUTH_RAD
    far = target[0] + 1e7 * np.array([math.cos(heading), math.sin(heading), 0.0])
    far[2] = 0.0
    assert camera.project(0, far)[0][1] == pytest.approx(camera.horizon, abs=1e-6)


# --------------------------------------------------------------------- files

def test_mp4_plays_with_the_expected_frames(short, tmp_path):
    """Read back with imageio-ffmpeg (the library that wrote it): frame count, size and rate."""
    path = tmp_path / "kick.mp4"
    movie = animation.animate(short, path, fps=10, size=(320, 180))
    assert movie.frames == 56 and movie.times[-1] == 1.0
    frames, seconds = imageio_ffmpeg.count_frames_and_secs(str(path))
    reader = imageio_ffmpeg.read_frames(str(path))
    meta = next(reader)
    decoded = sum(1 for _ in reader)
    assert frames == decoded == 56
    assert tuple(meta["size"]) == (320, 180) and meta["fps"] == 10.0
    assert seconds == pytest.approx(5.6, abs=0.1)


def test_gif_plays_with_the_expected_frames(short, tmp_path):
    """Read back with Pillow (the library that wrote it): frame count, size, and the frame delays.

    GIF delays are whole centiseconds; rounding the frame times keeps the
    total: 56 frames at 30/s play 1.87 s (each delay 30 or 40 ms).
    """
    from PIL import Image

    path = tmp_path / "kick.gif"
    movie = animation.animate(short, path, fps=30, size=(160, 90), time_range=(-0.5, 0.0))
    with Image.open(path) as image:
        assert image.n_frames == movie.frames == 16
        assert image.size == (160, 90)
        delays = []
        for k in range(image.n_frames):
            image.seek(k)
            delays.append(image.info["duration"])
    assert set(delays) <= {30, 40}
    assert sum(delays) == pytest.approx(1000 * movie.frames / 30, abs=10)


def test_a_falling_run_ends_at_the_fall(fall, tmp_path):
    """Acceptance: the last frame is the fall (t = fall time exactly) and no frame comes after it."""
    from PIL import Image

    movie = animation.animate(fall, tmp_path / "fall.gif", fps=10, size=(160, 90))
    fall_time = fall.summary["fall_time_s"]
    assert movie.times[-1] == fall_time
    assert np.all(movie.times <= fall_time)
    expected = animation.frame_times(-0.5, fall_time, 10, 0.2, (0.0, 1.15))
    np.testing.assert_array_equal(movie.times, expected)
    with Image.open(movie.path) as image:
        assert image.n_frames == expected.size


def test_still_writes_one_frame(short, tmp_path):
    from PIL import Image

    animation.still(short, tmp_path / "frame.png", 0.1, size=(320, 180))
    with Image.open(tmp_path / "frame.png") as image:
        assert image.size == (320, 180)


@pytest.mark.parametrize("options, fragments", [
    (dict(fps=0.5), ["frame rate", "[1, 120]", "frames/s"]),
    (dict(slow_motion=0.0), ["slow-motion factor", "(0, 1]"]),
    (dict(slow_motion=2.0), ["slow-motion factor", "(0, 1]"]),
    (dict(slow_after=-1.0), ["slow-motion time", "[0, 60]", "s"]),
    (dict(size=(321, 180)), ["width", "even", "px"]),
    (dict(size=(320, 20)), ["height", "[64, 3840]", "px"]),
    (dict(time_range=(0.5, 9.0)), ["animation end", "s"]),
])
def test_bad_options_are_one_line_input_errors(short, tmp_path, options, fragments):
    with pytest.raises(InputError) as info:
        animation.animate(short, tmp_path / "x.gif", **options)
    message = str(info.value)
    assert "\n" not in message
    for fragment in fragments:
        assert fragment in message


def test_unknown_suffix_and_custom_tyres_are_input_errors(tmp_path):
    with pytest.raises(InputError, match=r"\.mp4 or \.gif"):
        animation.animate(None, tmp_path / "x.avi")
    tyre = wk.tyres.linear_tyre(100.0, 0.01, 1e5)
    result = simulation.run(simulation.Scenario(symmetric_tyres=True, duration=0.2, settle=0.1),
                            tyres=(tyre, tyre))
    with pytest.raises(InputError, match=r"tyres=.rear, front."):
        animation.animate(result, tmp_path / "x.gif", size=(160, 90))
    movie = animation.animate(result, tmp_path / "x.gif", size=(160, 90), tyres=(tyre, tyre))
    assert movie.frames > 1


def test_lumped_rider_is_the_rear_frame_inertia_ellipsoid():
    """A preset with the rider lumped into the rear frame is drawn as the uniform ellipsoid of its inertia.

    The drawn surface's extents along the principal axes are the semi-axes
    a, b, c; m (b^2 + c^2) / 5 etc. give back the rear frame's principal
    moments of inertia to 1e-12 relative (round-off).
    """
    moore = wk.bicycles.load("balanceassist_635N").moore
    inertia = np.array([[moore["ic11"], 0.0, moore["ic31"]], [0.0, moore["ic22"], 0.0],
                        [moore["ic31"], 0.0, moore["ic33"]]])
    points = animation._inertia_ellipsoid(moore["mc"], inertia)
    moments, axes = np.linalg.eigh(inertia)
    a, b, c = np.max(np.abs(points @ axes), axis=0)
    rebuilt = moore["mc"] / 5.0 * np.array([b * b + c * c, a * a + c * c, a * a + b * b])
    np.testing.assert_allclose(rebuilt, moments, rtol=1e-12)


def test_a_preset_with_the_rider_included_animates(tmp_path):
    """The thesis' own set-up (rider lumped into the rear frame, no seating geometry) draws and writes."""
    result = simulation.run(simulation.Scenario.thesis(duration=0.3, settle=0.1))
    scene = animation.build_scene(result, result.trajectory["time"].to_numpy()[::50])
    names = [item.name for item in scene.items if item.kind == "hull"]
    assert names == ["C rear frame and rider (lumped)"]
    movie = animation.animate(result, tmp_path / "thesis.gif", fps=10, size=(160, 90))
    assert movie.times[-1] == pytest.approx(0.3)
