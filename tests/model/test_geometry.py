"""Point positions and body orientations generated from the model's kinematics (geometry.py).

Three independent references: the benchmark parameter set's own geometry
(Meijaard et al. 2007: wheelbase, trail, steer-axis tilt, wheel radii), a
direct SymPy evaluation of ``derivation.kinematics`` (not the generated
NumPy code), and the compiled C model's holonomic-constraint output.
"""
import math

import numpy as np
import pytest

import whipple_kick as wk
from whipple_kick.errors import InputError
from whipple_kick.figures import animation
from whipple_kick.model import geometry
from whipple_kick.model import symbols as S
from whipple_kick.model.symbolic import derivation
from whipple_kick.simulate import simulation


@pytest.fixture(scope="module")
def steady():
    """The default case's steady state: the first sample of a short default run, and its parameters."""
    result = simulation.run(simulation.Scenario(duration=0.3))
    first = result.trajectory.iloc[:1]
    q = {name: first[animation.COLUMNS[name]].to_numpy() for name in geometry.COORDINATES}
    return result, q, animation._model_parameters(result, None)


@pytest.mark.parametrize("bicycle", ["benchmark", "balanceassist_v1"])
def test_nominal_pose_is_the_benchmark_geometry(bicycle):
    """Knife-edge wheels, upright, steer 0, pitch = steer-axis tilt: the benchmark's own picture.

    Wheel centres at (0, 0, -rR) and (w, 0, -rF), front contact at (w, 0, 0),
    the steer axis meets the ground the trail c ahead of the front contact
    and leans back by lam. Measured: every difference <= 2.3e-16; bound
    1e-12 m / rad (a wrong Moore <-> benchmark conversion or frame is off by
    millimetres at least).
    """
    bike = wk.bicycles.load(bicycle)
    b = bike.benchmark
    p = dict(bike.moore, rtr=0.0, rtf=0.0)
    pose = geometry.evaluate(geometry.nominal_coordinates(p), p)
    point = {name: v[0] for name, v in pose.points.items()}
    np.testing.assert_allclose(point["rear_contact"], [0.0, 0.0, 0.0], atol=1e-12)
    np.testing.assert_allclose(point["rear_wheel_centre"], [0.0, 0.0, -b["rR"]], atol=1e-12)
    np.testing.assert_allclose(point["front_wheel_centre"], [b["w"], 0.0, -b["rF"]], atol=1e-12)
    np.testing.assert_allclose(point["front_contact"], [b["w"], 0.0, 0.0], atol=1e-12)
    axis = pose.frames["C"][0][:, 2]                    # C.z is the steer axis, pointing down
    ground = point["steer_axis_point"] - point["steer_axis_point"][2] / axis[2] * axis
    assert ground[0] == pytest.approx(b["w"] + b["c"], abs=1e-12)
    assert math.atan2(axis[0], axis[2]) == pytest.approx(b["lam"], abs=1e-12)
    # The mass centres of the bicycle-only set (rear frame B, front frame H).
    if not bike.includes_rider:
        np.testing.assert_allclose(point["rear_frame_mass_centre"], [b["xB"], 0.0, b["zB"]], atol=1e-12)
        np.testing.assert_allclose(point["front_frame_mass_centre"], [b["xH"], 0.0, b["zH"]], atol=1e-12)


def test_steady_state_agrees_with_the_symbolic_kinematics(steady):
    """Acceptance: wheel centres, steer axis and contacts equal derivation.kinematics evaluated by SymPy.

    Measured differences <= 2.3e-16 m (unit vectors: 0); bound 1e-9 m as
    the issue asks. Frame orientations are checked the same way.
    """
    _, q, params = steady
    pose = geometry.evaluate(q, params)
    kin = derivation.kinematics(tyre_model=True)
    N, origin = kin.frames["N"], kin.points["O"]
    values = {qi: float(q.get(f"q{i + 1}", [0.0])[0]) for i, qi in enumerate(kin.q)}   # q11: not drawn, 0
    values.update({S.sym(name): float(params[name]) for name in geometry.PARAMETER_NAMES})

    def numeric(matrix):
        return np.array(matrix.xreplace(values).evalf(30), dtype=float)

    for name, point in geometry.POINTS.items():
        expected = numeric(kin.points[point].pos_from(origin).to_matrix(N)).ravel()
        np.testing.assert_allclose(pose.points[name][0], expected, rtol=0, atol=1e-9, err_msg=name)
    for frame in geometry.FRAMES:
        np.testing.assert_allclose(pose.frames[frame][0], numeric(N.dcm(kin.frames[frame])), rtol=0, atol=1e-12,
                                   err_msg=frame)


def test_steady_state_contacts_are_on_the_ground(steady):
    """Acceptance: both contacts on the ground, each tyre pressed into it by no more than its compression.

    Rear contact z is 0 by construction (q1, q2 in the ground); the front
    contact's z is the holonomic residual, which the compiled C model also
    reports: they agree to 1e-15 m (measured 0 vs 5.6e-17). The drawn tyre
    disc's lowest point lies q_c - rt (1 - cos camber) below the ground
    (torus crown): between 0 and the compression q9 / q10 (3.4-6.0 mm), as
    checked here with 1e-12 m slack for round-off.
    """
    result, q, params = steady
    pose = geometry.evaluate(q, params)
    assert pose.points["rear_contact"][0, 2] == 0.0
    front_z = pose.points["front_contact"][0, 2]
    assert abs(front_z) <= 1e-9
    assert front_z == pytest.approx(result.trajectory["holonomic_residual"].iloc[0], abs=1e-15)
    scene = animation.build_scene(result, result.trajectory["time"].to_numpy()[:1])
    for wheel, compression, crown, camber in (
            ("rear", q["q9"][0], params["rtr"], result.trajectory["camber_rear"].iloc[0]),
            ("front", q["q10"][0], params["rtf"], result.trajectory["camber_front"].iloc[0])):
        disc = next(item for item in scene.items if item.name == f"{wheel} wheel")
        lowest = disc.points[0, :, 2].max()              # z is down
        assert -1e-12 <= lowest <= compression + 1e-12
        assert lowest == pytest.approx(compression - crown * (1 - math.cos(camber)), abs=1e-12)


def test_body_points_follow_the_rear_frame(steady):
    """A benchmark-frame point made rigid in C (benchmark_to_body) returns to where it was at the nominal pose.

    And at the steady state it sits where the model's rear-frame mass centre
    construction puts such a point (l1, l2 along C from the wheel centre):
    both to 1e-12 m (measured 1e-16).
    """
    _, q, params = steady
    knife = dict(params, rtr=0.0, rtf=0.0)
    point = np.array([0.4, 0.1, -0.9])
    body = geometry.benchmark_to_body(point, knife)
    nominal = geometry.evaluate(geometry.nominal_coordinates(knife), knife)
    placed = nominal.points["rear_wheel_centre"][0] + nominal.frames["C"][0] @ body
    np.testing.assert_allclose(placed, point, atol=1e-12)
    pose = geometry.evaluate(q, params)
    mass_centre = pose.points["rear_wheel_centre"][0] + pose.frames["C"][0] @ [params["l1"], 0.0, params["l2"]]
    np.testing.assert_allclose(mass_centre, pose.points["rear_frame_mass_centre"][0], atol=1e-12)


def test_many_instants_at_once_equal_one_by_one(steady):
    """Vectorised evaluation over n instants equals n single evaluations (exactly: same arithmetic)."""
    result, _, params = steady
    df = result.trajectory.iloc[::50]
    q = {name: df[animation.COLUMNS[name]].to_numpy() for name in geometry.COORDINATES}
    many = geometry.evaluate(q, params)
    for k in (0, len(df) // 2, len(df) - 1):
        one = geometry.evaluate({name: v[k] for name, v in q.items()}, params)
        for name in geometry.POINTS:
            np.testing.assert_array_equal(many.points[name][k], one.points[name][0])


def test_missing_names_are_input_errors():
    p = dict(wk.bicycles.load("balanceassist_v1").moore, rtr=0.01)
    q = dict.fromkeys(geometry.COORDINATES, 0.0)
    with pytest.raises(InputError, match="rtf"):
        geometry.evaluate(q, p)
    p["rtf"] = 0.01
    del q["q9"]
    with pytest.raises(InputError, match="q9"):
        geometry.evaluate(q, p)
