"""The transient tyre forms: one declaration and its function each, read by everything that lists the forms."""
import dataclasses

import pytest

import whipple_kick as wk
from whipple_kick.model import slip, transient
from whipple_kick.model.slip import compiled
from whipple_kick.simulate import lsoda, results
from whipple_kick.simulate.scenario import Scenario


def test_the_lists_of_forms_are_the_declarations(capsys):
    """The compiled model's order, the scenario's choices, doc and help, and the CLI's help all come from FORMS."""
    from conftest import run_console
    from whipple_kick.simulate import settings

    assert transient.TRANSIENTS == tuple(transient.FORMS) == ("contact_patch", "slip_lag", "force_lag", "carcass")
    assert transient.SYMBOLIC == ("contact_patch", "slip_lag", "force_lag")
    assert {name: f.states for name, f in transient.FORMS.items()} == transient.STATES
    declared = settings.settings(Scenario)["tyre_transient"]
    assert tuple(declared.choices) == transient.TRANSIENTS
    _, text, _ = run_console(wk.cli.simulate_main, ["--help"], capsys)
    text = " ".join(text.split())
    for name, form in transient.FORMS.items():
        assert transient.check(name) == transient.TRANSIENTS.index(name)
        said = f"{name}{' (default)' * (name == transient.DEFAULT_TRANSIENT)}: {form.description}"
        assert said in declared.help and said in declared.doc and said in text


def test_the_compiled_model_has_a_branch_per_symbolic_form_and_the_carcass_last():
    """The generated C dispatches on the form's index: one branch per form with a SymPy block, the carcass (the one
    form written in C) the rest."""
    source = compiled.library_path().with_suffix(".c").read_text()
    for name in transient.SYMBOLIC:
        assert f"(mode == {transient.TRANSIENTS.index(name)})" in source
    assert "(mode == 3)" not in source and "wk_carcass_r(" in source


@pytest.mark.parametrize("name", transient.TRANSIENTS)
def test_tolerances_and_columns_follow_the_declaration(name):
    """The integrator's tolerance of each tyre slot is rtol x 1e-2 x max(declared size, 1) (force_lag's forces:
    rtol itself, exactly, as before the declarations); a run's trajectory has the form's declared columns, in
    their order, and no other form's."""
    form = transient.FORMS[name]
    atol = lsoda.default_atol(1e-8, name)
    for slot, scale in zip(slip.PATCH_STATES, form.scales, strict=True):
        assert atol[slip.X[slot]] == (1e-8 if scale == 1e2 else 1e-10)
    columns = [c for c, _, _ in results.frame_layout(name)]
    assert all(col in columns for col, _, _, _ in form.columns)
    for other in set(transient.TRANSIENTS) - {name}:
        extra = {col for col, _, _, _ in transient.FORMS[other].columns} - {col for col, _, _, _ in form.columns}
        assert not extra & set(columns)
    result = wk.run(Scenario(tyre_transient=name, duration=0.2, settle=0.0))
    assert result.summary["tyres"]["transient"] == name
    assert [c for c in result.trajectory.columns if c in {col for col, _, _, _ in form.columns}] == \
        [col for col, _, _, _ in form.columns]


def test_a_second_form_written_in_c_is_refused():
    with pytest.raises(ValueError, match="four states"):
        transient.declare(dataclasses.replace(transient.FORMS["slip_lag"], name="x", states=("a",)))
    with pytest.raises(ValueError, match="one form written in C"):
        transient.declare(dataclasses.replace(transient.FORMS["carcass"], name="other_carcass"))
    assert "x" not in transient.FORMS and "other_carcass" not in transient.FORMS
