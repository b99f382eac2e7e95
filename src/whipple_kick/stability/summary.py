"""The summary of a sweep: weave and capsize speeds refined between samples, stable ranges, wobble."""

import numpy as np

from ._constants import GROUPS, MODE_DESCRIPTIONS, MODES, WOBBLE_MIN_FREQUENCY_HZ
from .modes import _segments, match_cost

# ------------------------------------------------------------------ the summary

def _root(fun, a, b):
    """Root of ``fun`` in [a, b] by Brent's method (to 1e-9 m/s): ``(speed, None)``, or ``(None, reason)``.

    The sweep's samples say a sign changes between ``a`` and ``b``; the fresh
    linearisations at the ends may disagree (a mode matched to another
    eigenvalue, a steady motion continued to another branch). Then there is
    no bracket and no root is claimed: an estimate outside [a, b] would be a
    number without meaning.
    """
    from scipy.optimize import brentq
    fa, fb = fun(a), fun(b)
    if fa == 0.0:
        return a, None
    if fb == 0.0:
        return b, None
    if not (np.isfinite(fa) and np.isfinite(fb)) or fa * fb > 0:
        return None, (f"the real part does not change sign between {a:g} and {b:g} m/s on fresh "
                      f"linearisations ({fa:+.3g} and {fb:+.3g} 1/s), although the sweep's samples do")
    return float(brentq(fun, a, b, xtol=1e-9, rtol=1e-12)), None


class _Sweep:
    """One model and loop of a sweep: eigenvalues, tracks and names per speed, with refinement."""

    def __init__(self, table, speeds, raw, eigen_at):
        self.table, self.speeds, self.eigen_at = table, speeds, eigen_at
        self.lams, self.vecs, self.ids = raw
        # mode name of (speed index, track)
        self.name = {(int(r.speed_index), int(r.track)): r.mode for r in table.itertuples()}

    def present(self, k):
        return self.lams[k] is not None

    def values(self, k, mode):
        """Eigenvalues named ``mode`` at speed index ``k`` (with their tracks)."""
        if not self.present(k):
            return []
        return [(complex(l), int(t)) for l, t in zip(self.lams[k], self.ids[k], strict=True) if self.name[k, int(t)] == mode]

    def eigenvalue(self, k, track_id):
        if not self.present(k):
            return None
        hit = np.nonzero(self.ids[k] == track_id)[0]
        return complex(self.lams[k][hit[0]]) if hit.size else None

    def tracked_real_part(self, k, track_id):
        """Re of the eigenvalue continuing ``track_id`` from speed index k to k+1, as a function of speed."""
        j0 = int(np.nonzero(self.ids[k] == track_id)[0][0])
        j1 = int(np.nonzero(self.ids[k + 1] == track_id)[0][0])
        l0, l1 = self.lams[k][j0], self.lams[k + 1][j1]
        v0, v1 = self.speeds[k], self.speeds[k + 1]

        def real_part(v):
            if v == v0:
                return float(l0.real)
            if v == v1:
                return float(l1.real)
            s = (v - v0) / (v1 - v0)
            ref_lam = np.array([(1 - s) * l0 + s * l1])
            ref_vec = (self.vecs[k][:, [j0]] if s < 0.5 else self.vecs[k + 1][:, [j1]])
            lam, vec = self.eigen_at(v, k if s < 0.5 else k + 1)
            return float(lam[np.argmin(match_cost(ref_lam, ref_vec, lam, vec)[0])].real)
        return real_part

    def largest_real_part(self, v, k):
        lam, _ = self.eigen_at(v, k)
        return float(np.max(lam.real))

    def split_speed(self, k, track_id):
        """Where a pair turns real (or two reals merge) between speed indices k and k+1.

        Near such a point the discriminant is linear in speed: the squared
        imaginary part on the complex side and the squared half-distance of
        the two real eigenvalues on the other vanish at the same speed.
        """
        v0, v1 = self.speeds[k], self.speeds[k + 1]
        a, b = self.eigenvalue(k, track_id), self.eigenvalue(k + 1, track_id)
        if a is None or b is None:
            return 0.5 * (v0 + v1)
        side_complex, side_real, k_real = (a, b, k + 1) if a.imag != 0 else (b, a, k)
        partner = [complex(l) for l in self.lams[k_real] if l.imag == 0.0 and complex(l) != side_real]
        if side_complex.imag == 0 or not partner:
            return 0.5 * (v0 + v1)
        other = min(partner, key=lambda l: abs(l - side_real))
        im2, gap2 = side_complex.imag ** 2, ((side_real.real - other.real) / 2) ** 2
        frac = im2 / (im2 + gap2)
        return float(v0 + (v1 - v0) * (frac if a.imag != 0 else 1 - frac))


def _unstable(values):
    return any(l.real > 0 for l, _ in values)


def _weave_speed(sweep):
    """Lowest speed [m/s] above which the weave is stable, and how it stabilises (or None, reason).

    A weave eigenvalue's real part crossing zero is located by Brent's
    method on fresh linearisations (:meth:`_Sweep.tracked_real_part`); a
    weave pair that stops being a pair while unstable (splits into two real
    eigenvalues, one of them unstable) stops being an oscillatory
    instability there, located by the discriminant (:meth:`_Sweep.split_speed`).
    """
    n = len(sweep.speeds)
    unstable = [_unstable(sweep.values(k, "weave")) for k in range(n)]
    if not any(unstable):
        return None, "the weave is stable (or absent) at every speed of the sweep"
    for k in range(n - 1):
        if not (unstable[k] and not unstable[k + 1]) or not (sweep.present(k) and sweep.present(k + 1)):
            continue
        for lam, t in sweep.values(k, "weave"):
            nxt = sweep.eigenvalue(k + 1, t)
            if lam.real <= 0 or nxt is None:
                continue
            crossing, why = _root(sweep.tracked_real_part(k, t), sweep.speeds[k], sweep.speeds[k + 1])
            if sweep.name[k + 1, t] == "weave" and nxt.imag != 0.0:
                return (crossing, "the weave's real part crosses zero") if why is None else (None, why)
            # The pair split between the two speeds: still unstable then if a root stays positive.
            pair = [complex(l) for l in sweep.lams[k + 1] if l.imag == 0.0 and abs(l - nxt) < 4 * abs(lam.imag)]
            if not pair:
                return None, (f"the weave pair stops being the weave between {sweep.speeds[k]:g} and "
                              f"{sweep.speeds[k + 1]:g} m/s without turning into two real eigenvalues "
                              f"near it (it continues as {nxt.real:+.3g}{nxt.imag:+.3g}j 1/s, "
                              f"{sweep.name[k + 1, t]}); refine the speed grid there")
            if max(l.real for l in pair) > 0:
                return sweep.split_speed(k, t), ("the weave pair splits into two real eigenvalues while "
                                                 "unstable (one stays unstable)")
            if why is not None:
                return None, why
            return crossing, "the weave's real part crosses zero just before the pair splits"
    return None, "the weave is unstable up to the end of the sweep"


def _capsize_speed(sweep, above=None):
    """Lowest speed [m/s] (from ``above`` up) where a capsize eigenvalue becomes unstable, and how (or None).

    Within a capsize branch the zero crossing is located by Brent's method;
    a capsize branch that is born unstable (from a weave pair that splits)
    becomes unstable at the crossing of its continuation if that lies after
    the split, else at the split.
    """
    n = len(sweep.speeds)
    found, unlocated = [], []
    for k in range(n - 1):
        if not (sweep.present(k) and sweep.present(k + 1)):
            continue
        for lam, t in sweep.values(k + 1, "capsize"):
            before = sweep.eigenvalue(k, t)
            if lam.real <= 0 or before is None:
                continue
            same_branch = sweep.name[k, t] == "capsize" and before.imag == 0.0
            if before.real <= 0:
                crossing, why = _root(sweep.tracked_real_part(k, t), sweep.speeds[k], sweep.speeds[k + 1])
                if why is not None:
                    unlocated.append(why)
                    continue
                found.append((crossing, "the capsize eigenvalue crosses zero" + ("" if same_branch else
                                                                                   " just after the weave pair splits")))
            elif not same_branch:
                found.append((sweep.split_speed(k, t), "the capsize eigenvalue is born unstable where the "
                                                       "weave pair splits"))
    found = [f for f in found if above is None or f[0] >= above - 1e-9]
    if not found:
        return None, unlocated[0] if unlocated else "no capsize eigenvalue becomes unstable within the sweep"
    return min(found)


def _stable_ranges(sweep):
    """Speed intervals [m/s] where every eigenvalue has a negative real part.

    Boundaries between sweep speeds are located by Brent's method on the
    largest real part (continuous in speed); an interval touching the end
    of the sweep is marked open there (``"lower_open"``/``"upper_open"``).
    """
    n = len(sweep.speeds)
    stable = [sweep.present(k) and float(np.max(sweep.lams[k].real)) < 0 for k in range(n)]
    ranges = []
    for start, stop in _segments(stable):
        if not stable[start]:
            continue
        lo, hi, notes = sweep.speeds[start], sweep.speeds[stop - 1], []
        # A boundary that cannot be located stays at the last stable sweep speed, and says so.
        if start > 0 and sweep.present(start - 1):
            root, why = _root(lambda v, k=start: sweep.largest_real_part(v, k), sweep.speeds[start - 1], lo)
            lo = lo if why is not None else root
            notes += [f"lower end not located, the sweep speed is given: {why}"] if why is not None else []
        if stop < n and sweep.present(stop):
            root, why = _root(lambda v, k=stop - 1: sweep.largest_real_part(v, k), hi, sweep.speeds[stop])
            hi = hi if why is not None else root
            notes += [f"upper end not located, the sweep speed is given: {why}"] if why is not None else []
        ranges.append({"from_m_s": float(lo), "to_m_s": float(hi), "lower_open": start == 0,
                       "upper_open": stop == n, **({"note": "; ".join(notes)} if notes else {})})
    return ranges


def _mode_ranges(table):
    """Per mode: speeds where it exists, the largest real part and the frequency range."""
    out = {}
    for mode, g in table.groupby("mode", sort=False):
        worst = g.loc[g["real_1_s"].idxmax()]
        out[mode] = {"speeds_m_s": [float(g["speed_m_s"].min()), float(g["speed_m_s"].max())],
                     "largest_real_part_1_s": float(worst["real_1_s"]),
                     "at_speed_m_s": float(worst["speed_m_s"]),
                     "frequency_hz": [float(g["frequency_hz"].min()), float(g["frequency_hz"].max())]}
    return {m: out[m] for m in MODES if m in out}


def _wobble_summary(table):
    """The wobble of one loop: where it exists, its frequency and damping, the least damped point (or None)."""
    w = table[(table["mode"] == "wobble") & (table["imag_1_s"] > 0)]
    if w.empty:
        fast = table[(table["frequency_hz"] >= WOBBLE_MIN_FREQUENCY_HZ) & (table["imag_1_s"] > 0)]
        return {"exists": False,
                "fast_oscillations": {m: {"frequency_hz": [float(g["frequency_hz"].min()), float(g["frequency_hz"].max())],
                                          "largest_steer_share": float(g["share_steer"].max())}
                                      for m, g in fast.groupby("mode")}}
    least = w.loc[w["damping_ratio"].idxmin()]
    return {"exists": True,
            "speeds_m_s": [float(w["speed_m_s"].min()), float(w["speed_m_s"].max())],
            "frequency_hz": [float(w["frequency_hz"].min()), float(w["frequency_hz"].max())],
            "damping_ratio": [float(w["damping_ratio"].min()), float(w["damping_ratio"].max())],
            "least_damped": {"speed_m_s": float(least["speed_m_s"]), "frequency_hz": float(least["frequency_hz"]),
                             "damping_ratio": float(least["damping_ratio"]), "real_1_s": float(least["real_1_s"])},
            "unstable": bool((w["real_1_s"] > 0).any()),
            "mean_shares": {g: float(w[f"share_{g}"].mean()) for g in GROUPS}}


def _loop_summary(table, sweep):
    weave, weave_how = _weave_speed(sweep)
    capsize, capsize_how = _capsize_speed(sweep, above=weave)
    return {"weave_speed_m_s": weave, "weave_speed_how": weave_how,
            "capsize_speed_m_s": capsize, "capsize_speed_how": capsize_how,
            "stable_speed_ranges": _stable_ranges(sweep),
            "wobble": _wobble_summary(table) if "share_front_tyre" in table else None,
            "modes": _mode_ranges(table)}


def _summarise(result, raw, refiners):
    """The summary of :class:`Stability` (JSON-ready): see :func:`analyse`."""
    df, speeds = result.eigenvalues, result.speeds
    out = {"speeds_m_s": {"from": float(speeds[0]), "to": float(speeds[-1]), "count": int(speeds.size)},
           "constant_speed": True, "mode_descriptions": {m: MODE_DESCRIPTIONS[m] for m in MODES},
           "wobble_min_frequency_hz": WOBBLE_MIN_FREQUENCY_HZ}
    for model_name in ("slip", "no-slip"):
        block = {}
        for (name, loop), data in raw.items():
            if name != model_name:
                continue
            table = df[(df["model"] == name) & (df["loop"] == loop)]
            sweep = _Sweep(table, speeds, data, refiners[name, loop])
            block[loop] = _loop_summary(table, sweep)
            if name == "no-slip":
                block[loop].pop("wobble")
        out[model_name] = block
    steady = result.steady
    out["steady_motion"] = {}
    for loop, g in steady.groupby("loop"):
        found = g[g["found_by"].notna()]
        missing = g[g["found_by"].isna()]
        out["steady_motion"][loop] = {
            "largest_lean_rad": float(found["roll_rad"].abs().max()) if len(found) else None,
            "speeds_without_steady_motion": int(len(missing)),
            "first_reason": None if missing.empty else str(missing["message"].iloc[0])}
    return out
