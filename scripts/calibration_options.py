"""Tables of several calibrations side by side, one per modelling option (docs/calibration.md).

Each folder is a ``calibrate --out DIR`` output (one rider model and kick
direction: the options are never pooled). Prints three Markdown tables:

1. per option: the non-implausible share after the last wave, the 90 %
   credible interval of every calibrated input, the largest implausibility
   at the posterior mean, and how many features the simulator's own runs at
   posterior draws predict within +-3 standardised errors;
2. per option, load and criterion: P(best) of each pressure (95 % Wilson
   interval) and the ``none`` share, the measured best (Table 8.9) in bold;
3. how often the measured best is the most probable pressure.

Usage::

    python scripts/calibration_options.py DIR [DIR ...]
"""
import argparse
import json
import pathlib
import sys

import numpy as np
import pandas as pd


def option(folder):
    """The modelling option a calibration is conditional on, in words."""
    choices = json.loads((folder / "settings.json").read_text())["choices"]
    return f"{choices['rider_body']} rider, {choices['lqr_model']} LQR, kicked {choices['kick_direction']}"


def summary_row(folder):
    """Table 1's cells of one calibration folder."""
    posterior = pd.read_csv(folder / "posterior.csv")
    features = pd.read_csv(folder / "features.csv")
    checks = pd.read_csv(folder / "checks.csv")
    share = checks[checks["check"] == "non_implausible_fraction"]["value"].iloc[-1]
    cells = [option(folder), f"{share:.3f}"]
    for name in posterior.columns:
        low, high = np.quantile(posterior[name], [0.05, 0.95])
        cells.append(f"{name} {low:.3g}-{high:.3g}")
    worst = features["implausibility_at_posterior_mean"].abs().max()
    ran = features[features["simulator_runs"] > 0]
    within = int((ran["simulator_standardised_error"].abs() <= 3).sum())
    return cells[:2] + ["; ".join(cells[2:]), f"{worst:.2f}", f"{within} of {len(ran)}"]


def p_best_rows(folder):
    """Table 2's rows of one calibration folder."""
    table = pd.read_csv(folder / "p_best.csv")
    rows, hits = [], []
    for (fz, criterion), group in table.groupby(["fz_n", "criterion"], sort=True):
        cells, best = [], None
        shown = group[group["pressure_kpa"].notna()].sort_values("pressure_kpa")
        for _, r in shown.iterrows():
            text = f"{r['p']:.2f} ({r['low']:.2f}-{r['high']:.2f})"
            cells.append(f"**{text}**" if r["measured_best"] else text)
            if r["measured_best"]:
                best = r["pressure_kpa"]
        none = group[group["pressure_kpa"].isna()]["p"]
        top = shown.loc[shown["p"].idxmax(), "pressure_kpa"]
        hits.append(best is not None and top == best)
        rows.append([option(folder), f"{fz:g} N", criterion, *cells,
                     f"{none.iloc[0]:.2f}" if len(none) else "0.00", f"{best:g}" if best is not None else "-"])
    return rows, hits


def markdown(header, rows):
    """A Markdown table."""
    lines = ["| " + " | ".join(header) + " |", "| " + " | ".join("---" for _ in header) + " |"]
    return "\n".join(lines + ["| " + " | ".join(str(c) for c in row) + " |" for row in rows])


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("folders", nargs="+", type=pathlib.Path, help="calibrate --out folders")
    args = p.parse_args(argv)
    missing = [str(f) for f in args.folders if not (f / "settings.json").is_file()]
    if missing:
        print(f"error: not a calibrate --out folder (no settings.json): {', '.join(missing)}", file=sys.stderr)
        return 2
    print(markdown(["option", "non-implausible share", "90 % credible intervals", "largest I at the posterior mean",
                    "features the simulator predicts within +-3"], [summary_row(f) for f in args.folders]))
    print()
    rows, hits = [], {}
    for folder in args.folders:
        if not (folder / "p_best.csv").is_file():
            continue
        r, h = p_best_rows(folder)
        rows += r
        hits[option(folder)] = h
    print(markdown(["option", "load", "criterion", "300 kPa", "400 kPa", "500 kPa", "none", "measured best"], rows))
    print()
    for name, h in hits.items():
        print(f"* {name}: the measured best is the most probable in {sum(h)} of {len(h)} (load, criterion)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
