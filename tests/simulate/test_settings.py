"""One declaration per Scenario field (issue 42, part 1).

A test module adds a plain field to a Scenario subclass with one
:func:`~whipple_kick.simulate.settings.setting` and nothing else: its range
check, its group, its refusal while the mechanism that reads it is off, its
place in the view of the assembly step that reads it and its ``simulate``
flag all follow. The shipped declarations are checked for what the table
promises (every field declared, every flag and view named after a field).
"""
import dataclasses

import pytest

from whipple_kick import cli
from whipple_kick.errors import InputError
from whipple_kick.model import parts
from whipple_kick.simulate import scenario as scenario_module
from whipple_kick.simulate import settings
from whipple_kick.simulate.scenario import FIELD_GROUPS, MECHANISM_FIELDS, Scenario
from whipple_kick.simulate.settings import EVERY_COMMAND, setting


@dataclasses.dataclass(frozen=True)
class EffortScenario(Scenario):
    """A Scenario with one more field, declared once."""

    lqr_effort: float = setting(
        1.0, "Weight of the steer torque in the LQR rider's cost [1] (a made-up field of this test).",
        unit="(factor)", low=0.0, high=100.0, label="LQR effort weight", mechanisms=("lqr",), views=("gains",),
        commands=EVERY_COMMAND, section="riding and control",
        help="weight of the steer torque in the LQR rider's cost (default {default})")


def test_the_new_field_is_checked_against_its_declared_range():
    assert EffortScenario(lqr_effort=4.0).validate().lqr_effort == 4.0
    with pytest.raises(InputError, match=r"^LQR effort weight = -1\.0 \(factor\) is outside the allowed range "
                                         r"\[0, 100\] \(factor\)$"):
        EffortScenario(lqr_effort=-1.0).validate()


def test_the_new_field_joins_its_group():
    groups = settings.groups(EffortScenario)
    assert groups["physics"][-1] == "lqr_effort" and groups["run"] == FIELD_GROUPS["run"]
    assert EffortScenario(lqr_effort=2.0).physics["lqr_effort"] == 2.0
    assert "lqr_effort" not in Scenario().physics


def test_the_new_field_is_refused_while_its_mechanism_is_off():
    with pytest.raises(InputError, match=r"^lqr_effort = 2\.0 is read only by the LQR rider \(controller 'lqr'\), "
                                         r"which this scenario does not use: leave it at its default 1\.0"):
        EffortScenario(controller="thesis", lqr_effort=2.0).validate()
    assert EffortScenario(controller="thesis").validate().unused_fields() == {}
    table = {title: names for title, _, _, names in scenario_module.mechanism_fields(EffortScenario)}
    assert table["the LQR rider"] == ("design_speed", "lqr_model", "lqr_effort")


def test_the_new_field_is_in_the_view_of_the_step_that_reads_it():
    view = EffortScenario(lqr_effort=2.0).gains_spec
    assert view.lqr_effort == 2.0 and view.controller == "lqr"
    assert view != EffortScenario().gains_spec and hash(view) != hash(EffortScenario().gains_spec)
    with pytest.raises(dataclasses.FrozenInstanceError):
        view.lqr_effort = 3.0
    assert "lqr_effort" not in {f.name for f in dataclasses.fields(EffortScenario().model_spec)}
    assert "lqr_effort" not in {f.name for f in dataclasses.fields(Scenario().gains_spec)}   # Scenario's own view


def test_the_new_field_has_its_flag(capsys):
    parser = cli._simulate_parser(EffortScenario)
    flag = {a.dest: a for a in parser._actions}["lqr_effort"]
    assert flag.option_strings == ["--lqr-effort"] and flag.metavar == "FACTOR"
    assert flag.help == "weight of the steer torque in the LQR rider's cost (default 1)"
    assert flag.container.title == "riding and control"
    sc = cli._scenario_from_args(parser.parse_args(["--lqr-effort", "2.5", "--speed", "4"]), EffortScenario)
    assert type(sc) is EffortScenario and (sc.lqr_effort, sc.speed) == (2.5, 4.0)
    assert cli._scenario_from_args(parser.parse_args([]), EffortScenario) == EffortScenario()
    with pytest.raises(SystemExit) as exit_:
        parser.parse_args(["--lqr-effort", "much"])
    err = capsys.readouterr().err
    assert exit_.value.code == 2 and err.count("\n") == 1 and "'much' is not a number (factor)" in err
    # Given with its mechanism off: the one-line refusal of validate.
    sc = cli._scenario_from_args(parser.parse_args(["--lqr-effort", "2", "--controller", "off"]), EffortScenario)
    with pytest.raises(InputError, match=r"lqr_effort = 2\.0 is read only by the LQR rider"):
        sc.validate()


def test_the_new_field_is_written_and_read_back(tmp_path):
    sc = EffortScenario(lqr_effort=3.0)
    sc.to_file(tmp_path / "scenario.toml")
    assert "lqr_effort = 3.0" in (tmp_path / "scenario.toml").read_text()
    assert EffortScenario.from_file(tmp_path / "scenario.toml") == sc


# ------------------------------------------------------------------ the shipped declarations

def test_every_field_is_declared_once_with_a_known_group_mechanism_view_and_command():
    known_mechanisms = set(scenario_module.MECHANISMS) | set(parts.REGISTRY)
    flags = []
    for s in scenario_module.SETTINGS.values():
        assert s.doc and s.group in settings.GROUPS, s.name
        assert set(s.mechanisms) <= known_mechanisms, s.name
        assert set(s.views) <= {*scenario_module.VIEWS, "design"}, s.name
        assert set(s.commands) <= set(settings.COMMANDS) and (not s.commands or s.section in cli.SECTIONS), s.name
        if s.commands:
            flags.append(s.option)
            assert s.help, s.name
        if s.choices:
            assert s.default in s.choices or s.default is None, s.name
        if s.low is not None or s.high is not None:
            s.check(s.default)   # the default is in its own range
    assert len(flags) == len(set(flags))
    assert [m[0] for m in MECHANISM_FIELDS][:3] == ["the carcass tyre", "the leaning upper body", "the arms on the bar"]


def test_the_class_documents_every_field_from_its_declaration():
    for s in scenario_module.SETTINGS.values():
        assert f"\n    {s.name} : " in Scenario.__doc__, s.name
    assert "    speed : float\n        Forward speed [m/s] of the steady motion before the kick." in Scenario.__doc__
    assert '    controller : {"lqr", "thesis", "off"}\n' in Scenario.__doc__
    assert "    design_speed : float or None\n" in Scenario.__doc__


def test_the_none_rules_are_read_from_the_declarations():
    # The default rear load (fz_n None) and pressure are declared once; the assembly and the CLI read them.
    from whipple_kick.library import thesis
    from whipple_kick.simulate import assembly
    assert assembly.DEFAULT_REAR_LOAD_N == scenario_module.SETTINGS["fz_n"].none_means == thesis.REFERENCE_LOAD_N
    assert Scenario().pressure_kpa == thesis.REFERENCE_PRESSURE_KPA
    flags = {a.dest: a for a in cli._simulate_parser()._actions}
    assert f"(default {thesis.REFERENCE_LOAD_N:g})" in flags["fz_n"].help
    assert f"(default {thesis.REFERENCE_PRESSURE_KPA:g})" in flags["pressure_kpa"].help
