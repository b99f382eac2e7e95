"""The page's form: derived from the Scenario's declarations, and refusing what simulate refuses, in its words."""
import pytest

from tests.conftest import run_console
from whipple_kick import cli
from whipple_kick.errors import InputError
from whipple_kick.explorer import form
from whipple_kick.library import tyres
from whipple_kick.simulate.scenario import SETTINGS, Scenario


def test_fields_come_from_the_declarations():
    fields = {f.name: f for f in form.fields()}
    assert tuple(fields) == form.PAGE_FIELDS
    for name, f in fields.items():
        s = SETTINGS[name]
        assert f.label == s.words and f.help == form.plain(s.doc) and "`" not in f.help
        assert f.value == ("" if s.default is None else form._text(s.default))
    assert fields["tyre"].choices == tuple(t[0] for t in tyres.available())
    assert fields["controller"].choices == SETTINGS["controller"].choices
    assert "table" not in fields["kick_profile"].choices and "smooth" in fields["kick_profile"].choices
    assert fields["fz_n"].placeholder == "default 635"
    assert fields["pressure_front_kpa"].placeholder == "default: the pressure"


@pytest.mark.parametrize("name", [n for n in form.PAGE_FIELDS if SETTINGS[n].high is not None or SETTINGS[n].low is not None])
def test_the_range_shown_is_the_one_the_message_names(name):
    """The range beside a field is written as check_range writes it in the message a value outside gets."""
    s = SETTINGS[name]
    outside = s.high + 1.0 if s.high is not None else s.low - 1.0
    with pytest.raises(InputError) as info:
        s.check(outside)
    field = next(f for f in form.fields() if f.name == name)
    assert str(info.value).endswith(f"allowed range {field.range_text}")


@pytest.mark.parametrize("page, flags", [
    ({"pressure_kpa": "1000"}, ["--pressure", "1000"]),          # outside the tyre's measured range
    ({"pressure_kpa": "0"}, ["--pressure", "0"]),                # outside the field's own range
    ({"speed": "20"}, ["--speed", "20"]),
    ({"fz_n": "10"}, ["--fz", "10"]),                            # no rider puts 10 N on the rear tyre
    ({"duration": "500"}, ["--duration", "500"]),
    ({"bicycle": "no_such_bicycle"}, ["--bicycle", "no_such_bicycle"]),
])
def test_a_refusal_is_simulates_message_beside_its_field(page, flags, capsys):
    status, _, err = run_console(cli.simulate_main, [*flags, "--no-plot"], capsys)
    assert status == 2
    with pytest.raises(form.FormError) as info:
        form.parse(page)
    assert info.value.errors == {next(iter(page)): err.removeprefix("error: ").rstrip("\n")}


def test_a_text_that_is_no_number_gets_the_flags_message(capsys):
    status, _, err = run_console(cli.simulate_main, ["--pressure", "abc"], capsys)
    with pytest.raises(form.FormError) as info:
        form.parse({"pressure_kpa": "abc", "speed": "fast"})
    assert status == 2 and info.value.errors["pressure_kpa"] in err
    assert info.value.errors == {"pressure_kpa": "'abc' is not a number (kPa)", "speed": "'fast' is not a number (m/s)"}


def test_blank_fields_keep_their_defaults_and_given_ones_are_used():
    assert form.parse(dict.fromkeys(form.PAGE_FIELDS, "")) == Scenario()
    sc = form.parse({"pressure_kpa": " 300 ", "fz_n": "701", "kick_direction": "left", "controller": "thesis"})
    assert (sc.pressure_kpa, sc.fz_n, sc.kick_direction, sc.controller) == (300.0, 701.0, "left", "thesis")


def test_a_field_no_mechanism_reads_is_refused_beside_it():
    with pytest.raises(form.FormError) as info:
        form.parse({"pressure_kpa": "300", "pressure_front_kpa": "350", "pressure_rear_kpa": "400"})
    assert list(info.value.errors) == ["pressure_kpa"]
    assert "pressure_front_kpa and pressure_rear_kpa are both given" in info.value.errors["pressure_kpa"]


def test_a_message_goes_to_the_field_it_names():
    assert form.field_of("pressure of tyre T03 (table7_9) = 1000.0 kPa is outside") == "pressure_kpa"
    assert form.field_of("front pressure = -1.0 kPa is outside") == "pressure_front_kpa"
    assert form.field_of("give the rear-tyre load fz (N) or the rider mass (kg), not both") == form.GENERAL


def test_the_stability_scenario_is_the_stability_commands():
    sc = form.parse({"pressure_kpa": "300", "fz_n": "701", "speed": "5", "kick_direction": "left"})
    st = form.stability_scenario(sc, 0.5)
    assert (st.pressure_kpa, st.fz_n, st.symmetric_tyres, st.speed) == (300.0, 701.0, True, 0.5)
    assert st.kick_direction == Scenario().kick_direction   # simulate's flags only: stability has none
