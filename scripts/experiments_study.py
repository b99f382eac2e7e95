"""The numbers of docs/experiments.md: the model against the thesis' kick-plate measurements, per tyre transient.

Usage:
    python scripts/experiments_study.py [--workers 2] [--forms contact_patch slip_lag force_lag]

For each tyre transient form (default: every one of
``whipple_kick.model.transient.transients()``, the default form first) it runs
``whipple_kick.studies.validation.validate`` (nine cases x two kick directions, the
experiments' set-up) and prints, as Markdown: the model against the measured
metrics per case, the mean |error| per metric, the slow swing, and the best
pressure per load by each rule and direction; then the printed
inconsistencies of the thesis tables and the implied time of peak #1. The
first lines name the commit, the model hash and the default transient the
numbers are from.
"""
import argparse
import statistics
import subprocess


def _fmt(value, fmt):
    try:
        v = float(value)
    except (TypeError, ValueError):
        return "-"
    return fmt.format(v) if v == v else "-"


def main():
    import whipple_kick as wk
    from whipple_kick.library import experiments
    from whipple_kick.simulate.scenario import Scenario
    from whipple_kick.studies import validation
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--forms", nargs="+", default=None)
    args = parser.parse_args()
    default = Scenario().tyre_transient
    forms = args.forms or [default] + [f for f in wk.transient.transients() if f != default]
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True).stdout.strip()
    print(f"commit {commit or 'unknown'}, model {wk.slip.model_hash()}, default tyre transient {default}\n")
    exp = experiments.load()
    results, verdicts = validation.compare_transients(validation.base_scenario(), forms, workers=args.workers)
    for form, result in results.items():
        t = result.table
        print(f"## tyre transient {form}\n")
        print("| case | source | last peak [s] | peaks | period [s] | δ 1-3 | δ 2-4 | δ 3-5 | f dom [Hz] | slow swing |")
        print("|---|---|---|---|---|---|---|---|---|---|")
        for _, r in t.sort_values(["case", "source", "direction"]).iterrows():
            src = r["source"] + (f" {r['direction']}" if r["direction"] else "")
            if r["status"] != "ok":
                print(f"| {r['case']} | {src} | {r['status']}: {r['error']} |||||||| ")
                continue
            print(f"| {r['case']} | {src} | {_fmt(r['last_peak_time_s'], '{:.3f}')} | {_fmt(r['n_peaks'], '{:.0f}')} | "
                  f"{_fmt(r['period_s'], '{:.3f}')} | {_fmt(r['log_dec_13'], '{:.2f}')} | "
                  f"{_fmt(r['log_dec_24'], '{:.2f}')} | {_fmt(r['log_dec_35'], '{:.2f}')} | "
                  f"{_fmt(r['dominant_frequency_hz'], '{:.0f}')} | {_fmt(r['slow_swing_ratio'], '{:.2f}')} |")
        s = result.summary
        print("\nmean |model - measured| (right / left / all, n):")
        for key, e in s["mean_abs_error"].items():
            print(f"- {key} [{e['unit']}]: {_fmt(e['right'], '{:.3f}')} / {_fmt(e['left'], '{:.3f}')} / "
                  f"{_fmt(e['all'], '{:.3f}')}, n = {e['n']}")
        model = t[(t["source"] == "model") & (t["status"] == "ok")]
        periods = [float(v) for v in model["period_s"] if v is not None and v == v]
        freqs = [float(v) for v in model["dominant_frequency_hz"] if v is not None and v == v]
        if periods:
            print(f"- model period #1-#3 {min(periods):.3f}-{max(periods):.3f} s (median {statistics.median(periods):.3f}); "
                  f"dominant frequency {min(freqs):.0f}-{max(freqs):.0f} Hz" if freqs else "")
        sw = s["slow_swing_ratio"]
        print(f"- slow swing 0.5-1 s after the kick: model mean {_fmt(sw['model_mean'], '{:.2f}')}, max "
              f"{_fmt(sw['model_max'], '{:.2f}')}, {sw['model_runs_above_measured']} runs above 0.08; measured {sw['measured']}")
        bp = s["best_pressure"]
        print("\nbest pressure per load (570/635/701 N): Table 8.9 " + "/".join(f"{p:g}" for p in bp["table_8_9"].values()))
        for rule in validation.RULES:
            for d in validation.DIRECTIONS:
                print(f"- {rule}, kicks to the {d}: " + "/".join("-" if p is None else f"{p:g}" for p in bp[rule][d].values())
                      + f" ({s['agreement_with_table_8_9'][rule][d]} agree)")
        for f in s["failed"]:
            print(f"- not compared: {f}")
        print()
    print("## does the best pressure depend on the tyre transient?\n")
    for rule, by_direction in verdicts.items():
        for d, text in by_direction.items():
            print(f"- {rule}, kicks to the {d}: {text}")
    print("\n## printed inconsistencies (eq. 8.3 and the % columns, within the printing's rounding)\n")
    for item in experiments.inconsistencies(exp):
        print(f"- {item['text']}")
    t1 = experiments.implied_first_peak_times(exp)
    print("\n## implied time of peak #1 with evenly spaced peaks [s]\n")
    print(", ".join(f"{k} {v:+.3f}" for k, v in t1.items()) + f"; mean {statistics.mean(t1.values()):+.3f}")


if __name__ == "__main__":
    main()
