"""The transient tyre forms: one declaration and its function each, read by everything that lists the forms."""
import dataclasses

import numpy as np
import pytest

import whipple_kick as wk
from whipple_kick.model import slip, transient
from whipple_kick.model.slip import compiled
from whipple_kick.simulate import lsoda, results
from whipple_kick.simulate.scenario import Scenario
from whipple_kick.studies.stability import linear


def test_the_lists_of_forms_are_the_declarations(capsys):
    """The compiled model's order, the scenario's choices, doc and help, and the CLI's help all come from FORMS."""
    from conftest import run_console
    from whipple_kick.simulate import settings

    assert transient.transients() == tuple(transient.FORMS) == ("contact_patch", "slip_lag", "force_lag", "carcass")
    assert transient.symbolic() == ("contact_patch", "slip_lag", "force_lag")
    declared = settings.settings(Scenario)["tyre_transient"]
    assert tuple(declared.choices) == transient.transients()
    _, text, _ = run_console(wk.cli.simulate_main, ["--help"], capsys)
    text = " ".join(text.split())
    for name, form in transient.FORMS.items():
        assert transient.check(name) == transient.transients().index(name)
        said = f"{name}{' (default)' * (name == transient.DEFAULT_TRANSIENT)}: {form.description}"
        assert said in declared.help and said in declared.doc and said in text


def test_the_compiled_model_has_a_branch_per_symbolic_form_and_the_carcass_last():
    """The generated C dispatches on the form's index: one branch per form with a SymPy block, the carcass (the one
    form written in C) the rest."""
    source = compiled.library_path().with_suffix(".c").read_text()
    for name in transient.symbolic():
        assert f"(mode == {transient.transients().index(name)})" in source
    assert "(mode == 3)" not in source and "wk_carcass_r(" in source


@pytest.mark.parametrize("name", transient.transients())
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
    for other in set(transient.transients()) - {name}:
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


# ------------------------------------------------------- a form declared here, in this test module only

def _lagged_again(wheel, first, second, vsy, speed, camber, fz, curves, sigma0):
    """The thesis' force lag as a form of this module's: its function, here, calls the shipped form's block."""
    return transient._force_lag(wheel, first, second, vsy, speed, camber, fz, curves, sigma0)


_AGAIN_STATES = ("again_fy_r", "again_fy_f", "again_mz_r", "again_mz_f")
_AGAIN_COLUMNS = (("again_fy_rear", "state", "again_fy_r", "N"), ("again_mz_front", "state", "again_mz_f", "N m"))


@pytest.fixture
def lagged_again():
    """A form declared here (a declaration and its function, nothing else edited), removed after the test."""
    form = transient.declare(transient.Form(
        "lagged_again", "the thesis' force lag, declared again in a test", _AGAIN_STATES, _lagged_again,
        scales=(1e2, 1e2, 1e2, 1e2), steady_outputs=("fy_ss_r", "fy_ss_f", "mz_ss_r", "mz_ss_f"),
        columns=_AGAIN_COLUMNS))
    try:
        yield form
    finally:
        del transient.FORMS[form.name]


def test_a_form_declared_here_is_a_choice_with_columns_states_and_its_own_cache_key(lagged_again, capsys):
    """The scenario's check and the command's choices take it, the trajectory has its declared columns with
    their units, its state names are the tyre slots' (the linear study names them by its columns), and the
    compiled model's key changes with it (and back)."""
    from conftest import run_console
    from whipple_kick.simulate import settings

    with_form = transient.fingerprint()
    assert transient.transients()[-1] == "lagged_again" and transient.check("lagged_again") == 4
    assert transient.symbolic()[-1] == "lagged_again"
    Scenario(tyre_transient="lagged_again").validate()
    assert "lagged_again" in settings.settings(Scenario)["tyre_transient"].choices
    code, _, err = run_console(wk.cli.simulate_main, ["--tyre-transient", "no_such", "--no-plot"], capsys)
    assert code == 2 and "lagged_again" in err        # argparse lists the choices, the new one among them
    names = results.column_names("lagged_again")
    assert [c for c in names if c.startswith("again_")] == ["again_fy_rear", "again_mz_front"]
    assert results.UNITS["again_fy_rear"] == "N" and results.unit_of("again_mz_front") == "N m"
    assert [slip.X[n] for n in _AGAIN_STATES] == [slip.X[n] for n in slip.PATCH_STATES]
    assert "again_fy_r" in slip.X and slip.for_parts(("trunk",)).X["again_mz_f"] == slip.X["mzf"]
    assert slip.tyre_state_names("lagged_again") == _AGAIN_STATES
    assert linear.state_labels("lagged_again")[-4:] == [("again_fy_rear", "N"), ("again_fy_f", ""),
                                                        ("again_mz_r", ""), ("again_mz_front", "N m")]
    assert lsoda.default_atol(1e-8, "lagged_again")[slip.X["again_fy_r"]] == 1e-8   # its scale 1e2: rtol itself
    del transient.FORMS["lagged_again"]
    try:
        assert transient.fingerprint() != with_form and "lagged_again" not in Scenario.__dataclass_fields__[
            "tyre_transient"].metadata["setting"].choices
        with pytest.raises(wk.errors.InputError, match="tyre transient 'lagged_again' is unknown"):
            Scenario(tyre_transient="lagged_again").validate()
        assert "again_fy_r" not in slip.X
    finally:
        transient.FORMS["lagged_again"] = lagged_again
    assert transient.fingerprint() == with_form


def test_a_form_whose_state_names_are_another_forms_in_other_slots_is_refused():
    with pytest.raises(ValueError, match=r"states \['fyf', 'fyr'\] are in other slots in form 'force_lag'"):
        transient.declare(dataclasses.replace(transient.FORMS["force_lag"], name="swapped",
                                              states=("fyf", "fyr", "mzr", "mzf")))
    assert "swapped" not in transient.FORMS


@pytest.mark.slow   # derives and compiles the model with five forms (55 s here), then runs it
def test_a_form_declared_here_runs_as_the_form_it_copies(lagged_again, tmp_path, capsys):
    """Declared in this module alone, the copy of the thesis' force lag is generated into the compiled model
    (its own branch, its own cache entry), run from the command line and from Python, and gives the thesis'
    form's trajectory bit for bit: the same expressions generate the same C arithmetic in another branch
    (measured: every shared column identical over a 0.5 s run), so the tolerance is 0."""
    from conftest import run_console

    source = compiled.library_path().with_suffix(".c").read_text()
    assert "(mode == 4)" in source and "again_fy_r" in source
    code, _, err = run_console(wk.cli.simulate_main, ["--tyre-transient", "lagged_again", "--duration", "0.5",
                                                      "--no-plot", "--quiet", "--out", str(tmp_path / "run")],
                               capsys)
    assert code == 0, err
    header = (tmp_path / "run" / "trajectory.csv").read_text().splitlines()[0].split(",")
    assert "again_fy_rear [N]" in header and "again_mz_front [N m]" in header
    copy = wk.run(Scenario(tyre_transient="lagged_again", duration=0.5)).trajectory
    thesis = wk.run(Scenario(tyre_transient="force_lag", duration=0.5)).trajectory
    assert set(copy.columns) == {*thesis.columns, "again_fy_rear", "again_mz_front"}
    for column in thesis.columns:
        assert np.array_equal(copy[column].to_numpy(), thesis[column].to_numpy()), column
    assert np.array_equal(copy["again_fy_rear"].to_numpy(), copy["fy_rear"].to_numpy())   # its state: the force
