"""How much of a pressure ranking is the model's own spread: the recommender's "no clear optimum" rule.

On the nine thesis cases (T03 at 300/400/500 kPa x rear loads 570/635/701 N,
default scenario) this script measures, for each ranking criterion of
``whipple_kick.simulate.criteria.CRITERIA`` (the recovery time, i.e. yaw, roll and steer rates settled,
and the thesis' last-peak time):

* the value per case at the default settings (rtol 1e-10), the margin between
  the best and the second-best pressure per load, and the ranking;
* how far the value moves when the integration tolerance changes (rtol 1e-8
  and 1e-12) and when the tyre coefficients change by 1 %: the Magic-Formula
  F_y peak factor (a1, a2), its cornering stiffness (a3), its curvature (a6,
  a7), its camber terms (a5, a8, a11), the M_z peak (c1, c2)
  and stiffness (c3, c4), every F_y and M_z coefficient at once, and eight
  draws of every coefficient scaled by an independent random factor in
  [0.99, 1.01] (front and rear alike);
* the spread: the largest such change over the nine cases, per criterion.
  That is ``wk.recommend.CRITERION_SPREAD_S``: a margin below it is "no clear optimum".

Usage: ``python scripts/recommender_spread.py`` (about 2 minutes on one core).
"""
import math
import sys

import numpy as np

import whipple_kick as wk
from whipple_kick.simulate import simulation
from whipple_kick.simulate.criteria import CRITERIA
from whipple_kick.simulate.simulation import Scenario

PRESSURES = (300.0, 400.0, 500.0)
LOADS = (570.0, 635.0, 701.0)
#: summary path of each criterion's value
VALUES = {"settling": lambda s: s["recovery"]["time_s"], "last_peak": lambda s: s["metrics"]["last_peak_time_s"]}


class PerturbedTyre:
    """A loaded tyre whose Magic-Formula coefficients are multiplied by factors (study only).

    ``fy_factors`` (14,) and ``mz_factors`` (18,) multiply the F_y and M_z
    coefficients of every coefficient set the tyre blends.
    """

    def __init__(self, tyre, fy_factors, mz_factors, label):
        self._tyre, self._fy, self._mz, self._label = tyre, fy_factors, mz_factors, label

    def __getattr__(self, name):
        return getattr(self._tyre, name)

    def __repr__(self):
        return f"{self._tyre!r} with {self._label}"

    @property
    def blend(self):
        return [(w, fy * self._fy, mz * self._mz) for w, fy, mz in self._tyre.blend]


def factors(indices, n, factor=1.01):
    out = np.ones(n)
    out[list(indices)] = factor
    return out


def perturbations():
    """(label, F_y factors, M_z factors) of the 1 % tyre changes."""
    rng = np.random.default_rng(20260121)
    out = [
        ("F_y peak D (a1, a2) x1.01", factors((1, 2), 14), np.ones(18)),
        ("F_y cornering stiffness BCD (a3) x1.01", factors((3,), 14), np.ones(18)),
        ("F_y curvature E (a6, a7) x1.01", factors((6, 7), 14), np.ones(18)),
        ("F_y camber terms (a5 x0.99, a8, a11 x1.01)", factors((8, 11), 14) * factors((5,), 14, 0.99), np.ones(18)),
        ("M_z peak D (c1, c2) x1.01", np.ones(14), factors((1, 2), 18)),
        ("M_z stiffness (c3, c4) x1.01", np.ones(14), factors((3, 4), 18)),
        ("every coefficient x1.01", np.full(14, 1.01), np.full(18, 1.01)),
    ]
    for k in range(8):
        out.append((f"every coefficient x U(0.99, 1.01), draw {k + 1}",
                    rng.uniform(0.99, 1.01, 14), rng.uniform(0.99, 1.01, 18)))
    return out


def summary(scenario, tyres=None):
    try:
        return simulation.run(scenario, tyres=tyres).summary   # a failed run's summary too
    except simulation.SimulationError:   # nothing computed to return
        return None


def value(s, criterion):
    if s is None or s["fell"] or s["outcome"] != "completed":
        return math.nan
    v = VALUES[criterion](s)
    return math.nan if v is None else v


def measure():
    """Print the tables and return the spread [s] by criterion (what ``CRITERION_SPREAD_S`` holds)."""
    print(f"slip model {wk.slip.model_hash()}\n")
    base = {(p, fz): summary(Scenario(pressure_kpa=p, fz_n=fz)) for fz in LOADS for p in PRESSURES}
    variants = {f"rtol {rtol:g}": {} for rtol in (1e-8, 1e-12)}
    for (p, fz) in base:
        for rtol in (1e-8, 1e-12):
            variants[f"rtol {rtol:g}"][(p, fz)] = summary(Scenario(pressure_kpa=p, fz_n=fz, rtol=rtol))
    for label, fy, mz in perturbations():
        variants[label] = {}
        for (p, fz) in base:
            scenario = Scenario(pressure_kpa=p, fz_n=fz)
            rear, front, _ = wk.assembly.build_tyres(scenario.tyre_spec)
            pair = (PerturbedTyre(rear, fy, mz, label), PerturbedTyre(front, fy, mz, label))
            variants[label][(p, fz)] = summary(wk.assembly.without_tyre_fields(scenario), tyres=pair)

    spread = {}
    for criterion in VALUES:
        print(f"## {criterion}: {CRITERIA[criterion].text}\n")
        print("| rear load | " + " | ".join(f"{p:g} kPa [s]" for p in PRESSURES) + " | best | margin [s] |")
        print("|---|" + "---|" * (len(PRESSURES) + 2))
        margins = {}
        for fz in LOADS:
            vals = np.array([value(base[(p, fz)], criterion) for p in PRESSURES])
            order = np.argsort(np.where(np.isfinite(vals), vals, np.inf))
            ok = [i for i in order if np.isfinite(vals[i])]
            margin = vals[ok[1]] - vals[ok[0]] if len(ok) > 1 else math.nan
            margins[fz] = margin
            cells = " | ".join("-" if not np.isfinite(v) else f"{v:.3f}" for v in vals)
            print(f"| {fz:g} N | {cells} | {PRESSURES[ok[0]]:g} kPa | {margin:.3f} |")
        print("\n| change | largest change of the value over the nine cases [s] | case |\n|---|---|---|")
        worst_all = 0.0
        for label, runs in variants.items():
            changes = {key: abs(value(runs[key], criterion) - value(base[key], criterion)) for key in base}
            finite = {k: v for k, v in changes.items() if np.isfinite(v)}
            lost = [k for k, v in changes.items() if not np.isfinite(v) and np.isfinite(value(base[k], criterion))]
            key = max(finite, key=finite.get)
            worst_all = max(worst_all, finite[key])
            note = f"; no value any more in {len(lost)} case(s)" if lost else ""
            print(f"| {label} | {finite[key]:.3f} | {key[0]:g} kPa, {key[1]:g} N{note} |")
        spread[criterion] = worst_all
        print(f"\nspread ({criterion}): {worst_all:.3f} s; loads whose margin is below it: "
              + (", ".join(f"{fz:g} N" for fz, m in margins.items() if not m >= worst_all) or "none") + "\n")
    print("wk.recommend.CRITERION_SPREAD_S = {" + ", ".join(f'"{k}": {v:.3f}' for k, v in spread.items()) + "}")
    return spread


def main():
    measure()
    return 0


if __name__ == "__main__":
    sys.exit(main())
