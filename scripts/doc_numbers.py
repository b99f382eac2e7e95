"""Rerun what the docs state and compare it with their text, so that no stated number goes stale.

A number a doc states is wrapped in a marker naming how it is computed::

    <!-- number: nine.570.recovery -->2.917 / 3.189 / 2.705<!-- /number -->

(invisible in the rendered Markdown). Each key's group (:data:`GROUPS`, the
part of the key before the first dot) reruns what the number comes from and
formats it as the doc prints it; the check lists every marker whose text
differs, every marker whose key no group computes, and every computed key no
doc carries. Timings (``timing.*``) are not rerun: they are the latest output
of the script that measured them, recorded in :data:`TIMINGS` with the
machine and the date the doc states; the check is that the script exists and
that the doc's numbers are that record.

Usage::

    python scripts/doc_numbers.py                 # check every group (about 5 minutes on 2 cores)
    python scripts/doc_numbers.py --only workflow simulate timing
    python scripts/doc_numbers.py --write         # rewrite the marked numbers with the values computed now
    python scripts/doc_numbers.py --list          # the keys the docs carry, by group

Exit status 1 when a number is stale (or unknown), 0 when every checked one matches. A slow test
(tests/test_scripts.py) runs the check.
"""
import argparse
import json
import math
import pathlib
import re
import sys

ROOT = pathlib.Path(__file__).resolve().parents[1]
#: The files whose markers are checked.
DOCS = ("README.md", "docs/sweeps.md", "docs/workflow.md", "docs/simulate.md", "docs/experiments.md",
        "docs/validation.md", "docs/uncertainty.md")
MARKER = re.compile(r"<!-- number: ([\w.]+) -->(.*?)<!-- /number -->", re.DOTALL)
#: Timings measured by a script (scripts/bench.py writes it): key -> value, script, machine, date.
TIMINGS = ROOT / "docs" / "timings.json"
LOADS = (570.0, 635.0, 701.0)


#: The spread of the thesis' force lag [s] (recommender_spread.py run on it, not rerun here): its table's verdicts.
FORCE_LAG_SPREAD_S = {"settling": 0.570, "last_peak": 0.011}


def _recommendation_cells(prefix, base=None, spread=None):
    """The nine-case table (recommend-pressure --fz 570 635 701): per load, both criteria's values and verdicts.

    ``spread``: the verdicts' spread by criterion [s] (default the recommender's own, CRITERION_SPREAD_S).
    """
    from whipple_kick.studies import recommend

    out = {}
    for rec in recommend.recommend_pressures(list(LOADS), base=base):
        load = f"{prefix}.{rec.fz_n:g}"
        rows = rec.table
        for criterion, column, name in (("settling", "recovery.time_s", "recovery"),
                                        ("last_peak", "last_peak_time_s", "last_peak")):
            out[f"{load}.{name}"] = " / ".join(f"{v:.3f}" for v in rows[column])
            best, margin, verdict = recommend._verdict(rows, criterion)
            if spread is not None and margin is not None:
                verdict = "clear" if margin >= spread[criterion] else "no clear optimum"
            out[f"{load}.{name}_best"] = f"{best:g} kPa, {margin:.3f} s: {verdict}"
    return out


def group_nine():
    """docs/sweeps.md: the nine thesis cases on the default model."""
    return _recommendation_cells("nine")


def group_force_lag():
    """docs/sweeps.md: the nine cases on the thesis' force lag."""
    from whipple_kick.simulate.scenario import Scenario
    return _recommendation_cells("force_lag", Scenario(tyre_transient="force_lag"), FORCE_LAG_SPREAD_S)


def group_fine():
    """docs/sweeps.md: the best pressure on the fine grid (T03's tyres interpolated every 10 kPa), both criteria."""
    from whipple_kick.studies import recommend

    out = {}
    for rec in recommend.recommend_pressures(list(LOADS), fine=True, step_kpa=10.0):
        for criterion, name in (("settling", "recovery"), ("last_peak", "last_peak")):
            best, margin, verdict = recommend._verdict(rec.table, criterion)
            out[f"fine.{rec.fz_n:g}.{name}_best"] = f"{best:g} kPa, {margin:.3f} s: {verdict}"
    return out


def group_spread():
    """docs/sweeps.md and recommend.CRITERION_SPREAD_S: the spread of each criterion (recommender_spread.py)."""
    import contextlib
    import io

    sys.path.insert(0, str(ROOT / "scripts"))
    import recommender_spread

    with contextlib.redirect_stdout(io.StringIO()):
        spread = recommender_spread.measure()
    return {"spread.settling": f"{spread['settling']:.3f}", "spread.last_peak": f"{spread['last_peak']:.3f}"}


def group_workflow():
    """docs/workflow.md: the default run's metrics at 100 Hz, 1 kHz and 5 kHz output."""
    import whipple_kick as wk

    out = {}
    for rate, label, digits in ((100.0, "100hz", 2), (1000.0, "1khz", 3), (5000.0, "5khz", 4)):
        s = wk.run(wk.Scenario(output_rate=rate)).summary
        out[f"workflow.recovery_{label}"] = f"{s['recovery']['time_s']:.{digits}f}"
        out[f"workflow.yaw_peak_{label}"] = f"{s['metrics']['yaw_rate_peaks_from_steady_rad_s'][0]:.3f}"
    return out


def group_simulate():
    """docs/simulate.md: where the bicycle without steer control loses its fork."""
    import whipple_kick as wk

    s = wk.run(wk.Scenario(controller="off")).summary
    assert s["fall_reason"] == "steer", s["fall_reason"]   # the docs say the fork turned over
    return {"simulate.off_fall_s": f"{s['fall_time_s']:.3f}", "simulate.off_fall_4": f"{s['fall_time_s']:.4f}"}


def group_experiments():
    """docs/experiments.md: the identified trunk rider's 6-7 Hz mode (rate against rate) and its last peaks
    found with and without the peak search's +-4 % noise band."""
    sys.path.insert(0, str(ROOT / "scripts"))
    import identify_rider

    out = {}
    mode = identify_rider.fast_mode(identify_rider.best_fields(ROOT / "docs" / "identification.json"))
    out["experiments.mode"] = f"{mode['eigenvalue'].real:.2f} +- {mode['eigenvalue'].imag:.1f}j"
    out["experiments.mode_hz"] = f"{mode['eigenvalue'].imag / (2 * math.pi):.2f}"
    out["experiments.steer_over_yaw_rate"] = f"{mode['rates']['u7'] / mode['rates']['u3']:.1f}"
    out["experiments.roll_over_yaw_rate"] = f"{mode['rates']['u4'] / mode['rates']['u3']:.2f}"
    out["experiments.lean_over_yaw_rate"] = f"{mode['rates']['u11'] / mode['rates']['u3']:.2f}"
    bands = identify_rider.last_peaks_by_band(ROOT / "docs" / "identification.json")
    for band, got in bands.items():
        out[f"experiments.{band}.runs"] = f"{got['runs']}"
        out[f"experiments.{band}.in_range"] = f"{got['in_range']}"
        out[f"experiments.{band}.range"] = f"{got['low']:.3f}-{got['high']:.3f}"
        out[f"experiments.{band}.mean_error"] = f"{got['mean_error']:.3f}"
    return out


def group_timing():
    """README.md: timings, as recorded by the script that measured them (not rerun)."""
    record = json.loads(TIMINGS.read_text())
    out = {}
    for key, entry in record.items():
        script = ROOT / entry["script"].split()[0]
        if not script.is_file():
            raise SystemExit(f"{TIMINGS.name}: {key} was measured by {entry['script']!r}, which does not exist")
        out[f"timing.{key}"] = f"{entry['value']:.{entry.get('digits', 1)}f}"
        out[f"timing.{key}.by"] = f"`{entry['script']}` on {entry['machine']}, {entry['date']}"
    return out


#: The uncertainty study docs/uncertainty.md quotes: its small tables (scripts/uncertainty_study.py --out DIR
#: writes them; copied here, not the runs) and study.json (N, seed, inputs, commit).
UNCERTAINTY = ROOT / "docs" / "uncertainty_study"


def _interval(row):
    return f"{row['p']:.2f} [{row['low']:.2f}, {row['high']:.2f}]"


def group_uncertainty():
    """docs/uncertainty.md: the stored study's P(best) (pooled and per option), the check against the measurement,
    rates, Sobol ranges and cost (the tables in :data:`UNCERTAINTY`; a rerun of the study is
    ``python scripts/uncertainty_study.py`` with study.json's N and seed). The shipped uncertainty file's inputs
    must be the study's: a changed file makes the doc stale."""
    import pandas as pd

    from whipple_kick.library import uncertain

    meta = json.loads((UNCERTAINTY / "study.json").read_text())
    shipped = [i.name for i in uncertain.load(uncertain.DEFAULT).inputs]
    if shipped != meta["inputs"]:
        raise SystemExit(f"docs/uncertainty_study holds a study of inputs {meta['inputs']}, the shipped file has "
                         f"{shipped}: rerun the study (docs/uncertainty.md says how) and copy its tables")
    n, d = meta["samples"], len(meta["inputs"])
    p_best = pd.read_csv(UNCERTAINTY / "p_best.csv")
    by_option = pd.read_csv(UNCERTAINTY / "p_best_by_option.csv")
    measured = pd.read_csv(UNCERTAINTY / "measured.csv")
    rates = pd.read_csv(UNCERTAINTY / "rates.csv")
    sobol = pd.read_csv(UNCERTAINTY / "sobol.csv")
    cost = json.loads((UNCERTAINTY / "cost.json").read_text())
    loads = sorted(p_best["fz_n"].unique())
    out = {"uncertainty.samples": f"{n}", "uncertainty.inputs": f"{d}", "uncertainty.rows": f"{n * (d + 2)}",
           "uncertainty.base_rows": f"{2 * n}", "uncertainty.runs": f"{cost['runs']}",
           "uncertainty.seed": f"{meta['seed']}", "uncertainty.commit": meta["commit"],
           "uncertainty.analysed": meta["analysed"], "uncertainty.loads": " and ".join(f"{f:g}" for f in loads)}
    for (fz, criterion), rows in p_best.groupby(["fz_n", "criterion"], sort=True):
        cells = []
        for _, row in rows.sort_values("pressure_kpa", na_position="last").iterrows():
            text = _interval(row) if row["pressure_kpa"] == row["pressure_kpa"] else f"{row['p']:.2f}"
            cells.append(f"**{text}**" if row["measured_best"] else text)
        out[f"uncertainty.p_best.{criterion}.{fz:g}"] = " / ".join(cells)
    for criterion in ("settling", "last_peak"):
        out[f"uncertainty.options.{criterion}"] = _options_table(by_option[by_option["criterion"] == criterion], loads)
    lp = measured[measured["criterion"] == "last_peak"]
    for fz, rows in lp[lp["fz_n"].notna()].groupby("fz_n"):
        diffs = ", ".join(f"{r['pressure_kpa']:g} kPa {r['measured_diff_s']:+.2f} s" for _, r in rows.iterrows())
        first = rows.iloc[0]
        out[f"uncertainty.measured.{fz:g}"] = (f"{first['measured_best_kpa']:g} kPa best ({diffs}; sd of a "
                                               f"difference {first['measured_sd_s']:.3f} s): {first['verdict']}")
    whole = lp[lp["fz_n"].isna()].iloc[0]
    out["uncertainty.measured.whole"] = (f"{whole['verdict']}; P = {whole['p_best']:.2f} [{whole['p_best_low']:.2f}, "
                                         f"{whole['p_best_high']:.2f}]")
    out["uncertainty.fell"] = f"{int(rates['fell'].sum())}"
    out["uncertainty.failed"] = f"{int(rates['failed'].sum())}"
    for criterion in ("settling", "last_peak"):
        column = rates[f"not_recovered_{criterion}"]
        out[f"uncertainty.not_recovered.{criterion}"] = f"{column.min()}-{column.max()}"
        none = p_best[(p_best["criterion"] == criterion) & p_best["pressure_kpa"].isna()]["p"]
        low, high = f"{100 * none.min():.0f}", f"{100 * none.max():.0f}"
        out[f"uncertainty.none.{criterion}"] = f"{low} %" if low == high else f"{low}-{high} %"
        rows = sobol[sobol["criterion"] == criterion]
        for name, group in rows.groupby("input", sort=False):
            out[f"uncertainty.st.{criterion}.{name}"] = f"{group['ST'].min():.2f}-{group['ST'].max():.2f}"
        one = 100 * rows["rows_one_not_recovered"] / rows["rows"]
        neither = 100 * rows["rows_neither_recovered"] / rows["rows"]
        out[f"uncertainty.censored.{criterion}"] = (f"{one.min():.0f}-{one.max():.0f} % / "
                                                     f"{neither.min():.0f}-{neither.max():.0f} %")
    out["uncertainty.st_conf_max"] = f"{sobol['ST_conf'].max():.2f}"
    out["uncertainty.verdict"] = "\n".join(f"* {line}" for line in
                                            (UNCERTAINTY / "verdict.txt").read_text().split("\n\n")[0].splitlines())
    for key in ("run_cpu_mean_s", "run_wall_mean_s", "integration_wall_mean_s"):
        out[f"uncertainty.cost.{key}"] = f"{cost[key]:.3f}"
    out["uncertainty.cost.integration_share"] = f"{100 * cost['integration_share']:.0f} %"
    out["uncertainty.cost.distinct"] = f"{cost['distinct']}"
    out["uncertainty.cost.wall_s"] = f"{cost['wall_s']:.0f}"
    return out


def _options_table(rows, loads):
    """P(best) per option (p_best_by_option.csv rows of one criterion) as a Markdown table: an input's option per
    row, per load the pressures' P(best) (the most probable in bold) and the option's rows."""
    header = "| input = option | " + " | ".join(f"{fz:g} N: 300 / 400 / 500 kPa (rows)" for fz in loads) + " |"
    lines = [header, "| --- |" + " --- |" * len(loads)]
    for (name, option), group in rows.groupby(["input", "option"], sort=False):
        cells = []
        for fz in loads:
            at = group[(group["fz_n"] == fz) & group["pressure_kpa"].notna()].sort_values("pressure_kpa")
            top = at["p"].max()
            shares = [f"**{p:.2f}**" if p == top else f"{p:.2f}" for p in at["p"]]
            cells.append(" / ".join(shares) + f" ({int(at['rows'].iloc[0])})")
        lines.append(f"| {name} = {option} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


GROUPS = {"nine": group_nine, "force_lag": group_force_lag, "fine": group_fine, "spread": group_spread,
          "workflow": group_workflow, "simulate": group_simulate, "experiments": group_experiments,
          "timing": group_timing, "uncertainty": group_uncertainty}


def markers():
    """Every marker in :data:`DOCS`: (file, key, text)."""
    found = []
    for name in DOCS:
        for match in MARKER.finditer((ROOT / name).read_text()):
            found.append((name, match.group(1), match.group(2)))
    return found


def compare(computed, groups):
    """Lines naming each stale, unknown or unplaced number of ``groups``."""
    problems = []
    carried = set()
    for name, key, text in markers():
        group = key.split(".")[0]
        if group not in GROUPS:
            problems.append(f"{name}: {key}: no group {group!r} computes it (known: {', '.join(GROUPS)})")
            continue
        if group not in groups:
            continue
        carried.add(key)
        if key not in computed:
            problems.append(f"{name}: {key}: group {group!r} does not compute it")
        elif computed[key] != text:
            problems.append(f"{name}: {key}: the doc says {text!r}, the model gives {computed[key]!r}")
    problems += [f"{key}: computed but no doc carries it" for key in sorted(set(computed) - carried)]
    return problems


def write(computed):
    """Replace each marked text with the value computed now."""
    for name in DOCS:
        path = ROOT / name
        text = path.read_text()
        new = MARKER.sub(lambda m: (f"<!-- number: {m.group(1)} -->{computed[m.group(1)]}<!-- /number -->"
                                    if m.group(1) in computed else m.group(0)), text)
        if new != text:
            path.write_text(new)
            print(f"rewrote {name}")


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--only", nargs="+", choices=list(GROUPS), help="groups to rerun (default all)")
    p.add_argument("--write", action="store_true", help="rewrite the marked numbers with the computed values")
    p.add_argument("--list", action="store_true", help="print the docs' keys by group and exit")
    args = p.parse_args(argv)
    if args.list:
        for name, key, text in markers():
            print(f"{name}: {key} = {text}")
        return 0
    groups = args.only or list(GROUPS)
    computed = {}
    for group in groups:
        computed.update(GROUPS[group]())
    if args.write:
        write(computed)
    problems = compare(computed, groups)
    for line in problems:
        print(line)
    print(f"{len(computed)} numbers of {', '.join(groups)} computed; {len(problems)} problems")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
