"""Held-out checks and the simulator's posterior predictive (issue 39 items 1-2), on the toy simulator."""
import numpy as np
import pytest

from whipple_kick.errors import InputError
from whipple_kick.library import priors
from whipple_kick.studies import calibration as cal

CELLS3 = [(570.0, 300.0), (635.0, 400.0), (701.0, 500.0)]
NAMES = ["gain_scale", "carcass_stiffness_scale", "kick_accel"]
FAST = dict(walkers=16, steps=600, waves=1)


def _toy(bias=0.0):
    """The toy as a held-out factory; kicked left, its frequency is ``bias`` Hz higher (a direction the
    calibration never saw)."""
    def factory(prior_list, cells, features, direction):
        toy = cal.ToySimulator(prior_list, cells, features)
        if direction == "right" or not bias:
            return toy
        shift = np.array([bias if f == "frequency_hz" else 0.0 for _ in toy.cells for f in toy.features])
        return lambda X: toy(X) + shift
    return factory


def _synthetic(truth, seed=0):
    """Toy features at ``truth`` (unit cube) plus the stated measurement noise, over CELLS3."""
    spec = priors.load()
    pl = cal.choose_priors(spec, NAMES)
    table = cal.measured_features(spec, cells=CELLS3)
    x = np.array([p.low + u * p.width for p, u in zip(pl, truth, strict=True)])
    clean = cal.ToySimulator(pl, CELLS3, list(cal.FEATURE_UNITS))(x[None, :])[0]
    rng = np.random.default_rng(seed)
    return clean + table["sd_measurement"].to_numpy() * rng.standard_normal(len(clean))


def test_held_out_load_predicts_the_left_out_load_of_the_toy():
    """Known answer: measurements synthesised by the toy at one input; each load left out in turn is predicted
    from the other two within 3 standardised errors (the toy's load terms are known to it, so only the inputs
    must carry over), every feature of every left-out cell is predicted, and the table's rows become checks."""
    measured = _synthetic([0.4, 0.6, 0.5])
    frame = cal.held_out("load", _toy(), inputs=NAMES, cells=CELLS3, measured=measured, draws=8, **FAST)
    assert len(frame) == 9 and set(frame["held_out"]) == {"without 570 N", "without 635 N", "without 701 N"}
    assert (frame["runs"] == 8).all()
    assert (frame["standardised_error"].abs() < 3).all(), frame[["key", "standardised_error"]]
    inside = (frame["predictive_5"] <= frame["measured"]) & (frame["measured"] <= frame["predictive_95"])
    assert inside.mean() >= 0.75   # 90 % intervals: 7 of 9 at the least, with some luck in a 9-point sample
    checks = cal.held_out_checks(frame)
    assert checks.query("check == 'held_out_load_share'")["value"].iloc[0] == 1.0
    assert len(checks) == 10


def test_held_out_direction_finds_a_direction_the_calibration_never_saw():
    """Kicked left the toy's frequency is 3 Hz higher: the direction check's frequency errors exceed 3 (the
    check can fail), the other features' do not; without the bias every error is within 3."""
    measured = _synthetic([0.5, 0.5, 0.5], seed=1)
    biased = cal.held_out("direction", _toy(bias=3.0), inputs=NAMES, cells=CELLS3, measured=measured, **FAST)
    freq = biased["feature"] == "frequency_hz"
    assert (biased.loc[freq, "standardised_error"].abs() > 3).all()
    assert (biased.loc[~freq, "standardised_error"].abs() < 3).all()
    fair = cal.held_out("direction", _toy(), inputs=NAMES, cells=CELLS3, measured=measured, **FAST)
    assert (fair["standardised_error"].abs() < 3).all()


@pytest.mark.parametrize("call, message", [
    (lambda: cal.held_out("pressure", _toy()), "held-out check 'pressure' unknown: choose load or direction"),
    (lambda: cal.held_out("load", _toy(), cells=[(635.0, 400.0)]), "the cells hold one load"),
    (lambda: cal.held_out("load", _toy(), draws=1), "draws = 1 must be"),
    (lambda: cal.held_out("direction", _toy(), direction="up"), "kick direction 'up' unknown"),
])
def test_bad_held_out_inputs_are_one_line_errors(call, message):
    with pytest.raises(InputError, match=message) as info:
        call()
    assert "\n" not in str(info.value)


def test_features_hold_the_simulator_predictive_beside_the_measurement(tmp_path):
    """With posterior runs, features.csv holds per feature the simulator's predictive interval, its runs and
    standardised error; a feature the toy puts far from the measurement gets a large one; settings.json says
    what the posterior is conditional on."""
    import json

    import pandas as pd

    spec = priors.load()
    pl = cal.choose_priors(spec, NAMES[:2])
    result, _, _ = cal.known_answer(cal.ToySimulator, pl, np.array([0.5, 0.5]), seed=0, cells=CELLS3,
                                    walkers=16, steps=600, waves=1, check_runs=6)
    f = result.features
    assert (f["simulator_runs"] == 6).all()
    assert (f["simulator_5"] < f["simulator_mean"]).all() and (f["simulator_mean"] < f["simulator_95"]).all()
    assert (f["simulator_standardised_error"].abs() < 3).all()
    paths = {p.name for p in result.write(tmp_path)}
    assert {"settings.json", "features.csv"} <= paths
    settings = json.loads((tmp_path / "settings.json").read_text())
    assert settings["fields"] == {"gain_scale": "gain_scale", "carcass_stiffness_scale": "carcass_stiffness_scale"}
    assert settings["choices"]["kick_direction"] == "right" and settings["choices"]["rider_body"] == "rigid"
    assert len(pd.read_csv(tmp_path / "features.csv")) == 9
