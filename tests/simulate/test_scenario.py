"""The Scenario: thesis defaults, presets, validation with one-line errors, copies with changes."""
import json
import re

import pytest

from whipple_kick.errors import InputError
from whipple_kick.simulate.scenario import Scenario


def test_defaults_are_the_thesis_settings_and_validate_returns_the_scenario():
    """What the defaults do, not what they are: the thesis' kick (150 mm in 0.150 s at a constant
    13.3 m/s^2, Dell'Orto 2025, Section 8.2), a rider seated for 635 N on the rear tyre, the LQR rider
    designed at the run's speed, T03 at 400 kPa on both wheels."""
    from whipple_kick.library import inputs
    from whipple_kick.simulate import assembly
    sc = Scenario()
    assert sc.validate() is sc
    kick = inputs.kick_of(sc)
    assert (kick.profile, kick.displacement, kick.duration) == ("constant", 0.150, 0.150)
    assert kick.peak_acceleration == pytest.approx(2 * 0.150 / 0.150 ** 2)      # 13.3 m/s^2
    rear, front, notes = assembly.build_tyres(sc.tyre_spec)
    assert (rear.name, rear.pressure_kpa, front.pressure_kpa, notes) == ("T03", 400.0, 400.0, [])
    assert sc.lqr_design_speed == sc.speed == 3.0
    from whipple_kick.simulate.simulation import run
    bike = run(sc.with_changes(duration=0.2)).summary["bicycle"]
    assert bike["bicycle"] == "balanceassist_v1" and bike["static_load_rear_n"] == pytest.approx(635.0, abs=1e-6)
    assert Scenario(speed=5.0).lqr_design_speed == 5.0 and Scenario(design_speed=3.0, speed=5.0).lqr_design_speed == 3.0
    assert Scenario(pressure_front_kpa=300.0, pressure_rear_kpa=500.0).pressures == (500.0, 300.0)
    json.dumps(sc.to_dict(), allow_nan=False)


def test_to_dict_is_asdict():
    """to_dict gives asdict's dict (fields in order, the values themselves), and asdict's deep copy of a field
    that is not a plain value (never one of a checked scenario, but the dataclass allows it)."""
    import dataclasses
    sc = Scenario(pressure_kpa=300.0, tyre_transient="contact_patch")
    assert list(sc.to_dict().items()) == list(dataclasses.asdict(sc).items())
    odd = dataclasses.replace(sc, kick_table=["rows"])   # not a scenario to run: only what to_dict makes of it
    out = odd.to_dict()
    assert out == dataclasses.asdict(odd) and out["kick_table"] is not odd.kick_table


def test_with_changes_copies_and_leaves_the_original():
    sc = Scenario()
    other = sc.with_changes(pressure_kpa=300.0, fz_n=701.0)
    assert (other.pressure_kpa, other.fz_n, sc.pressure_kpa, sc.fz_n) == (300.0, 701.0, 400.0, None)
    with pytest.raises(TypeError):
        sc.with_changes(pressure=300.0)   # not a field


@pytest.mark.parametrize("changes, fragment", [
    ({"speed": 0.0}, "speed = 0.0 m/s is outside the allowed range (0, 15] m/s"),
    ({"duration": 200.0}, "duration = 200.0 s is outside the allowed range (0, 120] s"),
    ({"rtol": 1e-16}, "rtol = 1e-16 (relative) is outside"),
    ({"fall_angle_deg": 90.0}, "fall angle = 90.0 deg is outside the allowed range (0, 90) deg"),
    ({"controller": "pid"}, "controller 'pid' is unknown; choose one of lqr, thesis, off"),
    ({"fz_n": 635.0, "rider_mass_kg": 70.0}, "give the rear-tyre load fz (N) or the rider mass (kg), not both"),
    ({"pressure_kpa": -1.0}, "pressure = -1.0 kPa is outside the allowed range (0, inf] kPa"),
    ({"kick_accel": 0.0}, "kick peak acceleration = 0.0 m/s^2 is outside"),
    ({"rear_load_share": 1.0}, "rear load share = 1.0 (unit 1) is outside the allowed range (0, 1) (unit 1)"),
    ({"rear_load_share": 0.0}, "rear load share = 0.0 (unit 1) is outside the allowed range (0, 1)"),
    # With the leaning body the hip's 0 is refused: one range, (0, 1e+06], below 0 as at 0 (issue 40 item 16).
    ({"rider_body": "leaning", "hip_stiffness": -1.0},
     "hip stiffness = -1.0 N m/rad is outside the allowed range (0, 1e+06] N m/rad"),
    ({"rider_body": "leaning", "hip_stiffness": 0.0}, "nothing to hold it up; allowed (0, 1e+06] N m/rad"),
    ({"hip_stiffness": -1.0}, "hip stiffness = -1.0 N m/rad is outside the allowed range [0, 1e+06] N m/rad"),
])
def test_fields_out_of_range_are_one_line_input_errors(changes, fragment):
    with pytest.raises(InputError, match=re.escape(fragment)) as info:
        Scenario(**changes).validate()
    assert "\n" not in str(info.value)


def test_bad_model_options_are_input_errors():
    for field_name, value, fragment in (("tyre_transient", "lagged", "tyre transient 'lagged' is unknown"),
                                        ("plate_stop", "stop", "plate stop 'stop' is unknown"),
                                        ("kick_heading", "north", "kick heading 'north' is unknown")):
        with pytest.raises(InputError, match=re.escape(fragment)):
            Scenario(**{field_name: value}).validate()


def test_thesis_preset_uses_the_force_lag():
    assert Scenario.thesis().tyre_transient == "force_lag"


def test_authors_code_preset_is_the_thesis_preset_with_their_assumptions():
    sc = Scenario.authors_code()
    thesis = Scenario.thesis(500.0)
    differ = {f: (getattr(thesis, f), getattr(sc, f)) for f in sc.to_dict() if getattr(sc, f) != getattr(thesis, f)}
    assert differ == {"camber_sign": ("physical", "reversed"), "start": ("steady", "upright"),
                      "settle": (0.5, 0.0), "plate_stop": ("impulse", "keep_speeds"),
                      "start_pitch": ("compressed", "uncompressed"), "slip_speed": ("wheel_centre", "contact_point")}
    assert sc.pressure_kpa == 500.0 and Scenario.authors_code(400.0, rtol=1e-10).pressure_kpa == 400.0
    # Each assumption switches back alone; an upright start needs the kick to start the run.
    assert Scenario.authors_code(plate_stop="impulse").validate().camber_sign == "reversed"
    for field_name, ours in (("start_pitch", "compressed"), ("slip_speed", "wheel_centre")):
        back = Scenario.authors_code(**{field_name: ours}).validate()
        assert {f for f in sc.to_dict() if getattr(back, f) != getattr(sc, f)} == {field_name}
    # Only an upright start has a start pitch: a steady start switches it back too.
    steady = Scenario.authors_code(start="steady", settle=0.5).validate()
    assert (steady.start_pitch, steady.slip_speed) == ("compressed", "contact_point")
    with pytest.raises(InputError, match="start pitch 'uncompressed' conflicts with start 'steady'"):
        Scenario(start_pitch="uncompressed").validate()
    with pytest.raises(InputError, match="start pitch 'level' is unknown; choose one of compressed, uncompressed"):
        Scenario(start_pitch="level").validate()
    with pytest.raises(InputError, match="slip speed 'hub' is unknown; choose one of wheel_centre, contact_point"):
        Scenario(slip_speed="hub").validate()
    with pytest.raises(InputError, match=r"settle time = 0.5 s conflicts with start 'upright'.*allowed: 0 s"):
        Scenario.authors_code(settle=0.5).validate()
    with pytest.raises(InputError, match="camber sign 'negative' is unknown; choose one of physical, reversed"):
        Scenario(camber_sign="negative").validate()
    with pytest.raises(InputError, match="start 'level' is unknown; choose one of steady, upright"):
        Scenario(start="level").validate()
    with pytest.raises(InputError, match="keep_speeds' needs piecewise = True"):
        Scenario(plate_stop="keep_speeds", piecewise=False).validate()


def test_scenario_file_round_trip_keeps_every_field(tmp_path):
    """to_file -> from_file gives the same Scenario (== compares every field, floats bit for bit), None included
    (steer_limit_deg None means no limit, not the default 90 deg)."""
    sc = Scenario(fz_n=701.0, pressure_front_kpa=300.0, pressure_rear_kpa=450.0, speed=4.25, design_speed=3.0,
                  gain_scale=0.5, low_inertia=True, kick_accel=10.0, kick_direction="left", rtol=1e-11,
                  output_rate=250.0, steer_limit_deg=None, tyre_transient="force_lag", friction="none")
    path = tmp_path / "scenario.toml"
    sc.to_file(path, note="a note")
    assert "# NOTE: a note" in path.read_text() and 'steer_limit_deg = "none"' in path.read_text()
    assert Scenario.from_file(path) == sc


def test_scenario_file_paths_are_absolute_when_written_and_relative_to_the_file_when_read(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    sc = Scenario(kick_profile="table", kick_table="plate.csv", bicycle="bikes/mine.toml")
    (tmp_path / "run").mkdir()
    sc.to_file(tmp_path / "run" / "scenario.toml")
    text = (tmp_path / "run" / "scenario.toml").read_text()
    assert f'kick_table = "{tmp_path / "plate.csv"}"' in text and f'bicycle = "{tmp_path / "bikes" / "mine.toml"}"' in text
    sub = tmp_path / "sub"
    sub.mkdir()
    (sub / "plate.csv").write_text("time,y\n0,0\n0.15,0.15\n")
    (sub / "mine.toml").write_text('kick_profile = "table"\nkick_table = "plate.csv"\nduration = 1\n')
    sc = Scenario.from_file(sub / "mine.toml")        # the table beside the file, not in the working folder
    assert sc.kick_table == str(sub / "plate.csv") and sc.duration == 1.0 and sc.speed == 3.0


def test_every_field_is_in_exactly_one_group():
    """Physics, run, numerics and compatibility switches: every field in one group, none twice, none missing;
    the groups' views hold the values; construction stays flat."""
    import dataclasses

    from whipple_kick.simulate.scenario import FIELD_GROUPS
    fields = [f.name for f in dataclasses.fields(Scenario)]
    grouped = [name for names in FIELD_GROUPS.values() for name in names]
    assert sorted(grouped) == sorted(fields) and len(grouped) == len(set(grouped))
    sc = Scenario(speed=4.0, rtol=1e-12, camber_sign="reversed", settle=0.2)
    assert sc.physics["speed"] == 4.0 and sc.numerics["rtol"] == 1e-12 and sc.run["settle"] == 0.2
    assert sc.compatibility["camber_sign"] == "reversed"
    # The authors'-code preset changes the thesis preset's compatibility switches and nothing else.
    thesis, authors = Scenario.thesis(500.0), Scenario.authors_code()
    assert thesis.physics == authors.physics and thesis.numerics == authors.numerics
    assert thesis.compatibility != authors.compatibility


def test_every_number_field_has_its_unit():
    """UNITS names the unit of every number field (the uncertainty study checks an input's unit against it; the
    refusals name it), a part's field's from its declaration."""
    import dataclasses

    from whipple_kick.model import parts
    from whipple_kick.simulate.scenario import UNITS
    numbers = {f.name for f in dataclasses.fields(Scenario) if "float" in str(f.type)}
    assert set(UNITS) == numbers
    assert all(UNITS[f.name] == f.unit for f in parts.fields())


def test_the_docstring_says_what_the_defaults_and_the_choices_are():
    """Issue 40 item 16: the class said its defaults were the thesis' simulation settings (rtol, tyre transient,
    coefficient set and design speed are not), and listed two of plate_stop's three choices."""
    from whipple_kick.model import carcass
    from whipple_kick.simulate import scenario
    doc = Scenario.__doc__
    assert "thesis' simulation settings" not in doc and "thesis' settings as" not in scenario.__doc__
    for field, choices in (("plate_stop", scenario.PLATE_STOPS), ("kick_heading", scenario.KICK_HEADINGS),
                           ("camber_sign", scenario.CAMBER_SIGNS), ("start", scenario.STARTS),
                           ("start_pitch", scenario.START_PITCHES), ("slip_speed", scenario.SLIP_SPEEDS),
                           ("rider_body", scenario.RIDER_BODIES), ("lqr_model", scenario.LQR_MODELS),
                           ("arms", scenario.ARMS), ("controller", scenario.CONTROLLERS),
                           ("tyre_transient", scenario.TYRE_TRANSIENTS), ("carcass_sliding", carcass.SLIDING_LAWS)):
        listed = re.search(rf"^    {field} : {{(.*)}}$", doc, re.MULTILINE)
        assert listed and sorted(re.findall(r'"(\w+)"', listed[1])) == sorted(choices), field
    # The hip's range as validate applies it with the leaning body: its 0 is refused.
    assert "[N m/rad], more than 0 to 1e+06; default 128" in doc
