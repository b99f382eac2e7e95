"""No field, flag or gain is accepted and then ignored (issue 31, items 5, 6, 8, 13).

The walk takes every :class:`Scenario` field (from ``dataclasses.fields``, so
a new field is walked without editing this file) through every mechanism
switch, and shows that a value other than the default either changes what the
run is made of or is refused. What the run is made of is checked cheaply,
without an integration: the compiled model's parameter vector, the rider's
gains (for the design on the simulated model: the design model's matrices and
its starting gains), the kick, and the settings the integration reads (as
:mod:`whipple_kick.simulate.integration` reads them).
"""
import argparse
import dataclasses
import pathlib
import re

import numpy as np
import pytest

from conftest import SCENARIO_DEFAULTS as DEFAULTS
from conftest import other_value
from whipple_kick import cli
from whipple_kick.errors import InputError
from whipple_kick.library import inputs
from whipple_kick.model import slip
from whipple_kick.simulate import assembly, control
from whipple_kick.simulate.scenario import FIELD_GROUPS, MECHANISM_FIELDS, Scenario

RIDER_FILE = pathlib.Path(__file__).parents[2] / "parameters" / "riders" / "jason.toml"


@pytest.fixture(scope="module")
def other_rider(tmp_path_factory):
    """Jason with a 10 % longer first measurement: another Yeadon rider file."""
    text = RIDER_FILE.read_text()
    head, measurements = text.split("[measurements]", 1)
    first = re.search(r"^(\w+) = ([0-9.]+)", measurements, re.MULTILINE)
    changed = measurements.replace(first.group(0), f"{first.group(1)} = {float(first.group(2)) * 1.1!r}", 1)
    path = tmp_path_factory.mktemp("rider") / "other.toml"
    path.write_text(head + "[measurements]" + changed)
    return str(path)


#: The mechanism switches, each with the other switches at their defaults; a new switch is a new line here,
#: and test_every_switch_is_walked fails until it is added.
SWITCHES = {
    "controller": ({"controller": "thesis"}, {"controller": "off"}),
    "lqr_model": ({"lqr_model": "simulated", "symmetric_tyres": True},),
    "rider_body": ({"rider_body": "leaning"},),
    "arms": ({"arms": "on"},),
    "tyre_transient": ({"tyre_transient": "contact_patch"}, {"tyre_transient": "slip_lag"},
                       {"tyre_transient": "force_lag"}),
    "reflex": ({"reflex_roll": -2.0},),
    "kick_profile": ({"kick_profile": "smooth"},),
    "piecewise": ({"piecewise": False},),
    "start": ({"start": "upright", "settle": 0.0},),
    "bicycle": ({"bicycle": "balanceassist_635N", "controller": "thesis"},),
    "pressures": ({"pressure_front_kpa": 350.0, "pressure_rear_kpa": 450.0},),
}
BASES = [{}] + [base for bases in SWITCHES.values() for base in bases]


def integration_reads(sc):
    """The scenario's settings the integration reads, as integration.integrate_run reads them."""
    reads = {name: getattr(sc, name) for name in ("settle", "duration", "output_rate", "fall_angle_deg",
                                                  "steer_limit_deg", "rtol", "piecewise", "start")}
    if sc.kick_profile == "constant" and sc.piecewise:   # only an instant plate stop has a speed change
        reads["plate_stop"] = sc.plate_stop
    if sc.start == "steady":   # an upright start has no steady motion to move back along
        reads["kick_heading"] = sc.kick_heading
    if sc.start == "upright":   # the pitch of the upright start (steady.start_state)
        reads["start_pitch"] = sc.start_pitch
    return reads


def fingerprint(sc):
    """What the run of ``sc`` is made of; raises InputError where the scenario is refused."""
    assembly.preflight(sc)
    kick = inputs.kick_of(sc)
    rear, front, _ = assembly.build_tyres(sc.tyre_spec)
    moore, design, info = assembly.build_bicycle(sc.bicycle_spec)
    body = assembly.rider_body(sc.body_spec, info)
    model = assembly.model_of(sc.body_spec, sc.tyre_transient)
    if sc.controller == "lqr" and sc.lqr_model == "simulated":
        spec = sc.design_spec
        felt, K = control.simulated_design_start(spec, design, model.parts)
        A, b, C = control._linear_design_model(spec, moore, rear, front, body, felt, 1.0, control.SCALED_BODY_GAINS,
                                               model)
        gains = {"design": (A, b, C, K, sc.gain_scale, sc.lqr_design_speed)}
        params = assembly.model_parameters(sc.model_spec, kick, moore, body, rear, front, None, model)
    else:
        gains, _ = assembly.controller_gains(sc.gains_spec, design)
        params = assembly.model_parameters(sc.model_spec, kick, moore, body, rear, front, gains, model)
    return (slip.parameter_vector(params), gains, kick, integration_reads(sc),
            assembly.no_slip_plant(moore, design, info), float(sc.speed))


def same(a, b):
    if isinstance(a, dict):
        return isinstance(b, dict) and a.keys() == b.keys() and all(same(a[k], b[k]) for k in a)
    if isinstance(a, (tuple, list)):
        return isinstance(b, (tuple, list)) and len(a) == len(b) and all(same(x, y) for x, y in zip(a, b, strict=True))
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        return np.shape(a) == np.shape(b) and bool(np.array_equal(a, b))
    if dataclasses.is_dataclass(a):
        return same(dataclasses.asdict(a), dataclasses.asdict(b)) if dataclasses.is_dataclass(b) else False
    return a == b


@pytest.fixture(scope="module")
def kick_table(tmp_path_factory):
    path = tmp_path_factory.mktemp("kick") / "plate.csv"
    path.write_text("time,y\n0.0,0.0\n0.05,0.02\n0.1,0.08\n0.15,0.15\n")
    return str(path)


def test_every_switch_is_walked():
    # Each mechanism of the table is on in one base of the walk and off in another.
    scenarios = [Scenario(**base) for base in BASES]
    for mechanism, _, active, _ in MECHANISM_FIELDS:
        assert {active(sc) for sc in scenarios} == {True, False}, mechanism


@pytest.mark.parametrize("base", BASES, ids=[",".join(f"{k}={v}" for k, v in b.items()) or "default" for b in BASES])
def test_every_field_changes_the_run_or_is_refused(base, other_rider, kick_table):
    start = Scenario(**base).validate()
    reference = fingerprint(start)
    ignored = []
    for field in dataclasses.fields(Scenario):
        value = other_value(field.name, other_rider)
        if value == getattr(start, field.name):   # the base already switched it: walk the default instead
            value = DEFAULTS[field.name]
        if field.name == "kick_table":
            value = kick_table
        changed = start.with_changes(**{field.name: value})
        try:
            changed.validate()
            print_ = fingerprint(changed)
        except InputError:
            continue   # refused: never accepted and ignored
        if same(print_, reference):
            ignored.append(f"{field.name}={value!r}")
    assert not ignored, f"accepted and ignored with {base or 'the defaults'}: {ignored}"


@pytest.mark.parametrize(("changes", "field"), [
    ({"hip_stiffness": 200.0}, "hip_stiffness"), ({"hip_damping": 10.0}, "hip_damping"),
    ({"arm_stiffness": 5.0}, "arm_stiffness"), ({"arm_damping": 1.0}, "arm_damping"),
    ({"tyre_transient": "force_lag", "carcass_damping": 50.0}, "carcass_damping"),
    ({"tyre_transient": "contact_patch", "carcass_sliding": "curve"}, "carcass_sliding"),
    ({"tyre_transient": "slip_lag", "carcass_stiffness_scale": 0.5}, "carcass_stiffness_scale"),
    ({"tyre_transient": "force_lag", "carcass_viscosity": 0.01}, "carcass_viscosity"),
    ({"controller": "thesis", "design_speed": 4.0}, "design_speed"),
    ({"controller": "off", "design_speed": 4.0}, "design_speed"),
    ({"controller": "thesis", "lqr_model": "simulated"}, "lqr_model"),
    ({"controller": "off", "lqr_model": "simulated"}, "lqr_model"),
    ({"controller": "lqr", "thesis_load_n": 701.0}, "thesis_load_n"),
    ({"reflex_delay": 0.1}, "reflex_delay"),
])
def test_item6_fields_of_an_unused_mechanism_are_refused(changes, field):
    # Issue 31 item 6: each was validated, recorded in scenario.toml and then ignored.
    with pytest.raises(InputError, match=rf"^{field} = .* is read only by .*: leave it at its default"):
        Scenario(**changes).validate()


def test_a_field_at_its_default_is_never_given():
    # Equal to its default, a field of an unused mechanism is not "given": the presets and every default pass.
    assert Scenario(controller="off", hip_stiffness=128.0, carcass_damping=0.0).validate().unused_fields() == {}
    assert Scenario.thesis().validate().unused_fields() == {}
    assert Scenario.authors_code().validate().unused_fields() == {}


@pytest.mark.parametrize("gain", ["reflex_roll", "reflex_roll_rate", "reflex_steer", "reflex_steer_rate"])
def test_item8_controller_off_means_no_rider_torque(gain):
    # Issue 31 item 8: with controller "off" reflex gains steered (up to 6 N m) while the summary said
    # "without steer control". "off" is no rider torque at all, so a reflex gain is refused with it.
    with pytest.raises(InputError, match=rf"^{gain} = 4.0 N m( s)?/rad is read only by the rider's steer control"):
        Scenario(controller="off", **{gain: 4.0}).validate()
    Scenario(controller="thesis", **{gain: 4.0}).validate()   # with a rider, the reflex acts


def test_item13_low_inertia_is_refused_with_a_body():
    # Issue 31 item 13: halving the rear frame's zB with the upper body split off lowered the mass centre
    # to 0.773 m, not to 0.500 m as for the rigid rider; Figure 8.9's variant is the lumped rider's.
    for body in ({"rider_body": "leaning"}, {"arms": "on"}):
        with pytest.raises(InputError, match="low_inertia halves the rear frame with the whole rider"):
            Scenario(low_inertia=True, **body).validate()
    Scenario(low_inertia=True).validate()


def test_pressure_is_refused_when_both_wheels_have_their_own():
    with pytest.raises(InputError, match=r"pressure_kpa = 300\.0 kPa is read only by a tyre without its own pressure"):
        Scenario(pressure_kpa=300.0, pressure_front_kpa=350.0, pressure_rear_kpa=450.0).validate()


def test_a_rider_file_is_refused_with_a_preset_that_includes_its_rider(other_rider):
    with pytest.raises(InputError, match=r"already includes its rider; rider .* would be ignored"):
        assembly.preflight(Scenario(bicycle="balanceassist_635N", controller="thesis", rider=other_rider))


# ------------------------------------------------------------------ user gains (item 5)

def test_item5_lean_gains_given_are_used():
    # Issue 31 item 5: kq11/ku11 were accepted and then dropped (only kq4 kq7 ku4 ku7 kq3 ku3 were kept).
    gains = assembly.custom_gains({"kq4": -10.0, "kq11": 3.0, "ku11": 0.5}, Scenario(rider_body="leaning"))
    assert gains["kq11"] == 3.0 and gains["ku11"] == 0.5 and gains["kq4"] == -10.0
    sc = Scenario(rider_body="leaning")
    moore, _, info = assembly.build_bicycle(sc.bicycle_spec)
    rear, front, _ = assembly.build_tyres(sc.tyre_spec)
    body = assembly.rider_body(sc.body_spec, info)
    params = assembly.model_parameters(sc.model_spec, inputs.kick_of(sc), moore, body, rear, front, gains,
                                       assembly.model_of(sc.body_spec, sc.tyre_transient))
    assert params["kq11"] == 3.0 and params["ku11"] == 0.5


def test_item5_lean_gains_need_a_leaning_body_and_gains_replace_the_controller():
    with pytest.raises(InputError, match=r"\['kq11'\] feed back the leaning upper body's states \(q11\), which only rider_body 'leaning' has"):
        assembly.custom_gains({"kq11": 3.0}, Scenario())
    with pytest.raises(InputError, match=r"gain_scale = 0\.5 is replaced by the given gains"):
        assembly.custom_gains({"kq4": -10.0}, Scenario(gain_scale=0.5))
    with pytest.raises(InputError, match="controller = 'thesis' is replaced by the given gains"):
        assembly.custom_gains({"kq4": -10.0}, Scenario(controller="thesis"))


# ------------------------------------------------------------------ the CLI's flags

#: simulate's flags that set no Scenario field (output, animation, the file or preset the scenario comes from).
NOT_SCENARIO_FLAGS = {"--help", "--version", "--out", "--force", "--no-plot", "--quiet", "--animate", "--fps",
                      "--slow-motion", "--slow-after", "--scenario", "--compat"}


def _flag_value(action, other_rider, kick_table):
    """argv words giving ``action`` a value other than its default."""
    flag = action.option_strings[-1]
    if isinstance(action, argparse._StoreTrueAction):
        return [flag]
    field = action.dest   # every scenario flag's destination is its field
    if action.choices:   # a choice other than the parser's default and the field's (a default of None)
        return [flag, next(c for c in action.choices if c not in (action.default, DEFAULTS.get(field)))]
    if field == "kick_table":
        return [flag, kick_table]
    value = other_value(field, other_rider) if field in DEFAULTS else None
    assert value is not None, f"{flag} sets no known Scenario field"
    return [flag, str(value)]


def test_every_simulate_flag_reaches_the_scenario(other_rider, kick_table):
    # Each flag of simulate's parser (from its actions, so a new flag is walked) changes the Scenario; the
    # field walk above then shows the field changes the run or is refused.
    parser = cli._simulate_parser()
    default = cli._scenario_from_args(parser.parse_args([]))
    walked = 0
    for action in parser._actions:
        if not action.option_strings or action.option_strings[-1] in NOT_SCENARIO_FLAGS:
            continue
        argv = _flag_value(action, other_rider, kick_table)
        if action.dest == "pressure_front_kpa":
            argv += ["--pressure-rear", "400"]
        elif action.dest == "pressure_rear_kpa":
            argv += ["--pressure-front", "400"]
        try:
            sc = cli._scenario_from_args(parser.parse_args(argv))
        except InputError:
            continue   # refused (e.g. a flag whose mechanism is off)
        assert sc != default, f"{argv} left the scenario unchanged"
        walked += 1
    assert walked > 40


def test_field_groups_cover_the_mechanism_table():
    every = {name for group in FIELD_GROUPS.values() for name in group}
    assert {name for *_, names in MECHANISM_FIELDS for name in names} <= every
