"""The uncertainty study: known answers of its statistics, pairing, seeds, executors, refusals, the CLI."""
import dataclasses
import json
import math
import pathlib
import warnings

import numpy as np
import pandas as pd
import pytest

import whipple_kick as wk
from whipple_kick.errors import InputError
from whipple_kick.library import uncertain
from whipple_kick.simulate.scenario import Scenario
from whipple_kick.studies import uncertainty

# Short runs: the machinery, not the physics, is under test (as tests/conftest.py's SWEEP_BASE).
BASE = Scenario(settle=0.1, output_rate=200.0)
TINY = """format = "whipple_kick uncertainty, version 1"
name = "tiny"
description = "two inputs, for tests"
[fixed]
duration = { value = 3.0, reason = "short: the machinery is under test" }
[inputs.speed]
field = "speed"
distribution = "uniform"
unit = "m/s"
low = 1.92
high = 2.0
reason = "thesis Section 8.3"
[inputs.kick_direction]
field = "kick_direction"
distribution = "choice"
reason = "not given"
[[inputs.kick_direction.options]]
label = "right"
probability = 0.5
value = "right"
[[inputs.kick_direction.options]]
label = "left"
probability = 0.5
value = "left"
"""


def _tiny_path():
    """The TINY file, written once for the tests that need no fixture's scope."""
    import tempfile
    path = pathlib.Path(tempfile.gettempdir()) / f"whipple_kick_tiny_{hash(TINY) & 0xffffffff:x}.toml"
    if not path.exists():
        path.write_text(TINY)
    return path


@pytest.fixture(scope="module")
def tiny(tmp_path_factory):
    path = tmp_path_factory.mktemp("unc") / "tiny.toml"
    path.write_text(TINY)
    return path


@pytest.fixture(scope="module")
def tiny_study(tiny, tmp_path_factory):
    """N = 2 (8 rows) at 300 and 500 kPa, 635 N, in a sweep folder, on the process pool."""
    folder = tmp_path_factory.mktemp("unc") / "runs"
    return uncertainty.run_study(tiny, samples=2, seed=3, loads=[635.0], pressures=[300.0, 500.0], base=BASE,
                                 workers=2, folder=folder), folder


def _stable(study):
    return study.outcomes.drop(columns=["run.wall_s", "run.cpu_s", "numerics.integration_wall_s"])


# ----------------------------------------------------------------- known answers

def _spec(names, low, high):
    inputs = tuple(uncertain.UncertainInput(n, "uniform", "test", n, "1", low, high) for n in names)
    return uncertain.UncertainSet("t", "", "", inputs, {})


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_ishigami_sobol_indices_match_the_analytic_values_within_their_intervals(seed):
    """Ishigami (a = 7, b = 0.1, inputs uniform on [-pi, pi]) through the study's own path: its sampler
    (SALib's design mapped by the inputs' inverse CDFs) and its analysis. Analytic values: Ishigami and
    Homma (1990), e.g. Saltelli et al. (2008) Global Sensitivity Analysis, Section 4.8. N = 1024: the
    95 % intervals are 0.03-0.09 wide; each index must lie within its own interval."""
    a, b = 7.0, 0.1
    spec = _spec(["x1", "x2", "x3"], -math.pi, math.pi)
    var = a ** 2 / 8 + b * math.pi ** 4 / 5 + b ** 2 * math.pi ** 8 / 18 + 0.5
    v1 = 0.5 * (1 + b * math.pi ** 4 / 5) ** 2
    v13 = b ** 2 * math.pi ** 8 * (1 / 18 - 1 / 50)
    s1 = [v1 / var, a ** 2 / 8 / var, 0.0]
    st = [(v1 + v13) / var, a ** 2 / 8 / var, v13 / var]
    unit, blocks = uncertainty.sample(spec, 1024, seed)
    assert unit.shape == (1024 * 5, 3) and blocks[:5] == ["A", "AB1", "AB2", "AB3", "B"]
    x = np.column_stack([inp.ppf(unit[:, k]) for k, inp in enumerate(spec.inputs)])
    y = np.sin(x[:, 0]) + a * np.sin(x[:, 1]) ** 2 + b * x[:, 2] ** 4 * np.sin(x[:, 0])
    for k, (name, S1, S1c, ST, STc) in enumerate(uncertainty.sobol_indices(spec, y, seed)):
        assert name == f"x{k + 1}"
        assert abs(S1 - s1[k]) <= S1c and abs(ST - st[k]) <= STc, (name, S1, S1c, ST, STc)
        assert S1c < 0.1 and STc < 0.1   # intervals narrow enough to mean something
    # The intervals are seeded, seed 0 included (SALib alone leaves seed 0 unseeded).
    assert uncertainty.sobol_indices(spec, y, seed) == uncertainty.sobol_indices(spec, y, seed)


def test_p_best_of_a_synthetic_ranking_lands_in_its_interval():
    """Rows whose winner is drawn with known probabilities (0.2, 0.5, 0.2, and 0.1 none recovered):
    each probability lies within its 95 % Wilson interval; ties split the credit; a pressure never best
    in 16 rows keeps an upper bound (Wilson: z^2 / (n + z^2) = 0.194), not a zero-width interval."""
    rng = np.random.default_rng(7)
    truth = np.array([0.2, 0.5, 0.2, 0.1])
    winner = rng.choice(4, size=2000, p=truth)
    times = np.full((2000, 3), 2.0)
    times[np.arange(2000), np.minimum(winner, 2)] = 1.0
    times[winner == 3] = np.inf   # no pressure recovered
    p, low, high = uncertainty.p_best_interval(uncertainty._best_share(times))
    assert np.all((low <= truth) & (truth <= high)), (p, low, high)
    assert np.all(high - low < 0.06)
    p, low, high = uncertainty.p_best_interval(np.zeros((16, 1)))
    assert p[0] == 0.0 and low[0] == 0.0 and high[0] == pytest.approx(1.959964 ** 2 / (16 + 1.959964 ** 2), rel=1e-6)
    share = uncertainty._best_share(np.array([[1.0, 1.0, 3.0], [np.inf, 2.0, np.inf]]))
    assert share.tolist() == [[0.5, 0.5, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0]]


# ----------------------------------------------------------------- pairing and seeds

def test_every_pressure_and_load_gets_the_same_inputs_of_a_row():
    spec = uncertain.load()
    unit, _ = uncertainty.sample(spec, 2, 0)
    cases, keys = uncertainty.study_cases(spec, unit, [570.0, 701.0], [300.0, 400.0, 500.0],
                                          BASE.with_changes(**spec.fixed))
    assert len(cases) == len(unit) * 2 * 3
    scenarios = [c[1] for c in wk.sweep_engine.make_cases(cases=cases, base=BASE)]
    by_row = {}
    for (row, fz, p), sc in zip(keys, scenarios, strict=True):
        assert (sc.fz_n, sc.pressure_kpa) == (fz, p)
        by_row.setdefault(row, set()).add(sc.with_changes(fz_n=None, pressure_kpa=0.0))
    assert len(by_row) == len(unit) and all(len(s) == 1 for s in by_row.values())
    assert len({next(iter(s)) for s in by_row.values()}) > 1   # rows differ from each other
    # The hip stiffness is set only in the rows with the leaning body (elsewhere the run ignores it).
    for case in cases:
        assert ("hip_stiffness" in case) == (case["rider_body"] == "leaning")
    assert any(c["rider_body"] == "leaning" for c in cases) and any(c["rider_body"] == "rigid" for c in cases)


def test_the_same_seed_gives_the_same_samples():
    spec = uncertain.load()
    a, _ = uncertainty.sample(spec, 4, 11)
    b, _ = uncertainty.sample(spec, 4, 11)
    c, _ = uncertainty.sample(spec, 4, 12)
    assert np.array_equal(a, b) and not np.array_equal(a, c)


def test_tiny_study_counts_every_run(tiny_study):
    study, _ = tiny_study
    assert len(study.inputs) == 8 and len(study.outcomes) == 16
    pb = study.p_best[study.p_best["criterion"] == "settling"]
    assert math.isclose(pb["p"].sum(), 1.0) and (pb["rows"] == 4).all()   # A and B rows, none left out
    assert (study.rates["runs"] == 8).all()
    assert not study.outcomes.drop(columns=["error"]).isna().all().any()
    assert study.verdict and study.verdict[0].startswith("635 N: ")
    # The real runs through the new tables: P(best) per option of the direction, counted pairs, Sobol rows.
    bo = study.p_best_by_option[study.p_best_by_option["input"] == "kick_direction"]
    assert set(bo["option"]) <= {"right", "left"} and bo["rows"].sum() == 4 * 3 * 2   # 4 A/B rows x (2 pressures + none) x 2 criteria
    d = study.differences
    assert ((d["pairs_both_recovered"] + d["pairs_one_not_recovered"] + d["pairs_neither_recovered"]) == d["pairs"]).all()
    assert set(uncertainty.SOBOL_COLUMNS) == set(study.sobol.columns)
    assert not study.p_best_by_option["p"].isna().any()


def test_the_same_seed_gives_the_same_tables_and_the_folder_resumes(tiny, tiny_study):
    study, folder = tiny_study
    again = uncertainty.run_study(tiny, samples=2, seed=3, loads=[635.0], pressures=[300.0, 500.0], base=BASE,
                                  workers=2, folder=folder)   # every case is in the folder: nothing reruns
    pd.testing.assert_frame_equal(_stable(again), _stable(study))
    pd.testing.assert_frame_equal(again.outcomes, study.outcomes)   # wall times too: read back, not rerun
    pd.testing.assert_frame_equal(again.p_best, study.p_best)


def test_a_stored_study_is_analysed_again_without_running_and_a_short_one_says_what_it_lacks(tiny, tiny_study):
    # The N = 512 study's runs outlive the code that analysed them: analyse_folder reads them back by case id.
    study, folder = tiny_study
    again = uncertainty.analyse_folder(folder, tiny, samples=2, seed=3, loads=[635.0], pressures=[300.0, 500.0],
                                       base=BASE)
    pd.testing.assert_frame_equal(again.outcomes, study.outcomes)
    for name in ("p_best", "differences", "sobol", "measured"):
        pd.testing.assert_frame_equal(getattr(again, name), getattr(study, name))
    with pytest.raises(InputError, match=r"lacks 16 of the design's 32 runs \(at 570 N\)"):
        uncertainty.analyse_folder(folder, tiny, samples=2, seed=3, loads=[570.0, 635.0],
                                   pressures=[300.0, 500.0], base=BASE)
    with pytest.raises(InputError, match="holds no sweep"):
        uncertainty.analyse_folder(folder.parent, tiny, samples=2, seed=3, base=BASE)


def test_dask_gives_the_same_tables_as_the_pool(tiny, tiny_study, dask_client):
    study, _ = tiny_study
    dask = uncertainty.run_study(tiny, samples=2, seed=3, loads=[635.0], pressures=[300.0, 500.0], base=BASE,
                                 executor=dask_client.get_executor())
    pd.testing.assert_frame_equal(_stable(dask), _stable(study))
    for name in ("p_best", "distributions", "differences", "rates", "sobol"):
        pd.testing.assert_frame_equal(getattr(dask, name), getattr(study, name))


# ----------------------------------------------------------------- refusals

def _with_input(tmp_path, block):
    path = tmp_path / "u.toml"
    path.write_text(TINY + block)
    return path


@pytest.mark.parametrize("block, message", [
    ('[inputs.grip]\nfield = "grip"\ndistribution = "uniform"\nunit = "1"\nlow = 0.9\nhigh = 1.1\nreason = "x"\n',
     r"inputs\.grip: 'grip' is no scenario field"),
    ('[inputs.p]\nfield = "pressure_kpa"\ndistribution = "uniform"\nunit = "kPa"\nlow = 300\nhigh = 500\n'
     'reason = "x"\n', r"inputs\.p: the study sets pressure_kpa itself"),
    ('[inputs.hip]\nfield = "hip_stiffness"\ndistribution = "uniform"\nunit = "N m/rad"\nlow = 128\nhigh = 1000\n'
     'reason = "x"\n', r"inputs\.hip: hip_stiffness is read only by the leaning upper body \(rider_body "
                       r"'leaning'\), which no sample uses: it would be ignored"),
])
def test_inputs_naming_nothing_or_ignored_are_refused(tmp_path, block, message):
    with pytest.raises(InputError, match=message) as info:
        uncertainty.run_study(_with_input(tmp_path, block), samples=2, base=BASE)
    assert "\n" not in str(info.value)


def _shipped(tmp_path, old, new):
    text = pathlib.Path(uncertain.available()[uncertain.DEFAULT]).read_text()
    assert text.count(old) == 1
    path = tmp_path / "u.toml"
    path.write_text(text.replace(old, new))
    return uncertain.load(path)


def test_an_unknown_fixed_field_is_one_line_with_the_fields(tmp_path):
    """Issue 40 item 1: a misspelt [fixed] field was a TypeError traceback (the fixed fields were applied before
    they were checked)."""
    path = tmp_path / "u.toml"
    path.write_text(TINY.replace("duration = {", "durration = {"))
    with pytest.raises(InputError, match=r"fixed\.durration: 'durration' is no scenario field \(did you mean "
                                         r"'duration'\?\); the fields: bicycle, fz_n, .*, slip_speed$") as info:
        uncertainty.run_study(path, samples=2, base=BASE)
    assert "\n" not in str(info.value)


@pytest.mark.parametrize("old, new, message", [
    # Issue 40 item 3: the unit was never checked (km/h ran as m/s).
    ('unit = "m/s"', 'unit = "km/h"', r"inputs\.speed\.unit: 'km/h' is not the unit of speed, 'm/s': give the "
                                      r"distribution in m/s$"),
    # Issue 40 item 4: a bound, an option or a fixed value the scenario refuses, named by its key, with the value,
    # the allowed range and the unit (it failed only when a sample hit it, and named the whole row).
    ("high = 2.0", "high = 20.0", r"inputs\.speed\.high: speed = 20\.0 m/s is outside the allowed range "
                                  r"\(0, 15\] m/s$"),
    ('distribution = "uniform"\nunit = "m/s"\nlow = 1.92\nhigh = 2.0',
     'distribution = "normal"\nunit = "m/s"\nmean = 2.0\nsd = 0.5',
     r"inputs\.speed \(a normal not truncated below: its samples reach -1\.5\d* m/s; give 'low'\): speed = "
     r"-1\.5\d* m/s is outside the allowed range \(0, 15\] m/s$"),
    ('value = "left"', 'value = "leftt"', r"inputs\.kick_direction\.options\[1\] \(left\): kick direction "
                                          r"'leftt' is unknown"),
    ("value = 3.0", "value = -3.0", r"fixed\.duration: duration = -3\.0 s is outside the allowed range "
                                    r"\(0, 120\] s$"),
])
def test_units_bounds_options_and_fixed_values_are_checked_at_load(tmp_path, old, new, message):
    path = tmp_path / "u.toml"
    assert TINY.count(old) == 1
    path.write_text(TINY.replace(old, new))
    with pytest.raises(InputError, match=message) as info:
        uncertainty.check_inputs(uncertain.load(path), BASE)
    assert str(info.value).startswith(f"{path}: ") and "\n" not in str(info.value)


@pytest.mark.parametrize("old, new, message", [
    # Issue 40 item 5: a misspelt option was reported as the hip stiffness' problem (no sample leaned).
    ('rider_body = "leaning"', 'rider_body = "leening"',
     r"inputs\.rider\.options\[2\] \(leaning body\): rider body 'leening' is unknown; choose one of rigid, "
     r"leaning$"),
    # A bound of a field only some rows read is checked on a row that reads it (the leaning body's).
    ("high = 1000.0", "high = 2e6", r"inputs\.hip_stiffness\.high: hip stiffness = 2000000\.0 N m/rad is outside "
                                    r"the allowed range \(0, 1e\+06\] N m/rad$"),
    ('label = "plate peak"\nprobability = 0.5\nvalue = "plate"', 'label = "plate peak"\nprobability = 0.5\n'
                                                                  'value = "plates"',
     r"inputs\.friction\.options\[1\] \(plate peak\): friction = 'plates' is unknown"),
])
def test_the_shipped_file_with_one_mistake_names_it(tmp_path, old, new, message):
    spec = _shipped(tmp_path, old, new)
    with pytest.raises(InputError, match=message):
        uncertainty.check_inputs(spec, Scenario())


def test_a_tyre_measured_at_one_pressure_is_named_with_it():
    """Issue 40 item 6: ``--uncertain --tyre T01`` said the study "needs at least one rear load and two
    pressures", not that T01 was measured at 400 kPa only."""
    with pytest.raises(InputError, match=r"needs at least two, got 400 kPa; tyre T01 \(table7_9\) was measured at "
                                         r"400 kPa only, .* choose a tyre measured at two or more \(T02 \(300, 400 "
                                         r"kPa\), T03 \(300, 400, 500 kPa\)"):
        uncertainty.run_study(uncertain.DEFAULT, samples=2, base=Scenario(tyre="T01"), pressures=[400.0])


def test_pressures_outside_the_tyres_range_are_refused(tiny):
    with pytest.raises(InputError, match=r"pressure of tyre T03 = 600(\.0)? kPa is outside the allowed range \[300, 500\] kPa"):
        uncertainty.run_study(tiny, samples=2, pressures=[300.0, 600.0], base=BASE)


def test_the_shipped_file_passes_the_checks():
    spec = uncertain.load()
    uncertainty.check_inputs(spec, Scenario().with_changes(**spec.fixed))
    # Without the carcass transient the carcass inputs would be ignored: refused.
    with pytest.raises(InputError, match=r"carcass_stiffness_scale is read only by the carcass tyre"):
        uncertainty.check_inputs(dataclasses.replace(spec, fixed={**spec.fixed, "tyre_transient": "force_lag"}),
                                 Scenario())


# ----------------------------------------------------------------- the CLI

def test_cli_bad_file_and_misplaced_options_exit_2(tmp_path, capsys):
    from conftest import run_console
    bad = tmp_path / "bad.toml"
    bad.write_text(TINY.replace("low = 1.92\nhigh = 2.0", "low = 2.0\nhigh = 1.92"))
    code, out, err = run_console(wk.cli.recommend_main, ["--fz", "635", "--uncertain", str(bad)], capsys)
    assert code == 2 and err.count("\n") == 1 and "bounds inverted" in err and "Traceback" not in err
    code, _, err = run_console(wk.cli.recommend_main, ["--fz", "635", "--samples", "8"], capsys)
    assert code == 2 and "--samples and --seed belong to the uncertainty study" in err
    code, _, err = run_console(wk.cli.recommend_main, ["--fz", "635", "--uncertain", "--fine"], capsys)
    assert code == 2 and "--fine cannot go with --uncertain" in err
    # Issue 40 item 2: a negative seed was NumPy's ValueError traceback (status 1).
    code, _, err = run_console(wk.cli.recommend_main, ["--fz", "635", "--uncertain", "--seed", "-1"], capsys)
    assert code == 2 and err == "error: seed = -1 is outside the allowed range: a whole number >= 0\n"
    # Issue 40 item 6, from the command line.
    code, _, err = run_console(wk.cli.recommend_main, ["--fz", "635", "--uncertain", "--tyre", "T01"], capsys)
    assert code == 2 and err.count("\n") == 1 and "T01 (table7_9) was measured at 400 kPa only" in err


def test_cli_writes_tables_and_figures(tiny, tmp_path, capsys):
    from conftest import run_console
    out = tmp_path / "study"
    code, text, err = run_console(wk.cli.recommend_main, [
        "--fz", "635", "--pressures", "300", "500", "--uncertain", str(tiny), "--samples", "2", "--seed", "3",
        "--out", str(out), "--no-progress"], capsys)
    assert code == 0, err
    assert "P(best) by settling" in text and "635 N: " in text
    for name in ("p_best.csv", "p_best_by_option.csv", "outcomes.csv", "sobol.csv", "differences.csv", "measured.csv",
                 "verdict.txt", *wk.cli.UNCERTAINTY_FIGURES):
        assert (out / name).stat().st_size > 0, name


def test_falls_and_failures_are_counted_never_dropped(tiny):
    """The rules on a made-up sweep table (2 pressures, N = 2: 8 rows, 4 of them A/B rows): a fall ranks
    after a recovery, a row where nothing recovered is the 'none' share, a failed run leaves its row out
    of P(best) with a note, and the Sobol analysis counts every lost run as censored at the duration."""
    spec = uncertain.load(tiny)
    unit, blocks = uncertainty.sample(spec, 2, 0)
    cases, keys = uncertainty.study_cases(spec, unit, [635.0], [300.0, 500.0], BASE)
    ids = [f"c{k}" for k in range(len(keys))]
    rows = []
    for k, (r, _, p) in enumerate(keys):
        row = {"case_id": ids[k], "status": "ok", "error": None, "fell": False, "recovery.time_s": 2.0 + r / 10,
               "last_peak_time_s": 1.0, "run.wall_s": 0.1, "run.cpu_s": 0.1, "numerics.integration_wall_s": 0.05}
        if p == 300.0:
            row["recovery.time_s"] -= 0.5          # 300 kPa faster ...
        if r == 0 and p == 300.0:                  # ... except row 0 (A): 300 kPa fell
            row.update(fell=True)
        if r == 3:                                 # row 3 (B of base point 0): neither recovered
            row["recovery.time_s"] = math.nan      # row 3: neither recovered
        if r == 4 and p == 500.0:                  # row 4 (A of base point 1): 500 kPa failed
            row.update(status="failed", error="SimulationError: test", **{"recovery.time_s": math.nan})
        rows.append(row)
    study = uncertainty.analyse(spec, 2, 0, unit, blocks, keys, ids, pd.DataFrame(rows), 3.0)
    assert blocks[:4] == ["A", "AB1", "AB2", "B"]
    pb = study.p_best[study.p_best["criterion"] == "settling"]
    p = dict(zip(pb["pressure_kpa"].fillna(-1.0), pb["p"], strict=True))   # -1: the 'none' share
    # A/B rows 0, 3, 4, 7; row 4 failed (left out): row 0 -> 500 (300 fell), row 3 -> none, row 7 -> 300.
    assert (pb["rows"] == 3).all() and (pb["rows_failed"] == 1).all()
    assert np.allclose([p[300.0], p[500.0], p[-1.0]], [1 / 3, 1 / 3, 1 / 3])
    rates = study.rates.set_index("pressure_kpa")
    assert rates.loc[300.0, "fell"] == 1 and rates.loc[500.0, "failed"] == 1
    assert rates.loc[300.0, "not_recovered_settling"] == 1 and rates.loc[500.0, "not_recovered_settling"] == 1
    assert any("1 of 4 rows left out of P(best)" in n for n in study.notes)
    # Sobol: no run is given a time; the rows with one run (0: fell, 4: failed) or none (3) recovered are counted.
    s = study.sobol[study.sobol["criterion"] == "settling"]
    assert (s["rows"] == 8).all() and (s["rows_one_not_recovered"] == 2).all()
    assert (s["rows_neither_recovered"] == 1).all()
    assert any("1 of 8 rows have a failed run" in n for n in study.notes)
    # The differences count the pairs with a run not recovered (rows 0, 3, 7 used) and rank them.
    d = study.differences[study.differences["criterion"] == "settling"].iloc[0]
    assert (d["pairs"], d["pairs_both_recovered"], d["pairs_one_not_recovered"], d["pairs_neither_recovered"]) == \
        (3, 1, 1, 1)
    assert np.allclose([d["p_a_first"], d["p_b_first"], d["p_neither"], d["p_tie"]], [1 / 3, 1 / 3, 1 / 3, 0.0])
    assert math.isclose(d["p_a_faster"], 0.5) and math.isclose(d["first_sign_mean"], 0.0)
    assert not any(math.isnan(v) for v in study.p_best_by_option["p"])


def test_every_shipped_input_changes_the_run():
    """Each input of the shipped file does physics: moving it alone (unit sample 0.1 -> 0.9, the other
    inputs at 0.5, the rider at the leaning body so the hip stiffness acts) changes the yaw-rate history.
    1 s runs at 200 Hz: the change is in the dynamics, visible from the kick on."""
    spec = uncertain.load()
    base = Scenario(fz_n=635.0, pressure_kpa=400.0).with_changes(**spec.fixed).with_changes(
        duration=1.0, output_rate=200.0, settle=0.1)
    rider = spec.names.index("rider")
    middle = [0.5] * len(spec.inputs)
    middle[rider] = 0.9   # leaning body
    histories = {}
    for k, name in enumerate(spec.names):
        for u in (0.1, 0.9):
            row = list(middle)
            row[k] = u
            sc = base.with_changes(**uncertainty.row_values(spec, row, base))
            histories[name, u] = wk.run(sc).trajectory["yaw_rate"].to_numpy()
        low, high = histories[name, 0.1], histories[name, 0.9]
        assert low.shape != high.shape or np.max(np.abs(low - high)) > 1e-6, name


# ------------------------------------------------ a measured bicycle's +/- as inputs (issue 34)

BIKE_FILE = ('format = "whipple_kick uncertainty, version 1"\nname = "bike"\ndescription = "test"\n'
             '[inputs.speed]\nfield = "speed"\ndistribution = "uniform"\nunit = "m/s"\nlow = 2.9\nhigh = 3.1\n'
             'reason = "test"\n'
             '[bicycle]\nmeasured = "balanceassist_v1"\nparameters = ["c", "lam", "mB", "seating.lst"]\n'
             'reason = "the bicycle file\'s own standard deviations"\n')


def test_each_row_runs_on_its_sampled_bicycle_and_every_pressure_on_the_same_one(tmp_path):
    """A row's bicycle is the measured one with the row's sampled values (exactly: written with repr) and every
    other parameter as measured; all pressures and loads of a row share it (pairing), and a row that repeats
    another's values shares its folder."""
    from whipple_kick.library import bicycleparameters, bicycles
    path = tmp_path / "bike.toml"
    path.write_text(BIKE_FILE)
    spec = uncertain.load(path)
    measured = bicycles.load("balanceassist_v1")
    unit, _ = uncertainty.sample(spec, 2, 0)
    uncertainty.check_inputs(spec, BASE)
    cases, keys = uncertainty.study_cases(spec, unit, [570.0, 635.0], [300.0, 500.0], BASE)
    by_row = {}
    for case, (row, _, _) in zip(cases, keys, strict=True):
        by_row.setdefault(row, set()).add(case["bicycle"])
    assert all(len(paths) == 1 for paths in by_row.values())
    for row, (folder,) in list(by_row.items())[:3]:
        values = spec.values(unit[row])
        with pytest.warns(wk.errors.DefaultValueWarning):   # the tyres come from the run's tyre file
            bike = bicycleparameters.load(folder)
        for name in ("c", "lam", "mB"):
            assert bike.benchmark[name] == values[f"bicycle.{name}"]
        assert bike.geometry["lst"] == values["bicycle.seating.lst"]
        assert bike.benchmark["w"] == measured.benchmark["w"] and bike.benchmark["IBxx"] == measured.benchmark["IBxx"]
    assert uncertainty.sampled_bicycle("balanceassist_v1", {"bicycle.c": 0.05}) == \
        uncertainty.sampled_bicycle("balanceassist_v1", {"bicycle.c": 0.05})


def test_a_bicycle_input_without_its_table_is_refused(tmp_path):
    path = tmp_path / "u.toml"
    path.write_text(TINY + '[inputs.trail]\nfield = "bicycle.c"\ndistribution = "uniform"\nunit = "m"\n'
                           'low = 0.03\nhigh = 0.05\nreason = "test"\n')
    with pytest.raises(InputError, match=r"sampled from a \[bicycle\] table"):
        uncertainty.check_inputs(uncertain.load(path), BASE)


@pytest.mark.filterwarnings("ignore::whipple_kick.errors.DefaultValueWarning")
def test_a_study_on_sampled_bicycles_runs_and_names_their_parameters(tmp_path):
    """Two pressures x one load x 12 rows of 2 s runs: the study runs on the sampled folders and its input table
    and Sobol analysis name the bicycle's parameters."""
    path = tmp_path / "bike.toml"
    path.write_text(BIKE_FILE.replace('"mB", "seating.lst"', '"mB"'))
    study = uncertainty.run_study(path, samples=2, seed=0, loads=(635.0,), pressures=(300.0, 500.0),
                                  base=BASE.with_changes(duration=2.0), workers=1)
    assert {"bicycle.c", "bicycle.lam", "bicycle.mB"} <= set(study.inputs.columns)
    assert len(set(study.inputs["bicycle.c"])) > 1
    assert (study.outcomes["status"] == "ok").all() and len(study.outcomes) == 24


def test_the_defaults_warning_comes_once_per_study(tmp_path, recwarn):
    """Issue 40 item 9: a BicycleParameters bicycle's ~600-character defaults warning came once per sampled
    bicycle (each case reset the warnings' once-registry). The study warns once; a case does not."""
    path = tmp_path / "bike.toml"
    path.write_text(BIKE_FILE.replace('"mB", "seating.lst"', '"mB"'))
    base = BASE.with_changes(duration=0.2)
    uncertainty.run_study(path, samples=2, seed=0, loads=(635.0,), pressures=(300.0, 500.0), base=base, workers=1)
    defaults = [w for w in recwarn if issubclass(w.category, wk.errors.DefaultValueWarning)]
    assert len(defaults) == 1 and "'Sampled': tyres from defaults" in str(defaults[0].message)
    folder = uncertainty.sampled_bicycle("balanceassist_v1", {"bicycle.c": 0.051})
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        record = wk.sweep_engine.run_case(base.with_changes(bicycle=folder), "c0")
    assert record["status"] == "ok", record["error"]
    assert not [w for w in caught if issubclass(w.category, wk.errors.DefaultValueWarning)]
    assert "tyres" in json.loads(record["summary"])["bicycle"]["defaults"]   # the summary still says so


# ----------------------------------------------------------------- the analysis on synthetic outcome tables (issue 39)

def _synthetic(spec, samples, time_of, loads=(635.0,), pressures=(300.0, 500.0)):
    """``analyse`` on a made-up sweep table: ``time_of(labels of the row, load, pressure) -> (settling, last peak)``
    (NaN: not recovered)."""
    unit, blocks = uncertainty.sample(spec, samples, 0)
    keys = [(r, fz, p) for fz in loads for r in range(len(unit)) for p in pressures]
    ids = [f"c{k}" for k in range(len(keys))]
    rows = []
    for k, (r, fz, p) in enumerate(keys):
        settling, last_peak = time_of(spec.labels(unit[r]), fz, p)
        rows.append({"case_id": ids[k], "status": "ok", "error": None, "fell": False, "recovery.time_s": settling,
                     "last_peak_time_s": last_peak, "run.wall_s": 0.1, "run.cpu_s": 0.1,
                     "numerics.integration_wall_s": 0.05})
    return uncertainty.analyse(spec, samples, 0, unit, blocks, keys, ids, pd.DataFrame(rows), 6.0)


def test_the_sobol_output_does_not_depend_on_the_value_given_to_runs_that_did_not_recover():
    """Issue 39 item 4: a run not recovered was given the run's duration and a row where both were not recovered a
    difference of 0, so a few rows carried most of the variance and the indices moved with the duration. The
    output now is which pressure recovers first (+1, -1, 0): the same whatever value (above every recovered time)
    stands for "not recovered", 6 s or 8 s; the old difference is not."""
    rng = np.random.default_rng(3)
    t = rng.uniform(1.0, 5.0, size=(400, 2))
    t[rng.random((400, 2)) < 0.2] = np.inf          # 20 % of runs not recovered
    y = uncertainty.first_sign(t[:, 0], t[:, 1])
    for value in (6.0, 8.0, 1e3):
        c = np.where(np.isfinite(t), t, value)
        assert np.array_equal(uncertainty.first_sign(c[:, 0], c[:, 1]), y)
    old6, old8 = (np.where(np.isfinite(t), t, v) for v in (6.0, 8.0))
    assert np.var(old8[:, 1] - old8[:, 0]) > 1.2 * np.var(old6[:, 1] - old6[:, 0])   # the old output moved
    assert set(np.unique(y)) == {-1.0, 0.0, 1.0}
    both = ~np.isfinite(t).any(axis=1)
    assert (y[both] == 0).all()                      # neither recovered: a tie, not a number


def test_the_measurement_resolves_only_differences_beyond_its_error():
    """Thesis Tables 8.6-8.8: last-peak differences to the measured best of 0.04/0.05 s (570 N) and 0.06/0.07 s
    (635 N) are within the 95 % error of a difference of two cells, 1.96 sqrt(2) hypot(0.04, 0.005 / sqrt(3)) =
    0.111 s (the calibration file's trial prior and the printing's rounding); 0.20 s at 701 N is not."""
    sd, reason = uncertainty.measurement_error()
    assert sd == pytest.approx(math.hypot(0.04, 0.005 / math.sqrt(3)), rel=1e-12) and "trial prior 0.04 s" in reason
    spec = uncertain.load(_tiny_path())
    study = _synthetic(spec, 128, lambda lab, fz, p: (2.0, 0.4 + p / 1e4), loads=(570.0, 635.0, 701.0),
                       pressures=(300.0, 400.0, 500.0))
    m = study.measured[(study.measured["criterion"] == "last_peak") & study.measured["fz_n"].notna()]
    resolved = m.groupby("fz_n")["measured_resolved"].all().to_dict()
    assert resolved == {570.0: False, 635.0: False, 701.0: True}
    assert (m[m["fz_n"] != 701.0]["verdict"] == "not resolved by the measurement").all()
    assert np.allclose(sorted(m["measured_diff_s"]), [0.04, 0.05, 0.06, 0.07, 0.20, 0.20])
    # The model here: 300 kPa always 0.02 s before 500 kPa, 0.01 s before 400: far from the measured +0.20 s,
    # in 256 rows (q = 1 in n rows is resolved from 0.975 only for n > 151: at fewer, "not resolved at this N").
    assert (m[m["fz_n"] == 701.0]["verdict"] == "inconsistent").all()
    assert any("701 N" in line and "inconsistent" in line for line in study.verdict)
    assert any("570 N" in line and "not resolved by the measurement" in line for line in study.verdict)


@pytest.mark.parametrize("shift, verdict", [(-0.4, "inconsistent"), (0.0, "consistent")])
def test_fewer_rows_never_turn_a_failed_measurement_check_into_a_pass(shift, verdict):
    """Issue 39 item 4: "admitted when the upper end of P(best)'s interval reaches 0.05" passed more easily with
    fewer rows (a probability of 0 in 16 rows has the upper end 0.19, in 200 rows 0.019). The check now places
    the measured difference (0.20 s, sd 0.057 s) in the model's paired differences plus the measurement error
    (predictive_check); the same effect in fewer rows widens the interval and never makes an inconsistent check
    consistent (nor a failing one pass): it is "not resolved at this N" at most."""
    rng = np.random.default_rng(5)
    best = rng.uniform(2.0, 3.0, 200)
    other = best + 0.2 + shift + 0.05 * rng.standard_normal(200)
    sd = math.sqrt(2) * uncertainty.measurement_error()[0]
    assert uncertainty.predictive_check(best, other, 0.20, sd)[3] == verdict
    for n in (100, 48, 16, 8, 4, 2):
        q, low, high, got = uncertainty.predictive_check(best[:n], other[:n], 0.20, sd)
        assert low <= q <= high
        assert got in (verdict, "not resolved at this N"), (n, got)
    # The old rule on the same effect: never best in n rows is "admitted" below 73 rows, not above.
    assert uncertainty.p_best_interval(np.zeros((16, 1)))[2][0] >= 0.05 > uncertainty.p_best_interval(
        np.zeros((200, 1)))[2][0]
    # A row where neither recovered is unknown: it widens the interval (0 and 1 for its two ends), never decides.
    q, low, high, _ = uncertainty.predictive_check(np.array([np.inf] * 4), np.array([np.inf] * 4), 0.20, sd)
    assert (low, high) == (0.0, 1.0)


def test_p_best_is_given_per_option_and_the_verdict_says_what_it_hinges_on():
    """The rows of each option are a sample of the others: here the kick direction alone decides (right: 300 kPa,
    left: 500 kPa, by 0.5 s), so P(best) per option is 1 for its pressure while the pooled one is about 0.5, the
    verdict says the pooled answer is a tie, and the Sobol intervals separate (the direction, total index near
    1; the speed near 0): "hinges most on kick_direction". N = 64 (256 rows)."""
    spec = uncertain.load(_tiny_path())

    def time_of(lab, fz, p):
        fast = 300.0 if lab["kick_direction"] == "right" else 500.0
        return (2.0 if p == fast else 2.5), (0.4 if p == fast else 0.45)
    study = _synthetic(spec, 64, time_of)
    bo = study.p_best_by_option[(study.p_best_by_option["criterion"] == "settling")
                                & (study.p_best_by_option["input"] == "kick_direction")]
    p = {(r["option"], r["pressure_kpa"]): r["p"] for _, r in bo.dropna(subset=["pressure_kpa"]).iterrows()}
    assert p[("right", 300.0)] == 1.0 and p[("left", 500.0)] == 1.0 and p[("right", 500.0)] == 0.0
    pooled = bo["pooled_p"].iloc[0]
    assert 0.3 < pooled < 0.7
    assert set(study.p_best_by_option["input"]) == {"speed", "kick_direction"}
    speed = study.p_best_by_option[study.p_best_by_option["input"] == "speed"]
    assert set(speed["option"]) == {"< 1.96", ">= 1.96"}   # split at the median of uniform 1.92-2.0 m/s
    text = "\n".join(study.verdict)
    assert "a tie, " in text and "hinges most on kick_direction" in text, text
    assert "by option (most probable best): kick_direction: right 300 kPa (1.00" in text
    assert "recovery time" in text and "last-peak time" in text    # both criteria
    s = study.sobol[study.sobol["criterion"] == "settling"].set_index("input")
    assert s.loc["kick_direction", "ST"] > 0.9 and s.loc["speed", "ST"] < 0.05
    assert not uncertainty.sobol_caution(s.reset_index())
    text = uncertainty.format_study(study)
    assert "    kick_direction = right (" in text and "    speed = < 1.96 (" in text   # the choice, the hinge input
    assert "635 N settling 300/500 kPa: kick_direction " in text and "one not recovered 0 %, neither 0 %" in text


def test_unresolved_indices_get_a_caution_and_no_hinge():
    """Pure noise (the winner is random, independent of the inputs) at N = 8: the indices are not resolved;
    the verdict says no single input decides and cautions that N does not resolve them, and a power-of-2 N
    gets no note while N = 12 does."""
    spec = uncertain.load(_tiny_path())
    rng = np.random.default_rng(11)
    study = _synthetic(spec, 8, lambda lab, fz, p: (2.0 + rng.random(), 0.4 + rng.random()))
    text = "\n".join(study.verdict)
    assert "hinges most on" not in text and "no single input decides" in text
    assert "[caution: N = 8 does not resolve these indices" in text
    assert not any("not a power of 2" in n for n in study.notes)
    study = _synthetic(spec, 12, lambda lab, fz, p: (2.0 + rng.random(), 0.4 + rng.random()))
    assert any("N = 12 is not a power of 2" in n for n in study.notes)


def test_sobol_caution_names_implausible_sums_and_wide_intervals():
    rows = pd.DataFrame({"input": ["a", "b", "c"], "S1": [0.9, 0.6, -0.3], "S1_conf": [0.1, 0.1, 0.1],
                         "ST": [0.4, 0.3, 0.2], "ST_conf": [0.5, 0.4, 0.3]})
    reasons = uncertainty.sobol_caution(rows)
    assert any("first-order indices sum to 1.20 +- 0.17 (between 0 and 1)" in r for r in reasons)
    assert any("1 of 3 inputs with an index negative" in r for r in reasons)
    assert any("largest total index (a 0.40 +- 0.50) is not resolved from 0" in r for r in reasons)
    assert any("3 of the 3 inputs with a total index >= 0.05 have intervals wider" in r for r in reasons)
    # Interactions only: first-order indices near 0 with intervals wider than them are not a caution by
    # themselves (they are at any N); resolved totals are resolved.
    interacting = pd.DataFrame({"input": ["a", "b", "c"], "S1": [0.02, 0.01, 0.0], "S1_conf": [0.06, 0.05, 0.04],
                                "ST": [0.85, 0.5, 0.3], "ST_conf": [0.08, 0.08, 0.06]})
    assert uncertainty.sobol_caution(interacting) == []
    assert any("2 of the 2 inputs with a first-order index >= 0.05 have intervals wider" in r for r in
               uncertainty.sobol_caution(interacting.assign(S1=[0.1, 0.08, 0.0], S1_conf=[0.2, 0.1, 0.04])))
    good = pd.DataFrame({"input": ["a", "b"], "S1": [0.7, 0.2], "S1_conf": [0.05, 0.05], "ST": [0.8, 0.25],
                         "ST_conf": [0.05, 0.05]})
    assert uncertainty.sobol_caution(good) == []
    below = good.assign(S1=[-0.5, -0.4], S1_conf=[0.3, 0.3])   # first-order sum -0.9 +- 0.42: true ones >= 0
    assert any("first-order indices sum to -0.90 +- 0.42" in r for r in uncertainty.sobol_caution(below))
    top, second, separated = uncertainty.hinge(good)
    assert (top["input"], second["input"], separated) == ("a", "b", True)
    assert not uncertainty.hinge(rows)[2]


def test_a_continuous_input_is_split_at_its_default_inside_its_range_else_at_its_median():
    """gain_scale uniform 0.5-1.6 (the default 1.0 is the project's LQR gains, inside): halves below and above 1.0,
    not the median 1.05; speed 1.92-2.0 m/s (the default 3 m/s is outside): at the median 1.96 m/s."""
    inputs = (uncertain.UncertainInput("gain_scale", "uniform", "test", "gain_scale", "1", 0.5, 1.6),
              uncertain.UncertainInput("speed", "uniform", "test", "speed", "m/s", 1.92, 2.0))
    spec = uncertain.UncertainSet("t", "", "", inputs, {})
    table = pd.DataFrame({"gain_scale": [0.6, 1.02, 1.5], "speed": [1.93, 1.95, 1.99]})
    groups = {(name, option): mask.tolist() for name, option, mask in uncertainty.input_groups(spec, table)}
    assert groups == {("gain_scale", "< 1"): [True, False, False], ("gain_scale", ">= 1"): [False, True, True],
                      ("speed", "< 1.96"): [True, True, False], ("speed", ">= 1.96"): [False, False, True]}


def test_a_study_tolerance_is_a_fixed_entry_and_every_case_runs_at_it(tmp_path):
    """Issue 41 item 4: a study's rtol is its file's [fixed] rtol (docs/sweeps.md gives what 1e-8 changes);
    every case runs at it, and a value out of range is one line naming rtol, the range and the unit."""
    path = tmp_path / "u.toml"
    path.write_text(TINY.replace("[fixed]\n", '[fixed]\nrtol = { value = 1e-8, reason = "a quicker study" }\n'))
    uncertainty.run_study(path, samples=2, loads=[635.0], pressures=[300.0, 500.0], base=BASE, workers=1,
                          folder=tmp_path / "runs")
    table = pd.read_csv(tmp_path / "runs" / wk.sweep_store.TABLE_FILE)
    assert len(table) == 16 and (table["rtol"] == 1e-8).all() and (table["numerics.rtol"] == 1e-8).all()
    path.write_text(TINY.replace("[fixed]\n", '[fixed]\nrtol = { value = 0.1, reason = "too coarse" }\n'))
    with pytest.raises(InputError, match=r"fixed\.rtol: .*rtol.*0\.1.*1e-14.*0\.001") as info:
        uncertainty.run_study(path, samples=2, base=BASE)
    assert "\n" not in str(info.value)
