"""Do the uncertainty study's Sobol indices depend on the run's length? (issue 39 item 4's acceptance)

The old Sobol output gave a run that did not recover by the run's end the
run's duration as its time (and a row where neither pressure recovered a
difference of 0), so its indices moved with the duration. The new output
(:func:`whipple_kick.studies.uncertainty.first_sign`: which pressure recovers
first, +1/-1/0) gives such a run no time at all. This script runs the shipped
study at one load twice on the same rows (same N and seed): with the run
length of the shipped file (6 s) and with a longer one (8 s, the uncertainty
file's ``[fixed]`` ``duration`` changed), and reports

* per criterion and pair of pressures: the share of rows with one / neither
  run not recovered at each length, and how many runs' criterion value changed;
* for the new indices and for the old ones (the difference with the censored
  time, computed here from the same runs for contrast): how many of the 8 s
  indices lie within the 6 s index's 95 % interval and vice versa, and within
  the two intervals combined (two estimates, each with its error; a bootstrap
  interval of an index that is exactly 0 in these rows has zero width), the
  ones outside, the largest change, and the sums of the indices.

Usage::

    nice python scripts/sobol_censoring.py --samples 16 --load 635 [--durations 6 8] [--out DIR] [--workers 1]

(``--out`` keeps the runs, so a stopped run resumes.)
"""
import argparse
import dataclasses
import itertools
import os
import sys
import tempfile
import time

import numpy as np
import pandas as pd

from whipple_kick.library import uncertain
from whipple_kick.simulate.criteria import CRITERIA
from whipple_kick.simulate.scenario import Scenario
from whipple_kick.studies import uncertainty


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--samples", type=int, default=16, help="SALib base samples N (default 16)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--load", type=float, default=635.0, help="rear load [N] (default 635)")
    p.add_argument("--durations", type=float, nargs=2, default=(6.0, 8.0), help="the two run lengths [s]")
    p.add_argument("--workers", type=int, default=1)
    p.add_argument("--out", help="folder for the runs (default: a temporary one)")
    args = p.parse_args(argv)
    spec = uncertain.load()
    studies = {}
    with tempfile.TemporaryDirectory() as tmp:
        out = args.out or tmp
        for duration in args.durations:
            t0 = time.perf_counter()
            s = dataclasses.replace(spec, fixed={**spec.fixed, "duration": duration})
            studies[duration] = uncertainty.run_study(
                s, samples=args.samples, seed=args.seed, loads=[args.load], base=Scenario(), workers=args.workers,
                folder=os.path.join(out, f"runs_{duration:g}s"), progress=sys.stderr.isatty())
            print(f"{duration:g} s: {len(studies[duration].outcomes)} runs in {time.perf_counter() - t0:.0f} s",
                  flush=True)
    short, long_ = args.durations
    print(f"\nshipped file, N = {args.samples} ({len(studies[short].inputs)} rows), seed {args.seed}, "
          f"{args.load:g} N; run length {short:g} s against {long_:g} s")
    report(studies[short], studies[long_], short, long_)


def times(study, criterion):
    """``(rows x pressures)`` criterion values, ``inf`` where the run did not recover (fell, failed, not settled)."""
    col = CRITERIA[criterion].column
    o = study.outcomes
    v = pd.to_numeric(o[col], errors="coerce").to_numpy(dtype=float)
    ok = np.isfinite(v) & ~o["fell"].to_numpy(dtype=bool) & (o["status"] == "ok").to_numpy()
    pressures = list(dict.fromkeys(o["pressure_kpa"]))
    return np.where(ok, v, np.inf).reshape(-1, len(pressures)), pressures


def old_indices(study, criterion, duration):
    """The old output's indices: ``T(b) - T(a)`` with a run not recovered given the run's duration."""
    t, pressures = times(study, criterion)
    c = np.where(np.isfinite(t), t, duration)
    rows = []
    for (i, pa), (j, pb) in itertools.combinations(enumerate(pressures), 2):
        y = c[:, j] - c[:, i]
        if np.ptp(y) == 0.0:
            continue
        for name, s1, s1c, st, stc in uncertainty.sobol_indices(study.spec, y, study.seed):
            rows.append({"criterion": criterion, "pressure_a_kpa": pa, "pressure_b_kpa": pb, "input": name,
                         "S1": s1, "S1_conf": s1c, "ST": st, "ST_conf": stc})
    return pd.DataFrame(rows)


def compare(a, b, label):
    """Print how many indices of ``b`` lie within ``a``'s intervals and the other way, and within the two
    intervals combined (``sqrt(conf_a^2 + conf_b^2)``: two estimates, each with its error), per criterion."""
    keys = ["criterion", "pressure_a_kpa", "pressure_b_kpa", "input"]
    m = a.merge(b, on=keys, suffixes=("_a", "_b"))
    for criterion, g in m.groupby("criterion", sort=False):
        for idx in ("S1", "ST"):
            d = (g[f"{idx}_b"] - g[f"{idx}_a"]).abs()
            ca, cb = g[f"{idx}_conf_a"], g[f"{idx}_conf_b"]
            within_a, within_b = int((d <= ca).sum()), int((d <= cb).sum())
            within = int((d <= np.hypot(ca, cb)).sum())
            zero = int((ca == 0).sum())
            print(f"  {label} {criterion} {idx}: {within_a} of {len(g)} long-run indices within the short run's "
                  f"interval ({zero} of those intervals of zero width), {within_b} the other way, {within} within "
                  f"the combined interval; largest change {d.max():.2f} (median half-width {ca.median():.2f})")
            out = g[d > np.hypot(ca, cb)]
            for _, r in out.iterrows():
                print(f"    outside: {r['pressure_a_kpa']:g}/{r['pressure_b_kpa']:g} kPa {r['input']}: "
                      f"{r[f'{idx}_a']:.2f} +- {r[f'{idx}_conf_a']:.2f} -> {r[f'{idx}_b']:.2f} +- "
                      f"{r[f'{idx}_conf_b']:.2f}")
        sums = g.groupby(["pressure_a_kpa", "pressure_b_kpa"])[["ST_a", "ST_b", "S1_a", "S1_b"]].sum()
        neg = int((g["S1_a"] < 0).sum()), int((g["S1_b"] < 0).sum())
        print(f"  {label} {criterion}: sums of total indices per pair {_range(sums['ST_a'])} / {_range(sums['ST_b'])}, "
              f"of first-order {_range(sums['S1_a'])} / {_range(sums['S1_b'])}; negative first-order "
              f"{neg[0]} / {neg[1]} of {len(g)}")


def _range(s):
    return f"{s.min():.2f}-{s.max():.2f}"


def report(short, long_, d_short, d_long):
    """Print the comparison of the two studies (same rows, two run lengths)."""
    for criterion in CRITERIA:
        ts, pressures = times(short, criterion)
        tl, _ = times(long_, criterion)
        rec_s, rec_l = np.isfinite(ts), np.isfinite(tl)
        both = rec_s & rec_l
        changed = int((np.abs(ts[both] - tl[both]) > 1e-9).sum())
        print(f"\n{criterion}: runs recovered {int(rec_s.sum())} / {int(rec_l.sum())} of {ts.size} "
              f"({d_short:g} s / {d_long:g} s); recovered at {d_short:g} s but not at {d_long:g} s: "
              f"{int((rec_s & ~rec_l).sum())}; recovered in both with another value: {changed}")
        for (i, pa), (j, pb) in itertools.combinations(enumerate(pressures), 2):
            shares = []
            for t in (ts, tl):
                one = np.isfinite(t[:, i]) != np.isfinite(t[:, j])
                both = ~np.isfinite(t[:, i]) & ~np.isfinite(t[:, j])
                shares.append(f"one {100 * one.mean():.0f} %, neither {100 * both.mean():.0f} %")
            sign_changed = int((uncertainty.first_sign(ts[:, i], ts[:, j])
                                != uncertainty.first_sign(tl[:, i], tl[:, j])).sum())
            print(f"  {pa:g}/{pb:g} kPa: rows with a run not recovered {shares[0]} ({d_short:g} s), {shares[1]} "
                  f"({d_long:g} s); which recovers first changed in {sign_changed} of {len(ts)} rows")
    print("\nnew output (which recovers first), short run against long run:")
    compare(short.sobol, long_.sobol, "new")
    print("\nold output (T(b) - T(a), a run not recovered given the run's duration), for contrast:")
    compare(pd.concat([old_indices(short, c, d_short) for c in CRITERIA]),
            pd.concat([old_indices(long_, c, d_long) for c in CRITERIA]), "old")
    for name, study in (("short", short), ("long", long_)):
        cautions = [" / ".join(uncertainty.sobol_caution(g)) for _, g in
                    study.sobol.groupby(["criterion", "pressure_a_kpa", "pressure_b_kpa"], sort=False)]
        print(f"\n{name} run: {sum(bool(c) for c in cautions)} of {len(cautions)} outputs get the caution "
              "(indices not resolved at this N)")


if __name__ == "__main__":
    main()
