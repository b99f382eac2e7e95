"""Uncertainty files: the shipped one reads, every bad file is one line, the inverse CDFs are right."""
import numpy as np
import pytest
from scipy import stats

import whipple_kick as wk
from whipple_kick.errors import InputError
from whipple_kick.library import uncertain

HEAD = 'format = "whipple_kick uncertainty, version 1"\nname = "t"\ndescription = "test"\n'
SPEED = ('[inputs.speed]\nfield = "speed"\ndistribution = "uniform"\nunit = "m/s"\nlow = 1.92\nhigh = 2.0\n'
         'reason = "thesis Section 8.3"\n')
DIRECTION = ('[inputs.dir]\nfield = "kick_direction"\ndistribution = "choice"\nreason = "not given"\n'
             '[[inputs.dir.options]]\nlabel = "right"\nprobability = {p}\nvalue = "right"\n'
             '[[inputs.dir.options]]\nlabel = "left"\nprobability = 0.5\nvalue = "left"\n')


def write(tmp_path, body):
    path = tmp_path / "u.toml"
    path.write_text(HEAD + body)
    return path


def test_the_shipped_file_reads_with_a_reason_on_every_input():
    spec = uncertain.load()
    assert spec.name == "kickplate_2025" and list(uncertain.available()) == ["kickplate_2025"]
    assert spec.names == ("speed", "kick_accel", "kick_direction", "carcass_stiffness_scale", "carcass_damping",
                          "friction", "rider", "gain_scale", "hip_stiffness", "rear_load_share")
    assert all(len(i.reason) > 20 for i in spec.inputs)
    rider = spec.inputs[spec.names.index("rider")]
    assert rider.fields == ("lqr_model", "rider_body")
    assert rider.possible("rider_body") == {"rigid", "leaning"}
    # The published ranges (thesis Section 8.3; identification bounds) as the file gives them.
    speed, accel = spec.inputs[0], spec.inputs[1]
    assert (speed.low, speed.high, accel.low, accel.high) == (1.92, 2.0, 30.0, 40.0)
    assert spec.fixed["kick_profile"] == "smooth" and spec.fixed["duration"] == 6.0
    # The share: from the seated rider (0.630 at 570 N) to Table 8.3's totals (0.694 at 701 N), rounded out;
    # every value in it is reachable at every study load (riders.for_load_share; shift <= 0.15 m, tested there).
    share = spec.inputs[spec.names.index("rear_load_share")]
    assert (share.field, share.low, share.high) == ("rear_load_share", 0.63, 0.70)
    bike = wk.bicycles.load("balanceassist_v1")
    for fz in (570.0, 635.0, 701.0):
        for value in (share.low, share.high):
            assert abs(wk.riders.for_load_share(bike, value, fz_n=fz).shift_m) <= 0.15


def test_inverse_cdfs():
    """Uniform, truncated normal and choice map the unit interval as their distributions say (exact
    quantiles; a choice's frequencies on a fine grid within 1e-3, the grid's resolution)."""
    u = np.linspace(0.0005, 0.9995, 1000)
    uni = uncertain.UncertainInput("a", "uniform", "r", "speed", "m/s", 1.0, 3.0)
    assert np.allclose(uni.ppf(u), 1.0 + 2.0 * u)
    norm = uncertain.UncertainInput("b", "normal", "r", "speed", "m/s", None, None, 2.0, 0.5)
    assert np.allclose(norm.ppf(u), stats.norm.ppf(u, 2.0, 0.5))
    assert np.isfinite(norm.ppf([0.0, 1.0])).all()   # the edges are kept inside (0, 1)
    cut = uncertain.UncertainInput("c", "normal", "r", "speed", "m/s", 1.9, 2.6, 2.0, 0.5)
    x = cut.ppf(u)
    assert x.min() >= 1.9 and x.max() <= 2.6 and np.all(np.diff(x) > 0)
    opts = tuple(uncertain.Option(k, p, {"f": k}) for k, p in (("a", 0.2), ("b", 0.5), ("c", 0.3)))
    choice = uncertain.UncertainInput("d", "choice", "r", options=opts)
    freq = np.bincount(choice.ppf(u), minlength=3) / u.size
    assert np.allclose(freq, [0.2, 0.5, 0.3], atol=1e-3)


@pytest.mark.parametrize("body, message", [
    (SPEED.replace('distribution = "uniform"', 'distribution = "lognormal"'),
     r"inputs\.speed\.distribution: 'lognormal' is unknown; choose one of uniform, normal, choice"),
    (SPEED.replace("low = 1.92\nhigh = 2.0", "low = 2.0\nhigh = 1.92"),
     r"inputs\.speed: bounds inverted or empty: low = 2 m/s must be < high = 1\.92 m/s"),
    (SPEED.replace('reason = "thesis Section 8.3"\n', ""), r"inputs\.speed: missing 'reason'"),
    (SPEED.replace('unit = "m/s"', 'unit = "m/s"\nmean = 1.0'), r"inputs\.speed: unknown key\(s\) mean"),
    (DIRECTION.format(p=0.6), r"inputs\.dir\.options: probabilities sum to 1\.1, not 1 \(within 1e-09\)"),
    (DIRECTION.format(p=0.5) + DIRECTION.format(p=0.5).replace("inputs.dir", "inputs.dir2"),
     r"inputs\.dir2: sets 'kick_direction', which inputs\.dir sets too"),
    (SPEED.replace('distribution = "uniform"\nunit = "m/s"\nlow = 1.92\nhigh = 2.0',
                   'distribution = "normal"\nunit = "m/s"\nmean = 2.0\nsd = 0.0'), r"inputs\.speed\.sd: value 0"),
    ("", r"inputs: must be a table"),
])
def test_bad_files_are_one_line(tmp_path, body, message):
    with pytest.raises(InputError, match=message) as info:
        uncertain.load(write(tmp_path, body))
    assert "\n" not in str(info.value) and str(tmp_path) in str(info.value)


def test_probabilities_within_the_tolerance_pass(tmp_path):
    spec = uncertain.load(write(tmp_path, DIRECTION.format(p=0.5 + 5e-10)))
    assert spec.values([0.25]) == {"kick_direction": "right"} and spec.values([0.75]) == {"kick_direction": "left"}


def test_a_missing_file_is_one_line():
    with pytest.raises(InputError, match=r"uncertainty file 'nope\.toml' does not exist \(shipped: kickplate_2025\)"):
        uncertain.load("nope.toml")


def test_facade():
    assert wk.uncertain is uncertain


# ------------------------------------------------ a measured bicycle's +/- as inputs (issue 34)

BICYCLE = ('[bicycle]\nmeasured = "balanceassist_v1"\nparameters = ["c", "lam", "seating.lst"]\n'
           'reason = "the bicycle file\'s own standard deviations"\n')


def test_a_bicycle_table_samples_the_measured_parameters_from_their_standard_deviations(tmp_path):
    """Each named parameter becomes a normal input with the file's value as mean and its +/- as sd (times
    sd_scale), truncated to 3 sd: the numbers are those of BicycleParameters' own reading of the file."""
    from whipple_kick.library import bicycleparameters, bicycles
    known = bicycleparameters.parameter_uncertainties(bicycles.load("balanceassist_v1"))
    spec = uncertain.load(write(tmp_path, SPEED + BICYCLE))
    assert spec.measured_bicycle == "balanceassist_v1"
    assert spec.names == ("speed", "bicycle.c", "bicycle.lam", "bicycle.seating.lst")
    for inp in spec.inputs[1:]:
        mean, sd = known[inp.name.removeprefix("bicycle.")]
        assert inp.distribution == "normal" and (inp.mean, inp.sd) == (mean, sd)
        assert (inp.low, inp.high) == (mean - 3 * sd, mean + 3 * sd)
        assert inp.ppf([0.5])[0] == pytest.approx(mean, abs=1e-12 * abs(mean))
    doubled = uncertain.load(write(tmp_path, SPEED + BICYCLE + "sd_scale = 2.0\n"))
    assert [i.sd for i in doubled.inputs[1:]] == [2 * i.sd for i in spec.inputs[1:]]


@pytest.mark.parametrize("body, message", [
    (BICYCLE.replace('"lam"', '"g"'), "'g' has no standard deviation in 'balanceassist_v1'"),
    (BICYCLE.replace('reason = "the bicycle file\'s own standard deviations"\n', ""), "must have measured and reason"),
    (BICYCLE + "sd_scale = 0\n", "bicycle.sd_scale: value 0 must be > 0"),
    ('[fixed]\nbicycle = { value = "benchmark", reason = "x" }\n' + BICYCLE, "fixed.bicycle would contradict it"),
])
def test_a_bad_bicycle_table_is_one_line(tmp_path, body, message):
    with pytest.raises(InputError, match=message.replace("(", r"\(").replace(")", r"\)")) as info:
        uncertain.load(write(tmp_path, SPEED + body))
    assert "\n" not in str(info.value)
