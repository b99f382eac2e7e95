"""The rider's degrees of freedom as declared parts (whipple_kick.model.parts).

A part is declared once, in its own module; the derivation, the generated code and its cache key, the
layouts, the steady state, the trajectory's columns and the gain table follow from the declaration. The
test below shows it: a part declared here, in this module only (no other file touched), is built, run and
energy-checked.
"""
import dataclasses
import inspect

import numpy as np
import pytest

import whipple_kick as wk
from whipple_kick.library import inputs
from whipple_kick.model import energy, parts, slip
from whipple_kick.simulate import assembly, lsoda, results, steady


def test_the_trunk_is_a_declared_part_with_units_and_sources():
    """Every symbol the trunk declares has a unit and a description; its layout appends q11 and u11 after the
    base model's states, so every base state keeps its index; the rigid rider's model has no trunk state."""
    trunk = parts.REGISTRY["trunk"]
    assert trunk.source and trunk.coordinates == ("q11",) and trunk.speeds == ("u11",)
    for name, description, unit, _ in trunk.symbols:
        assert description and unit, name
    rigid, leaning = slip.for_parts(()), slip.for_parts(("trunk",))
    assert rigid is slip.layout.BASE and "q11" not in rigid.X and "kq11" not in rigid.P
    assert leaning.STATE_NAMES[:len(rigid.STATE_NAMES)] == rigid.STATE_NAMES
    assert leaning.STATE_NAMES[len(rigid.STATE_NAMES):] == ("q11", "u11")
    assert leaning.GAIN_STATES["kq11"] == "q11" and leaning.OUT["hip_torque"] >= len(rigid.OUTPUT_NAMES)
    assert slip.for_parts((), True).REFLEX_STATES == slip.REFLEX_STATES and not rigid.REFLEX_STATES


def test_the_model_is_declared_not_read_from_the_parameter_names():
    """The model's parameters carry their model: a body with some of a part's parameters is refused for the
    model with the part (one line naming what is missing), and a part's parameters for a model without it are
    refused rather than choosing the part; a nonzero delay needs the delay filter; a plain mapping is no
    model's parameters, and values that contradict their model are refused."""
    moore = wk.assembly.build_bicycle(wk.Scenario().bicycle_spec)[0]
    tyre = wk.tyres.load("T03", pressure_kpa=400)
    leaning = slip.Model(("trunk",))
    with pytest.raises(wk.InputError, match=r"the leaning upper body needs all of .*; missing hip_tilt"):
        slip.model_parameters(moore, tyre, tyre, model=leaning, body={"kh": 1.0, "ch": 2.0})
    with pytest.raises(wk.InputError, match=r"\['ch', 'kh'\] are not the rigid model's \(they are the trunk part's"):
        slip.model_parameters(moore, tyre, tyre, body={"kh": 1.0, "ch": 2.0})
    with pytest.raises(wk.InputError, match="a delay needs the model with the delay filter"):
        slip.model_parameters(moore, tyre, tyre, body={"reflex_delay": 0.05})
    params = slip.model_parameters(moore, tyre, tyre, model=slip.Model((), True), body={"reflex_delay": 0.05})
    assert params.model.layout is slip.for_parts((), True) and params.copy().model is params.model
    with pytest.raises(TypeError, match="not a plain mapping"):
        slip.CompiledRHS(dict(params))
    # Values that contradict their model are refused, not read as another model.
    with pytest.raises(wk.InputError, match=r"reflex_delay = 0\.05 s does not fit the rigid model"):
        slip.CompiledRHS(slip.Parameters(slip.Model(), params))
    with pytest.raises(wk.InputError, match="tyre_transient = 3 is not the force_lag model's index 2"):
        slip.CompiledRHS(slip.Parameters(slip.Model((), True, "force_lag"), params))


def _bare_part(name, **declared):
    """A part with nothing in it but its name and its relations to other parts (never built here)."""
    return parts.Part(name=name, description="a test part", source="this test", symbols=(), coordinates=(),
                      speeds=(), parameters=(), gains={}, columns={}, outputs={}, build=lambda m: None, **declared)


def test_a_parts_needs_are_declared_and_checked_and_the_declaration_order_does_not_matter(monkeypatch):
    """The arms are built after the trunk because they say so (``after``), not because the trunk is declared
    first: with the registry in the reverse order the model's parts, layout and cache key are the same. A
    part that needs another (``needs``) is refused, in one line naming both and how to select the missing
    one, by a model without it; a circle of parts each built after the other is refused."""
    assert parts.ARMS.after == ("trunk",) and not parts.ARMS.needs
    forward = slip.Model(("arms", "trunk"))
    fingerprint = forward.layout.fingerprint()
    assert forward.parts == ("trunk", "arms") == slip.Model(("trunk", "arms")).parts
    reversed_registry = dict(reversed(list(parts.REGISTRY.items())))
    assert list(reversed_registry)[:2] == ["arms", "trunk"]   # the arms now declared before the trunk
    monkeypatch.setattr(parts, "REGISTRY", reversed_registry)
    assert tuple(p.name for p in parts.named(("trunk", "arms"))) == ("trunk", "arms")
    assert slip.layout.Layout(("arms", "trunk")).fingerprint() == fingerprint
    parts.declare(_bare_part("handlebar_bag", needs=("arms",), after=("trunk",)))
    with pytest.raises(wk.InputError, match=r"^handlebar_bag \(part 'handlebar_bag'\) needs the arms on the bar"):
        parts.named(("handlebar_bag", "trunk"))
    with pytest.raises(wk.InputError) as refused:
        parts.named(("handlebar_bag",))
    assert str(refused.value) == ("handlebar_bag (part 'handlebar_bag') needs the arms on the bar (part 'arms'), "
                                  "which the model lacks; select it with arms 'on'")
    assert [p.name for p in parts.named(("handlebar_bag", "arms", "trunk"))] == ["trunk", "arms", "handlebar_bag"]
    assert [p.name for p in parts.named(("handlebar_bag", "arms"))] == ["arms", "handlebar_bag"]
    parts.declare(_bare_part("a", after=("b",)))
    parts.declare(_bare_part("b", after=("a",)))
    with pytest.raises(ValueError, match=r"parts \['a', 'b'\] need or follow each other in a circle"):
        parts.named(("a", "b"))
    with pytest.raises(ValueError, match="names itself"):
        _bare_part("c", needs=("c",))


def test_merged_upper_body_conserves_mass_and_mass_centre():
    """merge_into_rear_frame against a hand computation: masses add, the mass centre is the weighted mean, and
    the inertia about the new mass centre is each body's own plus its parallel-axis term. The upper body is
    a 40 kg point-like block 0.3 m above and 0.1 m ahead of the hip, turned by the hinge's tilt."""
    moore = {"mc": 10.0, "l1": 0.3, "l2": -0.2, "ic11": 1.0, "ic22": 1.5, "ic33": 0.8, "ic31": 0.1}
    body = {"hip_tilt": 0.0, "lh1": 0.2, "lh3": -0.5, "mt": 40.0, "lt1": 0.1, "lt3": -0.3,
            "it11": 2.0, "it22": 2.5, "it33": 0.5, "it31": 0.05}
    out = parts.merge_into_rear_frame(moore, body)
    assert out["mc"] == 50.0
    r_c, r_g = np.array([0.3, -0.2]), np.array([0.3, -0.8])
    r = (10.0 * r_c + 40.0 * r_g) / 50.0
    assert (out["l1"], out["l2"]) == pytest.approx(tuple(r), abs=1e-15)
    d_c, d_g = r_c - r, r_g - r
    assert out["ic22"] == pytest.approx(1.5 + 2.5 + 10.0 * d_c @ d_c + 40.0 * d_g @ d_g, rel=1e-14)
    assert out["ic11"] == pytest.approx(1.0 + 2.0 + 10.0 * d_c[1] ** 2 + 40.0 * d_g[1] ** 2, rel=1e-14)
    assert out["ic31"] == pytest.approx(0.1 + 0.05 - 10.0 * d_c[0] * d_c[1] - 40.0 * d_g[0] * d_g[1], rel=1e-14)
    # A tilted hinge turns the upper body's axes: its inertia rotates, its mass centre follows (G.x, G.z in C).
    tilted = parts.merge_into_rear_frame(moore, dict(body, hip_tilt=0.3))
    c, s = np.cos(0.3), np.sin(0.3)
    g = np.array([0.2, -0.5]) + 0.1 * np.array([c, -s]) - 0.3 * np.array([s, c])
    assert (tilted["l1"], tilted["l2"]) == pytest.approx(tuple((10.0 * r_c + 40.0 * g) / 50.0), abs=1e-15)
    trace = 1.0 + 1.5 + 0.8 + 2.0 + 2.5 + 0.5
    d_c, d_g = r_c - np.array([tilted["l1"], tilted["l2"]]), g - np.array([tilted["l1"], tilted["l2"]])
    trace += 2 * (10.0 * d_c @ d_c + 40.0 * d_g @ d_g)   # the trace is invariant under the rotation
    assert tilted["ic11"] + tilted["ic22"] + tilted["ic33"] == pytest.approx(trace, rel=1e-14)


# ------------------------------------------------------------------ one more degree of freedom

def _build_shift(m):
    """A mass on the saddle sliding sideways along the rear frame's C.y (q12 [m]) on SymPy's PrismaticJoint,
    held by a LinearSpring and a LinearDamper along a LinearPathway."""
    import sympy.physics.mechanics as me

    kin, b = m.kin, m.par
    N, C = kin.frames["N"], kin.frames["C"]
    q12, u12 = m.coordinate("q12", "u12")
    do = kin.points["do"]
    rest = do.locatenew("shift_rest", b["ls1"] * C.x + b["ls3"] * C.z)   # fixed in the rear frame
    rest.v2pt_theory(do, N, C)
    # The mass slides on SymPy's PrismaticJoint along C.y; its own frame S (a joint's child has one) stays
    # parallel to C.
    S = me.ReferenceFrame("S")
    so = me.Point("shift_mass")
    mass = m.body("shifting_mass", so, S, b["ms"], me.inertia(S, b["is11"], b["is22"], b["is33"]))
    joint = me.PrismaticJoint("shift", m.rigid_body("rear_frame"), mass, coordinates=q12, speeds=u12,
                              parent_point=rest, joint_axis=C.y)
    so.v1pt_theory(rest, N, C)   # the joint gives its velocity in the rear frame; Kane's method reads it in N
    m.system.add_joints(joint)
    # The spring and the damper pull along a straight pathway from an anchor in the rear frame 1 m to the
    # left of the rest point: its length 1 + q12 keeps its direction (C.y) for any shift under 1 m, where a
    # pathway from the rest point itself, of length |q12|, would have none at q12 = 0. The derivation takes
    # the spring's store and the damper's dissipation from them.
    anchor = rest.locatenew("shift_anchor", -C.y)
    anchor.v2pt_theory(do, N, C)
    pathway = me.LinearPathway(anchor, so)
    m.system.add_actuators(me.LinearSpring(b["ks"], pathway, equilibrium_length=1),
                           me.LinearDamper(b["cs"], pathway))
    m.outputs["shift_force"] = -(b["ks"] * q12 + b["cs"] * u12)


def _shift_part():
    return parts.Part(
        name="shift",
        description="a mass on the saddle sliding sideways on a spring-damper (a test part)",
        source="this test",
        symbols=(("q12", "sideways shift of the sliding mass along C.y", "m", "coordinate"),
                 ("u12", "rate of q12", "m/s", "speed"),
                 ("ms", "sliding mass", "kg", "constant"),
                 ("ls1", "its rest point from the rear wheel centre along C.x", "m", "constant"),
                 ("ls3", "its rest point from the rear wheel centre along C.z", "m", "constant"),
                 ("is11", "its moment of inertia about C.x", "kg m^2", "constant"),
                 ("is22", "its moment of inertia about C.y", "kg m^2", "constant"),
                 ("is33", "its moment of inertia about C.z", "kg m^2", "constant"),
                 ("ks", "its lateral spring stiffness", "N/m", "constant"),
                 ("cs", "its lateral damping", "N s/m", "constant"),
                 ("kq12", "steer-torque feedback gain on the shift q12", "N m/m", "constant")),
        coordinates=("q12",), speeds=("u12",),
        parameters=("ms", "ls1", "ls3", "is11", "is22", "is33", "ks", "cs", "kq12"),
        gains={"kq12": "q12"},
        columns={"q12": ("mass_shift", "m"), "u12": ("mass_shift_rate", "m/s")},
        outputs={"shift_force": ("N", "force of the spring-damper on the sliding mass along C.y")},
        build=_build_shift,
        # What a scenario needs to run it: the field that selects it, the fields that set its spring-damper
        # (their ranges, units and defaults), and the values of its other parameters (a 5 kg mass 0.6 m above
        # the rear wheel centre: a test's numbers, not a rider's).
        selected_by=("shift", "on"),
        fields=(parts.Field("shift_stiffness", "ks", "shift stiffness", "N/m", 0.0, 1e6, 2000.0, "this test",
                            refuse_low="leaves the sliding mass with nothing to hold it"),
                parts.Field("shift_damping", "cs", "shift damping", "N s/m", 0.0, 1e5, 20.0, "this test")),
        values={"ms": 5.0, "ls1": 0.1, "ls3": -0.6, "is11": 0.02, "is22": 0.02, "is33": 0.02},
        title="the sliding mass",
    )


@pytest.fixture
def shift(monkeypatch):
    part = _shift_part()
    monkeypatch.setitem(parts.REGISTRY, part.name, part)
    return part


@pytest.mark.slow   # derives and compiles a model nobody else uses (about 40 s)
def test_a_part_declared_here_is_built_run_and_energy_checked(shift):
    """One more degree of freedom, declared in this module only: a 5 kg mass on the saddle sliding sideways on
    a 2000 N/m, 20 N s/m spring-damper (the rider's hips shifting on the saddle, say). Its model is
    derived, generated and compiled on first use; the steady turn solves for its steady shift; a run from a
    roll-rate push with the mass displaced 2 cm balances its energy to integration accuracy (the mass's
    kinetic and potential energy, the spring's store and the damper's dissipation all enter); the trajectory's
    columns and the gain table come from the declaration; the default model is untouched.

    Measured (the spring and damper SymPy actuators along a pathway): balance residual 5.9e-10 J against
    512 J of kinetic energy, the damper dissipating 0.35 J;
    steady shift -2.9e-6 m; the shift spans 33 mm. Bounds: 1e-6 J (rtol 1e-10 integration of the
    quadratures) and the mass moves by more than 1 mm.
    """
    sc = wk.Scenario(duration=1.0, output_rate=200.0)
    base = assembly.assemble(sc, inputs.kick_of(sc.validate())).params
    assert base.model.layout is slip.layout.BASE
    # No kick (the plate's stop is an impulse the run's pipeline carries across; the push here is enough).
    params = slip.Parameters(slip.Model(("shift",), transient=base.model.transient), base)
    params.update(ms=5.0, ls1=0.1, ls3=-0.6, is11=0.02, is22=0.02, is33=0.02, ks=2000.0, cs=20.0, kq12=0.0,
                  kick_D=0.0)
    layout = params.model.layout
    assert layout.part_names == ("shift",) and layout.GAIN_STATES["kq12"] == "q12"
    ss = steady.steady_state(params, 3.0)
    assert "q12" in ss.unknowns and abs(ss.unknowns["q12"]) < 1e-3
    rhs = slip.CompiledRHS(ss.params)
    assert rhs.layout is layout and len(ss.x) == len(layout.STATE_NAMES)
    x0 = ss.x.copy()
    x0[slip.X["u4"]] += 0.3
    x0[layout.X["q12"]] += 0.02
    traj = lsoda.integrate(rhs, x0, 2.0, rtol=1e-10, output_rate=200)
    assert not traj.failed and not traj.fell
    out = rhs.outputs_at(traj.t, traj.x)
    column = {**{n: traj.x[:, slip.X[n]] for n in energy.QUADRATURE_STATES},
              **{n: out[:, layout.OUT[n]] for n in ("kinetic_energy", "potential_energy", "spring_energy")}}
    stored = sum(column[n] for n in ("kinetic_energy", "potential_energy", "spring_energy", "E_carcass_r",
                                     "E_carcass_f"))
    supplied = (sum(column[n] for n in ("W_plate", "W_steer", "W_wheel", "W_zero_slip", "W_moment"))
                - sum(column[n] for n in ("D_slide", "D_damper", "D_carcass")))
    residual = (stored - stored[0]) - (supplied - supplied[0])
    assert np.abs(residual).max() < 1e-6
    shift_m = traj.x[:, layout.X["q12"]]
    assert np.abs(shift_m - shift_m[-1]).max() > 1e-3   # it really moves
    force = out[:, layout.OUT["shift_force"]]
    assert force == pytest.approx(-(2000.0 * shift_m + 20.0 * traj.x[:, layout.X["u12"]]), rel=1e-12, abs=1e-9)
    names = [name for name, _, _ in results.frame_layout("carcass", layout)]
    assert {"mass_shift", "mass_shift_rate", "shift_force"} <= set(names)
    assert "mass_shift" not in [name for name, _, _ in results.frame_layout("carcass", slip.layout.BASE)]


def test_a_parts_scenario_fields_come_from_its_declaration():
    """The parts' fields (the trunk's hip stiffness and damping, the arms' stiffness and damping) are scenario
    fields with the declared defaults, validated with the declared range and unit, refused while the part is
    not selected (rider_body 'rigid', arms 'off') and given CLI flags, all from the declaration; the run's
    part parameters are the fields' values."""
    from whipple_kick import cli
    from whipple_kick.simulate import scenario as scenario_module
    from whipple_kick.simulate.scenario import FIELD_GROUPS, BodySpec, Scenario

    fields = parts.fields()
    assert [f.name for f in fields] == ["hip_stiffness", "hip_damping", "arm_stiffness", "arm_damping"]
    names = [f.name for f in dataclasses.fields(Scenario)]
    source = inspect.getsource(scenario_module)
    for part in (parts.TRUNK, parts.ARMS):
        for f in part.fields:
            assert Scenario.__dataclass_fields__[f.name].default == f.default and f.source
            assert f"    {f.name} : float\n        The {f.label} of {part.title} [{f.unit}]" in Scenario.__doc__
            assert f.name in FIELD_GROUPS["physics"] and f.name in BodySpec.__dataclass_fields__
            # Written in the class body (static readers see it), its declaration read from the part's.
            assert f'    {f.name}: float = part_setting("{part.name}", "{f.name}")' in source
            setting = scenario_module.SETTINGS[f.name]
            assert (setting.part, setting.unit, setting.low, setting.high) == (part.name, f.unit, f.low, f.high)
        # The fields follow the field that selects the part, in declaration order.
        at = names.index(part.selected_by[0])
        assert names[at + 1:at + 1 + len(part.fields)] == [f.name for f in part.fields]
    with pytest.raises(wk.InputError, match=r"hip stiffness = -1.0 N m/rad is outside the allowed range"):
        Scenario(rider_body="leaning", hip_stiffness=-1.0).validate()
    assert "the leaning upper body (rider_body 'leaning')" in Scenario(hip_damping=10.0).unused_fields()["hip_damping"]
    flags = {a.dest: a for a in cli._simulate_parser()._actions}
    assert flags["hip_stiffness"].metavar == "N_M_PER_RAD" and "of the leaning upper body" in flags["hip_stiffness"].help
    sc = Scenario(rider_body="leaning", hip_stiffness=300.0, hip_damping=7.0)
    assert parts.selected(sc) == (parts.TRUNK,) and parts.selected(Scenario()) == ()
    assert parts.TRUNK.field_parameters(sc) == {"kh": 300.0, "ch": 7.0}
    arms = Scenario(arms="on", arm_stiffness=10.0, arm_damping=1.0)
    assert parts.selected(arms) == (parts.ARMS,) and parts.ARMS.field_parameters(arms) == {"ka": 10.0, "ca": 1.0}
    assert "the arms on the bar (arms 'on')" in Scenario(arm_damping=1.0).unused_fields()["arm_damping"]
    from whipple_kick.studies.stability import report
    assert "; the leaning upper body (hip stiffness 300 N m/rad, hip damping 7 N m s/rad)" in report.describe(sc)


def test_a_parts_gains_values_and_rider_parameters_come_from_its_declaration(shift):
    """The rest of a part's footprint in a run, from its declaration: its gains are known to the custom-gains
    check and refused (one line naming the part and how to select it) while the scenario does not select it;
    its declared values and fields are its parameters in the rider's body; the trunk takes its placement and
    inertia from the rider's segments because it declares them (``from_rider``), and a declaration that sets
    one parameter twice is refused."""
    from whipple_kick.simulate import scenario as scenario_module

    cls = scenario_module.with_parts(shift)
    with pytest.raises(wk.InputError) as refused:
        assembly.custom_gains({"kq12": 1.0}, cls())
    assert str(refused.value) == ("gain(s) ['kq12'] feed back the sliding mass's states (q12), which only shift 'on' "
                                  "has (here 'off'); allowed: 0 or the sliding mass")
    assert assembly.custom_gains({"kq12": 1.0}, cls(shift="on"))["kq12"] == 1.0
    body = assembly.rider_body(cls(shift="on", shift_damping=40.0).body_spec, {})
    assert {n: body[n] for n in ("ms", "ls3", "ks", "cs")} == {"ms": 5.0, "ls3": -0.6, "ks": 2000.0, "cs": 40.0}
    assert set(parts.TRUNK.from_rider) < set(slip.parameters.body_names()) - set(parts.TRUNK.gains)
    segments = dict.fromkeys(parts.TRUNK.from_rider, 0.25)
    leaning = assembly.rider_body(wk.Scenario(rider_body="leaning").body_spec, {"body": segments})
    assert all(leaning[n] == 0.25 for n in segments) and leaning["kh"] == 128.0
    with pytest.raises(ValueError, match=r"values \['ms'\] are not among its parameters that nothing else"):
        dataclasses.replace(shift, from_rider=("ms",))


def test_a_part_declared_here_has_its_columns_in_the_stability_study(shift):
    """The linear stability study names a part's states by its declared columns and counts them as the
    rider's body, for a part declared after the study's modules were imported."""
    from whipple_kick.studies.stability import linear, modes

    assert linear.state_labels(body=("q12", "u12"))[-2:] == [("mass_shift", "m"), ("mass_shift_rate", "m/s")]
    assert {"q12", "u12", "q11"} <= modes._body_states() and "q4" not in modes._body_states()


def test_a_part_declared_here_is_in_the_gain_table_and_the_trajectory_columns(shift):
    """The rider's gain table (the LQR design's, the gain check's) and the trajectory's columns and units are
    read from the registry when used, so the part declared after the package was imported is in them, and
    out of them again once it is removed."""
    assert slip.gain_states()["kq12"] == "q12"
    assert slip.gain_names()[:6] == ("kq3", "kq4", "kq7", "ku3", "ku4", "ku7") and "kq12" in slip.gain_names()
    assert results.part_columns()["q12"] == ("mass_shift", "m")
    assert results.unit_of("mass_shift_rate") == "m/s" and results.UNITS["shift_force"] == "N"
    assert "mass_shift" in results.UNITS and "mass_shift" in set(results.UNITS)
    with pytest.raises(wk.errors.InputError, match=r"unknown steer-torque gain\(s\) \['kq99'\]; known: .*'kq12'"):
        assembly.custom_gains({"kq99": 1.0})
    parts.REGISTRY.pop(shift.name)
    try:
        assert "kq12" not in slip.gain_states() and "q12" not in results.part_columns()
        assert "mass_shift" not in results.UNITS
    finally:
        parts.REGISTRY[shift.name] = shift


@pytest.mark.slow   # derives and compiles the shift model when no other test has (about 40 s), then runs it
def test_a_part_declared_here_runs_through_scenario_assemble_and_run_from_its_field_and_flag(shift):
    """The acceptance of issue 42: the sliding-mass part, declared in this module alone, is selected and set
    by scenario fields and command-line flags derived from its declaration (``with_parts``), assembled into
    a model with it and run; its fields are validated and refused while it is off, and the plain Scenario
    has none of them.

    Measured: a 1 s run from the default kick at 3 m/s completes; the mass's shift spans 68 mm (bound 0.1 mm:
    it really is in the model), its spring-damper force is the declared law to rounding (bound rel 1e-12),
    the run's energy balance residual is 1.4e-9 J against 512 J of kinetic energy (bound 1e-6 J, as the
    part's own energy test: the run's rtol 1e-8 integration of the quadratures).
    """
    from whipple_kick import cli
    from whipple_kick.simulate import scenario as scenario_module
    from whipple_kick.simulate import simulation

    cls = scenario_module.with_parts(shift)
    assert "shift" not in wk.Scenario.__dataclass_fields__ and cls.__dataclass_fields__["shift"].default == "off"
    args = cli._simulate_parser(cls).parse_args(["--shift", "on", "--shift-stiffness", "2500", "--shift-damping",
                                                 "30", "--duration", "1.0"])
    sc = cli._scenario_from_args(args, cls).validate()
    assert (sc.shift, sc.shift_stiffness, sc.shift_damping, sc.duration) == ("on", 2500.0, 30.0, 1.0)
    assert shift.selected(sc) and parts.selected(sc) == (shift,) and parts.selected(cls()) == ()
    with pytest.raises(wk.InputError, match=r"shift stiffness = -1.0 N/m is outside the allowed range"):
        cls(shift="on", shift_stiffness=-1.0).validate()
    with pytest.raises(wk.InputError, match="shift stiffness"):   # its low end refused while it is selected
        cls(shift="on", shift_stiffness=0.0).validate()
    assert "the sliding mass (shift 'on')" in cls(shift_damping=5.0).unused_fields()["shift_damping"]
    with pytest.raises(wk.InputError):
        cls(shift_damping=5.0).validate()   # refused, not ignored, while the part is off
    built = assembly.assemble(sc, inputs.kick_of(sc)).params
    assert built.model.parts == ("shift",) and built.model.layout.part_names == ("shift",)
    assert (built["ks"], built["cs"], built["ms"], built["kq12"]) == (2500.0, 30.0, 5.0, 0.0)
    result = simulation.run(sc)
    assert result.summary["outcome"] == "completed"
    traj = result.trajectory
    assert {"mass_shift", "mass_shift_rate", "shift_force"} <= set(traj.columns)
    assert np.ptp(traj["mass_shift"]) > 1e-4
    assert traj["shift_force"].to_numpy() == pytest.approx(
        -(2500.0 * traj["mass_shift"] + 30.0 * traj["mass_shift_rate"]).to_numpy(), rel=1e-12, abs=1e-12)
    assert np.abs(traj[results.BALANCE_COLUMN]).max() < 1e-6


# ------------------------------------------------------------------ the hip on SymPy's joint and actuators

def _hand_written_trunk(m):
    """The trunk as it was built by hand before the hip became a PinJoint with a TorqueActuator: the reference."""
    import sympy.physics.mechanics as me

    kin, b = m.kin, m.par
    N, C = kin.frames["N"], kin.frames["C"]
    q11, u11 = m.coordinate("q11", "u11")
    # No joint: the coordinate, its speed and dq11/dt = u11 by hand.
    m.system.add_coordinates(q11)
    m.system.add_speeds(u11)
    m.system.add_kdes(q11.diff(me.dynamicsymbols._t) - u11)
    H = me.ReferenceFrame("H")
    H.orient_axis(C, C.y, b["hip_tilt"])
    G = me.ReferenceFrame("G")
    G.orient_axis(H, H.x, q11)
    G.set_ang_vel(H, u11 * H.x)
    do = kin.points["do"]
    ho = do.locatenew("ho", b["lh1"] * C.x + b["lh3"] * C.z)
    ho.v2pt_theory(do, N, C)
    go = ho.locatenew("go", b["lt1"] * G.x + b["lt3"] * G.z)
    go.v2pt_theory(ho, N, G)
    m.body("upper_body", go, G, b["mt"], me.inertia(G, b["it11"], b["it22"], b["it33"], 0, 0, b["it31"]))
    kin.frames.update(H=H, G=G)
    kin.points.update(ho=ho, go=go)
    hip_torque = -(b["kh"] * q11 + b["ch"] * u11)
    m.system.add_loads(me.Torque(C, -hip_torque * H.x), me.Torque(G, hip_torque * H.x))
    axis_share = H.x.dot(C.z)
    m.hands_frame, m.hands_angle, m.hands_rate = G, axis_share * q11, axis_share * u11
    m.spring_energy.append(b["kh"] * q11**2 / 2)
    m.damper_dissipation.append(b["ch"] * u11**2)
    m.outputs["hip_torque"] = hip_torque


def _hand_written_arms(m):
    """The arms' loads as written by hand before the TorqueActuator: the reference."""
    import sympy.physics.mechanics as me

    from whipple_kick.model import symbols

    kin, b = m.kin, m.par
    C, E = kin.frames["C"], kin.frames["E"]
    arm_angle = symbols.dyn("q7") - m.hands_angle
    arm_rate = symbols.dyn("u7") - m.hands_rate
    arm_torque = -(b["ka"] * arm_angle + b["ca"] * arm_rate)
    m.system.add_loads(me.Torque(m.hands_frame, -arm_torque * C.z), me.Torque(E, arm_torque * C.z))
    m.spring_energy.append(b["ka"] * arm_angle**2 / 2)
    m.damper_dissipation.append(b["ca"] * arm_rate**2)
    m.outputs["arm_steer_torque"] = arm_torque


def _at_random_points(eom, n=3, seed=42):
    """The equations' mass matrix, forcing, energies and outputs at ``n`` random points (states, parameters,
    inputs and time each uniform in [-1, 1] or, for a parameter, [0.5, 1.5]): one array per point."""
    import sympy as sm
    import sympy.physics.mechanics as me

    names = sorted(eom.extra)
    exprs = [eom.mass_matrix, eom.forcing, eom.kinetic_energy, eom.potential_energy,
             *(eom.extra[k] for k in names)]
    dynamic = sorted(set().union(*(me.find_dynamicsymbols(sm.sympify(e)) for e in exprs)), key=str)
    free = sorted(set().union(*(sm.sympify(e).free_symbols for e in exprs)), key=str)
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(n):
        values = {d: rng.uniform(-1.0, 1.0) for d in dynamic}
        values.update({s: rng.uniform(0.5, 1.5) for s in free})
        f = sm.lambdify([list(values)], exprs, modules="numpy", cse=True)
        out.append(np.concatenate([np.ravel(np.asarray(v, dtype=float)) for v in f(list(values.values()))]))
    return (names, [str(d) for d in dynamic], [str(s) for s in free]), out


@pytest.mark.slow   # two symbolic derivations of the model with the trunk and the arms (about a minute each)
def test_the_hip_on_sympys_pin_joint_and_torque_actuator_gives_the_hand_written_equations(monkeypatch):
    """The trunk's hip is SymPy's PinJoint with the spring-damper a TorqueActuator at it, the arms' spring-damper
    a TorqueActuator between the bar and the hands' frame; the model with both has the same mass matrix,
    forcing, energies and outputs as the hand-written frames, points and loads it replaced, at three random
    points of states, parameters and inputs (relative 1e-12: the two are the same expressions up to the order
    of terms, so only rounding differs).

    Measured: largest relative difference 0; the mass matrix, forcing and energies even compare equal as SymPy
    expressions, and the generated C of the models with the trunk, the arms and both is byte-identical to
    the hand-written one's (sha256 2ed34dec..., 2b5564ee..., 8b86b8fa...), so the regression references hold
    unchanged."""
    from whipple_kick.model.symbolic import derivation

    joint = derivation.slip_equations(("trunk", "arms"))
    monkeypatch.setitem(parts.REGISTRY, "trunk", dataclasses.replace(parts.TRUNK, build=_hand_written_trunk))
    monkeypatch.setitem(parts.REGISTRY, "arms", dataclasses.replace(parts.ARMS, build=_hand_written_arms))
    by_hand = derivation.slip_equations(("trunk", "arms"))
    assert joint.q == by_hand.q and joint.u == by_hand.u and joint.inputs == by_hand.inputs
    names, at_joint = _at_random_points(joint)
    names_by_hand, at_hand = _at_random_points(by_hand)
    assert names == names_by_hand and "hip_torque" in names[0] and "arm_steer_torque" in names[0]
    assert "q11(t)" in names[1] and "kh" in names[2]   # the same symbols, so the same random values
    for a, b in zip(at_joint, at_hand, strict=True):
        assert np.all(np.isfinite(a))
        assert np.abs(a - b).max() <= 1e-12 * np.abs(b).max()


# ------------------------------------------------------------------ the rider's segments and the drawing

_LEGS = ("J1", "J2", "K1", "K2")
_LIFT_M = 0.1


def _legs_body(bench, seat, mass, com, inertia):
    """The legs as a body of their own (a test part's): their mass, mass centre and inertia by name."""
    return {"legs_mass": mass, "legs_x": float(com[0]), "legs_z": float(com[2]), "legs_ixx": float(inertia[0, 0]),
            "legs_iyy": float(inertia[1, 1]), "legs_izz": float(inertia[2, 2]), "legs_ixz": float(inertia[0, 2])}


def _legs_pose(body, states, rear_rotation, rear_origin):
    """The legs' frame in a drawing: the rear frame's, lifted by _LIFT_M (the ground's z points down)."""
    return rear_rotation, rear_origin - _LIFT_M * np.array([0.0, 0.0, 1.0])


@pytest.fixture
def legs(monkeypatch):
    """A part, declared here only, that carries the rider's legs as a body of its own, drawn in a frame of its
    own (no equations: it is never built here)."""
    part = parts.Part(name="legs", description="the rider's legs as a body of their own (a test part)",
                      source="this test", symbols=(), coordinates=(), speeds=(), parameters=(), gains={},
                      columns={}, outputs={}, build=lambda m: None, selected_by=("legs", "on"), title="the legs",
                      split=parts.Split(segments=_LEGS, body=_legs_body, moves_with="L"), pose=_legs_pose)
    monkeypatch.setitem(parts.REGISTRY, part.name, part)
    return part


def test_a_part_declared_here_splits_the_rider_and_is_drawn_in_its_frame(legs):
    """A part's whole footprint on the rider from its declaration, no other file touched: its segments (the
    legs) are split off the seated rider as its own body, the rest stays in the rear frame, the scenario field
    that selects it splits the run's bicycle for it, and the animation draws its segments in its frame, posed
    as it declares; the other parts' splits still hold (the arms take the forearms from the trunk).

    Bounds: lumping the legs' body back into the rear frame gives the rider seated whole to rel 1e-12 (the
    same sums in another order); the drawn legs are the rigid rider's lifted by the declared 0.1 m, to 1e-12 m.
    """
    import copy

    from whipple_kick.figures import animation
    from whipple_kick.library import riders
    from whipple_kick.simulate import scenario as scenario_module
    from whipple_kick.simulate import simulation

    bike = wk.bicycles.load("balanceassist_v1")
    rider = riders.yeadon_rider("jason", mass_kg=80.0)
    split = riders.split_rider(bike, rider, ("legs",))
    body = split.body
    assert split.held == () and split.body_mass == body["legs_mass"] and 15.0 < body["legs_mass"] < 40.0
    inertia = np.array([[body["legs_ixx"], 0.0, body["legs_ixz"]], [0.0, body["legs_iyy"], 0.0],
                        [body["legs_ixz"], 0.0, body["legs_izz"]]])
    back = riders.lump_into_frame(split.combined.benchmark, "B", body["legs_mass"],
                                  np.array([body["legs_x"], 0.0, body["legs_z"]]), inertia)
    whole = riders.seat(bike, rider).benchmark
    for key in ("mB", "xB", "zB", "IBxx", "IByy", "IBzz", "IBxz", "mH", "IHxx"):
        assert back[key] == pytest.approx(whole[key], rel=1e-12, abs=1e-12), key
    carried = riders.segment_carriers(("legs",))
    assert {s for s, p in carried.items() if p is legs} == set(_LEGS)
    assert all(p is None for s, p in carried.items() if s not in _LEGS)
    # With the trunk and the arms: the arms (built after the trunk) take the forearms, the legs theirs.
    carried = riders.segment_carriers(("trunk", "arms", "legs"))
    assert {s: p.name for s, p in carried.items()} == {**dict.fromkeys(("P", "T", "C", "A1", "B1"), "trunk"),
                                                       **dict.fromkeys(("A2", "B2"), "arms"),
                                                       **dict.fromkeys(_LEGS, "legs")}
    # The run's bicycle is split for it when its field selects it (the bicycle's view holds the field).
    cls = scenario_module.with_parts(legs)
    _, _, info = assembly.build_bicycle(cls(legs="on").bicycle_spec)
    _, _, plain = assembly.build_bicycle(cls().bicycle_spec)
    assert set(info["body"]) == set(body) and plain["body"] is None
    assert info["total_mass_kg"] == pytest.approx(plain["total_mass_kg"], rel=1e-12)
    # The drawing: the legs in the part's frame "L", posed by its declaration; the rest where it was.
    result = simulation.run(wk.Scenario(duration=0.2))
    drawn = copy.copy(result)
    drawn.scenario, drawn.summary = cls(legs="on"), copy.deepcopy(result.summary)
    drawn.summary["bicycle"]["body"] = info["body"]
    times = result.trajectory["time"].to_numpy()[:1]
    rigid = {item.name: item.points for item in animation.build_scene(result, times).items}
    items = {item.name: item.points for item in animation.build_scene(drawn, times).items}
    legs_drawn = [name for name in items if name.startswith("L ")]
    assert set(legs_drawn) == {"L J1", "L K1", "L left shank", "L right shank", "L left foot", "L right foot"}
    assert not any(n.startswith("L ") for n in rigid) and "C left shank" not in items
    for name in legs_drawn:
        np.testing.assert_allclose(items[name], rigid["C" + name[1:]] + [0.0, 0.0, -_LIFT_M], rtol=0, atol=1e-12)
    np.testing.assert_allclose(items["C head"], rigid["C head"], rtol=0, atol=0)


def test_the_parts_build_into_a_sympy_system_the_derivation_reads_back():
    """The trunk's build adds its body, its hip joint (which brings q11, u11 and dq11/dt = u11) and its
    spring-damper actuator to SymPy's System, which starts with the bicycle's four bodies; the derivation
    reads them back (the coordinates after the bicycle's, the upper body with its weight). A build whose
    system holds coordinates the part does not declare is refused, naming both."""
    import sympy.physics.mechanics as me

    from whipple_kick.model import symbols
    from whipple_kick.model.symbolic import derivation

    kin = derivation.kinematics(tyre_model=True)
    chosen = parts.named(("trunk",))
    par = {n: symbols.sym(n) for n in symbols.SLIP_CONSTANTS + parts.TRUNK.parameters}
    mech = parts.Mechanics(kin=kin, par=par, hands_frame=kin.frames["C"])
    assert [b.name for b in mech.system.bodies] == ["rear_frame", "rear_wheel", "front_frame", "front_wheel"]
    parts.TRUNK.build(mech)
    q11, u11 = symbols.dyn("q11"), symbols.dyn("u11")
    assert tuple(mech.system.q) == (q11,) and tuple(mech.system.u) == (u11,)
    assert [type(j).__name__ for j in mech.system.joints] == ["PinJoint"]
    assert [type(a).__name__ for a in mech.system.actuators] == ["TorqueActuator"] and len(mech.loads()) == 2
    assert [b.name for b in mech.added_bodies()] == ["upper_body"]
    derivation.take_parts(kin, mech, chosen)
    assert kin.q[-1] == q11 and kin.u[-1] == u11 and kin.qd_to_u[q11.diff(me.dynamicsymbols._t)] == u11
    point, weight = kin.gravity_loads[-1]
    assert point is mech.rigid_body("upper_body").masscenter
    assert weight == par["mt"] * par["g"] * kin.frames["N"].z
    # A build that gives the system a coordinate its part does not declare is refused.
    kin = derivation.kinematics(tyre_model=True)
    mech = parts.Mechanics(kin=kin, par=par, hands_frame=kin.frames["C"])
    parts.TRUNK.build(mech)
    mech.system.add_coordinates(symbols.dyn("q9"))
    with pytest.raises(ValueError, match=r"gave the system the coordinates \['q11', 'q9'\]; they declare \['q11'\]"):
        derivation.take_parts(kin, mech, chosen)
