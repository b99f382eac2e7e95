"""The study scripts' own output (scripts/ is not a package: imported by path)."""
import json
import pathlib
import sys

import pytest

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "scripts"))

import thesis_figures


def _summary(time_s, fell=False):
    return {"fell": fell, "fall_time_s": 1.25 if fell else None, "fall_reason": "roll" if fell else None,
            "recovery": {"time_s": time_s}}


def test_thesis_figures_says_when_a_run_did_not_recover():
    """A run that never settled reads "not recovered within the run" (before: "recovery ... None s")."""
    line = thesis_figures.run_line(_summary(None, fell=True))
    assert line == "fell at 1.250 s (roll); recovery (yaw, roll, steer rates within 5 %) not recovered within the run"
    assert "None" not in thesis_figures.run_line(_summary(None))
    assert thesis_figures.run_line(_summary(2.5)).endswith("within 5 %) 2.500 s")


def test_identification_scores_a_case_as_the_docs_say():
    """scripts/identify_rider.py: a case's score is the sum of its squared misses (MISS), the slow swing's
    excess over 8 %, 9 for a metric the model does not give and 100 for a fall; a perfect case scores 0."""
    import identify_rider as ir

    exp = ir.experiments.load()
    target = ir.measured(exp, 635.0, 400.0)
    assert target == {"dominant_frequency_hz": 6.0, "period_s": 0.19, "log_dec_13": 0.72, "n_peaks": 6,
                      "last_peak_time_s": 0.36}
    # Bounds map the unit box onto each parameter's range (log ranges geometrically).
    values = ir.values_of([0.0, 1.0, 0.5], ["arm_stiffness", "reflex_delay", "hip_stiffness"])
    assert values["arm_stiffness"] == 1.0 and abs(values["reflex_delay"] - 0.06) < 1e-15
    assert abs(values["hip_stiffness"] - (50.0 * 5000.0) ** 0.5) < 1e-9
    # Every searched parameter has bounds, and every combination names its own.
    for _fixed, names in ir.COMBINATIONS.values():
        assert set(names) <= set(ir.BOUNDS)


def test_every_stated_number_has_a_group_and_the_timings_are_their_script_s_record():
    """Issue 31 item 18: every marked number in the docs names a group of scripts/doc_numbers.py that reruns it;
    the README's timings are the latest record of the script that measured them (docs/timings.json), which
    exists; the recommender's spread constant is the one the docs state (both from recommender_spread.py)."""
    import doc_numbers

    found = doc_numbers.markers()
    assert len(found) > 50
    assert {key.split(".")[0] for _, key, _ in found} <= set(doc_numbers.GROUPS)
    assert doc_numbers.compare(doc_numbers.group_timing(), ["timing"]) == []
    from whipple_kick.studies import recommend
    stated = {key: text for _, key, text in found if key.startswith("spread.")}
    assert stated == {f"spread.{k}": f"{v:.3f}" for k, v in recommend.CRITERION_SPREAD_S.items()}


def test_the_uncertainty_doc_quotes_its_stored_study():
    """docs/uncertainty.md's numbers are those of the study stored in docs/uncertainty_study (its small tables,
    not rerun: the study takes half an hour), and that study's inputs are the shipped file's: an edited number,
    new tables or a changed uncertainty file without a rerun fail here."""
    import doc_numbers

    assert doc_numbers.compare(doc_numbers.group_uncertainty(), ["uncertainty"]) == []


def test_a_stale_number_is_caught(tmp_path, monkeypatch):
    """The check names a marker whose text differs from the rerun, one no group computes, and a computed key
    that no doc carries."""
    import doc_numbers

    (tmp_path / "docs").mkdir()
    (tmp_path / "README.md").write_text("cold <!-- number: timing.x -->20<!-- /number --> s, "
                                        "<!-- number: bogus.y -->1<!-- /number -->")
    for name in doc_numbers.DOCS[1:]:
        (tmp_path / name).write_text("")
    monkeypatch.setattr(doc_numbers, "ROOT", tmp_path)
    problems = doc_numbers.compare({"timing.x": "41", "timing.z": "2"}, ["timing"])
    assert problems == ["README.md: timing.x: the doc says '20', the model gives '41'",
                        "README.md: bogus.y: no group 'bogus' computes it (known: " + ", ".join(doc_numbers.GROUPS) + ")",
                        "timing.z: computed but no doc carries it"]


@pytest.mark.slow
def test_the_docs_numbers_match_a_rerun():
    """Reruns everything the docs state (scripts/doc_numbers.py, about 5-10 minutes on 2 cores) and fails naming
    each number that no longer matches the model."""
    import doc_numbers

    assert doc_numbers.main([]) == 0


@pytest.mark.slow
def test_uncertainty_study_reports_its_cost(tmp_path, capsys):
    """scripts/uncertainty_study.py on a two-input file at N = 2 (8 rows x 3 pressures x 3 loads, 3 s runs):
    it prints the study and the cost lines docs/uncertainty.md quotes."""
    import uncertainty_study

    path = tmp_path / "tiny.toml"
    path.write_text('format = "whipple_kick uncertainty, version 1"\nname = "tiny"\ndescription = "test"\n'
                    '[fixed]\nduration = { value = 3.0, reason = "short" }\n'
                    '[inputs.speed]\nfield = "speed"\ndistribution = "uniform"\nunit = "m/s"\nlow = 1.92\n'
                    'high = 2.0\nreason = "thesis Section 8.3"\n'
                    '[inputs.accel]\nfield = "kick_accel"\ndistribution = "uniform"\nunit = "m/s^2"\nlow = 30\n'
                    'high = 40\nreason = "thesis Section 8.3"\n')
    uncertainty_study.main(["--file", str(path), "--samples", "2", "--out", str(tmp_path / "out")])
    out = capsys.readouterr().out
    assert "cost: 72 runs (8 rows x 3 pressures x 3 loads; 72 distinct cases" in out
    assert "per run in its worker: wall mean" in out and "N = 500: 2000 rows, 18000 runs" in out
    record = json.loads((tmp_path / "out" / "cost.json").read_text())   # what docs/uncertainty.md's numbers read
    assert (record["runs"], record["rows"], record["distinct"], record["extrapolate_runs"]) == (72, 8, 72, 18000)
    first = (tmp_path / "out" / "p_best.csv").read_text()
    (tmp_path / "out" / "p_best.csv").unlink()
    capsys.readouterr()
    uncertainty_study.main(["--file", str(path), "--samples", "2", "--out", str(tmp_path / "out"), "--analyse"])
    assert "cost:" not in capsys.readouterr().out   # nothing ran
    assert (tmp_path / "out" / "p_best.csv").read_text() == first   # the same runs, the same statistics


@pytest.mark.slow
def test_sobol_censoring_compares_two_run_lengths(tmp_path, capsys):
    """scripts/sobol_censoring.py at N = 2 (24 rows x 3 pressures, 635 N, 6 and 8 s): it reports the rows without
    a time at each length and the new and the former indices against each other."""
    import sobol_censoring

    sobol_censoring.main(["--samples", "2", "--out", str(tmp_path)])
    out = capsys.readouterr().out
    assert "shipped file, N = 2 (24 rows), seed 0, 635 N; run length 6 s against 8 s" in out
    assert "new output (which recovers first), short run against long run:" in out and "old output" in out
    assert out.count("within the combined interval") == 8   # (new, old) x 2 criteria x (S1, ST)
    assert "which recovers first changed in" in out


def test_the_cost_bench_runs_each_path_and_its_counting_requests_are_inert_outside_valgrind(tmp_path, capsys):
    """scripts/bench_sweep.py cost (issue 41 item 6): every path runs and gets a ratio to the baseline run;
    the callgrind client requests compile and do nothing in a process valgrind does not run."""
    import bench_sweep

    lib = bench_sweep._callgrind_helper(str(tmp_path))
    lib.wk_cg_start()
    lib.wk_cg_stop(b"run")
    ratios = bench_sweep.bench_cost(1, 0.3, 1)
    assert set(ratios) == set(bench_sweep.COST_PATHS) and ratios["run"] == 1.0
    assert all(r > 0 for r in ratios.values())
    assert "instructions" not in capsys.readouterr().out


def test_the_fall_bench_runs_every_falling_case_on_both_careful_paths():
    """scripts/bench_sweep.py fall: each case falls on both careful paths (Python and C) after the same
    evaluations, and gets a wall time on each."""
    import bench_sweep

    walls, careful, facts = bench_sweep.bench_fall(1, 3.0)
    for label, _ in bench_sweep.FALLING:
        (evaluations, fall_time, _), (evaluations_c, fall_time_c, _) = (facts[label, p] for p in ("python", "c"))
        assert evaluations == evaluations_c and fall_time is not None
        assert abs(fall_time - fall_time_c) <= 1e-12   # round-off (tests/simulate/test_lsoda_c.py)
        assert all(walls[label, p][0] > careful[label, p][0] > 0 for p in bench_sweep.CAREFUL_PATHS)


def test_the_models_compiler_flags_give_the_bits_of_the_reference_flags(tmp_path):
    """Issue 41 item 3: the flags the model is built with (model.compiler.MODEL_FLAGS, -O3 -fno-math-errno) were adopted because
    they give -O2's trajectory bit for bit; this builds the model's C source both ways and integrates a
    short kick with each (exact equality: a flag that let the compiler reassociate or contract would fail)."""
    import bench_sweep
    import numpy as np

    from whipple_kick.model import compiler
    from whipple_kick.simulate.scenario import Scenario

    shipped = next(name for name, flags, _ in bench_sweep.FLAG_SETS if flags == compiler.MODEL_FLAGS)
    libraries = bench_sweep._flag_libraries(str(tmp_path), [bench_sweep.FLAG_SETS[0][0], shipped])
    scenario = Scenario(duration=1.0, settle=0.1)
    (_, x_ref, t_ref), (_, x, t) = (bench_sweep._integrate_with(lib, scenario) for lib in libraries.values())
    assert len(libraries) == 2 and t.size > 1000
    assert np.array_equal(t, t_ref) and np.array_equal(x, x_ref)


def test_calibration_options_tables_each_option_and_counts_where_the_measured_best_leads(tmp_path, capsys):
    """scripts/calibration_options.py on a synthetic calibrate folder: the option in words, the credible
    interval, the simulator's count within +-3, the measured best in bold and counted only where it leads."""
    import calibration_options

    folder = tmp_path / "cal"
    folder.mkdir()
    (folder / "settings.json").write_text(json.dumps({"choices": {"rider_body": "rigid", "lqr_model": "whipple",
                                                                  "kick_direction": "left"}}))
    (folder / "posterior.csv").write_text("gain_scale\n" + "\n".join(f"{0.6 + k / 1000:.3f}" for k in range(101)))
    (folder / "features.csv").write_text("implausibility_at_posterior_mean,simulator_runs,simulator_standardised_error\n"
                                         "1.5,8,0.5\n-2.5,8,-3.5\n0.2,0,\n")
    (folder / "checks.csv").write_text("check,name,value,detail\nnon_implausible_fraction,wave 1,0.25,x\n"
                                       "non_implausible_fraction,wave 2,0.125,x\n")
    rows = ["fz_n,criterion,pressure_kpa,p,low,high,rows,rows_failed,measured_best"]
    for criterion, shares in (("last_peak", (0.5, 0.3, 0.2)), ("settling", (0.1, 0.6, 0.3))):
        rows += [f"570.0,{criterion},{p:.1f},{s},0.0,1.0,32,0,{p == 300.0}" for p, s in zip((300.0, 400.0, 500.0),
                                                                                             shares, strict=True)]
        rows.append(f"570.0,{criterion},,0.0,0.0,0.1,32,0,False")
    (folder / "p_best.csv").write_text("\n".join(rows) + "\n")
    assert calibration_options.main([str(folder)]) == 0
    out = capsys.readouterr().out
    assert "| rigid rider, whipple LQR, kicked left | 0.125 | gain_scale 0.605-0.695 | 2.50 | 1 of 2 |" in out
    assert "| 570 N | last_peak | **0.50 (0.00-1.00)** | 0.30 (0.00-1.00) |" in out
    assert "the measured best is the most probable in 1 of 2 (load, criterion)" in out
    assert calibration_options.main([str(tmp_path)]) == 2
