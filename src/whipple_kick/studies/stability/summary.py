"""The summary of a sweep: weave and capsize speeds refined between samples, stable ranges, wobble."""

from typing import NamedTuple

import numpy as np
from scipy.optimize import brentq

from whipple_kick.errors import InputError

from ._constants import GROUPS, MODE_DESCRIPTIONS, MODES, WOBBLE_MIN_FREQUENCY_HZ
from .modes import _segments, match_cost

# ------------------------------------------------------------------ the summary

#: Equal steps between two sweep speeds in which a weave pair's split is first looked for (then
#: bisection): a split and a merge of another pair in the same interval are told apart.
SPLIT_SCAN = 16

def _root(fun, a, b):
    """Root of ``fun`` in [a, b] by Brent's method (to 1e-9 m/s): ``(speed, None)``, or ``(None, reason)``.

    The sweep's samples say a sign changes between ``a`` and ``b``; the fresh
    linearisations at the ends may disagree (a mode matched to another
    eigenvalue, a steady motion continued to another branch). Then there is
    no bracket and no root is claimed: an estimate outside [a, b] would be a
    number without meaning. Nor where a speed tried has no near-upright
    steady motion (:class:`_NoLinearisation`).
    """
    try:
        fa, fb = fun(a), fun(b)
        if fa == 0.0:
            return a, None
        if fb == 0.0:
            return b, None
        if not (np.isfinite(fa) and np.isfinite(fb)) or fa * fb > 0:
            return None, (f"the real part does not change sign between {a:g} and {b:g} m/s on fresh "
                          f"linearisations ({fa:+.3g} and {fb:+.3g} 1/s), although the sweep's samples do")
        return float(brentq(fun, a, b, xtol=1e-9, rtol=1e-12)), None
    except _NoLinearisation as exc:   # a speed between the samples without a near-upright steady motion
        return None, str(exc)


class _NoLinearisation(Exception):
    """A speed between two sweep samples has no near-upright steady motion to linearise about
    (:func:`whipple_kick.simulate.steady.find_steady_state` refuses a start that is not near-upright)."""


class _Split(NamedTuple):
    """Where a pair turns real between two sweep speeds, on fresh linearisations (:meth:`_Sweep.split`)."""

    speed: float
    #: Re of the double eigenvalue there [1/s].
    real: float
    #: The pair's eigenvalue (Im > 0) within 1e-9 m/s on the complex side, and the larger of the two real
    #: eigenvalues on the real side: (speed, eigenvalue, angle-like vector, index of the nearer sweep speed).
    complex_side: tuple
    real_side: tuple


class _Sweep:
    """One model and loop of a sweep: eigenvalues, tracks and names per speed, with refinement."""

    def __init__(self, table, speeds, raw, eigen_at):
        self.table, self.speeds, self._eigen_at = table, speeds, eigen_at
        self.lams, self.vecs, self.ids = raw
        # mode name of (speed index, track)
        self.name = {(int(r.speed_index), int(r.track)): r.mode for r in table.itertuples()}
        self._splits = {}   # (speed index, the pair's tracks) -> split() of that pair

    def present(self, k):
        return self.lams[k] is not None

    def eigen_at(self, v, k):
        """Eigenvalues and angle-like vectors of a fresh linearisation at ``v`` [m/s] (continued from sample k).

        Raises _NoLinearisation where there is no near-upright steady motion at ``v``: the refinement then
        gives no speed, with the reason, instead of one found on another branch.
        """
        try:
            return self._eigen_at(v, k)
        except InputError as exc:    # NoSteadyMotion, or no rider design at that speed
            raise _NoLinearisation(f"{str(exc).split(':', maxsplit=1)[0]} between the sweep's samples "
                                   f"{self.speeds[max(k - 1, 0)]:g}-{self.speeds[min(k + 1, len(self.speeds) - 1)]:g} "
                                   "m/s; refine the speed grid there") from None

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

    def follow(self, start, end, real=None):
        """Re of the eigenvalue continuing from ``start`` to ``end``, as a function of speed.

        ``start`` and ``end`` are ``(speed, eigenvalue, angle-like vector,
        index of a sweep speed near it)``. At a speed between them the fresh
        linearisation's eigenvalue of least :func:`match_cost` to the
        eigenvalue interpolated between the ends, with the nearer end's
        vector, is taken; ``real`` (True or False) keeps only real or only
        complex eigenvalues (a pair before it splits, a real root after).
        """
        (v0, l0, x0, k0), (v1, l1, x1, k1) = start, end

        def real_part(v):
            if v == v0:
                return float(l0.real)
            if v == v1:
                return float(l1.real)
            s = (v - v0) / (v1 - v0)
            ref_lam = np.array([(1 - s) * l0 + s * l1])
            ref_vec = np.asarray(x0 if s < 0.5 else x1).reshape(-1, 1)
            lam, vec = self.eigen_at(v, k0 if s < 0.5 else k1)
            if real is not None and np.any(keep := (lam.imag == 0.0) == real):
                lam, vec = lam[keep], vec[:, keep]
            return float(lam[np.argmin(match_cost(ref_lam, ref_vec, lam, vec)[0])].real)
        return real_part

    def tracked_real_part(self, k, track_id):
        """Re of the eigenvalue continuing ``track_id`` from speed index k to k+1, as a function of speed."""
        j0 = int(np.nonzero(self.ids[k] == track_id)[0][0])
        j1 = int(np.nonzero(self.ids[k + 1] == track_id)[0][0])
        return self.follow((self.speeds[k], self.lams[k][j0], self.vecs[k][:, j0], k),
                           (self.speeds[k + 1], self.lams[k + 1][j1], self.vecs[k + 1][:, j1], k + 1))

    def largest_real_part(self, v, k):
        lam, _ = self.eigen_at(v, k)
        return float(np.max(lam.real))

    def split(self, k, track_id):
        """Where the pair of ``track_id``, complex at speed index k and real at k+1, turns real: ``(_Split, None)`` or ``(None, reason)``.

        Located on fresh linearisations by the number of complex eigenvalues
        within a disc about the pair (twice the largest modulus of the pair
        and of its tracks' eigenvalues at k+1, plus 1 1/s): the first of
        :data:`SPLIT_SCAN` equal steps from speed k where it drops by two
        (another pair may merge in the same interval, before or after), then
        bisection to 1e-9 m/s. Neither the tracker's pairing of the roots nor an
        interpolation of samples enters, so the speed does not depend on the
        grid. The pair's real part at the split (the double root) says
        whether it splits stable or unstable.
        """
        a, b = self.eigenvalue(k, track_id), self.eigenvalue(k + 1, track_id)
        if a is None or b is None or a.imag == 0.0 or b.imag != 0.0:
            return None, (f"the eigenvalue does not turn from complex to real between {self.speeds[k]:g} and "
                          f"{self.speeds[k + 1]:g} m/s")
        tracks = frozenset(int(t) for l, t in zip(self.lams[k], self.ids[k], strict=True)
                           if complex(l) in (a, a.conjugate()))
        if (k, tracks) not in self._splits:
            moduli = [abs(a)] + [abs(self.eigenvalue(k + 1, t) or 0.0) for t in tracks]
            try:
                self._splits[k, tracks] = self._locate_split(k, 2 * max(moduli) + 1.0)
            except _NoLinearisation as exc:
                self._splits[k, tracks] = None, str(exc)
        return self._splits[k, tracks]

    def _locate_split(self, k, radius):
        v0, v1 = float(self.speeds[k]), float(self.speeds[k + 1])

        def at(v):
            lam, vec = self.eigen_at(v, k if v - v0 < v1 - v else k + 1)
            near = np.abs(lam) < radius
            return v, lam, vec, near, int(np.count_nonzero(near & (lam.imag != 0.0)))
        lo = at(v0)
        for v in np.linspace(v0, v1, SPLIT_SCAN + 1)[1:]:
            hi = at(float(v))
            if hi[-1] == lo[-1] - 2:
                break
            lo = hi
        else:
            return None, (f"no pair turns real between {v0:g} and {v1:g} m/s on fresh linearisations (the "
                          f"number of complex eigenvalues below {radius:.3g} 1/s never drops by two in "
                          f"{SPLIT_SCAN} steps), although the sweep's samples say so; refine the speed grid there")
        while hi[0] - lo[0] > 1e-9:
            mid = 0.5 * (lo[0] + hi[0])
            if not lo[0] < mid < hi[0]:
                break
            here = at(mid)
            if here[-1] not in (lo[-1], hi[-1]):
                return None, (f"the number of complex eigenvalues below {radius:.3g} 1/s changes by other "
                              f"than two near {mid:g} m/s on fresh linearisations; refine the speed grid there")
            lo, hi = (here, hi) if here[-1] == lo[-1] else (lo, here)
        (vc, lam_c, vec_c, near_c, _), (vr, lam_r, vec_r, near_r, _) = lo, hi
        # complex side: the pair is the complex eigenvalue (Im > 0) in the disc nearest the real axis
        cands = np.nonzero(near_c & (lam_c.imag > 0))[0]
        jc = int(cands[np.argmin(lam_c.imag[cands])])
        double = float(lam_c[jc].real)
        # real side: of the two real eigenvalues in the disc nearest the double root, the larger
        cands = np.nonzero(near_r & (lam_r.imag == 0.0))[0]
        two = cands[np.argsort(np.abs(lam_r[cands].real - double))[:2]]
        jr = int(two[np.argmax(lam_r[two].real)])
        return _Split(0.5 * (vc + vr), double, (vc, complex(lam_c[jc]), vec_c[:, jc], k if vc - v0 < v1 - vc else k + 1),
                      (vr, complex(lam_r[jr]), vec_r[:, jr], k if vr - v0 < v1 - vr else k + 1)), None


def _unstable(values):
    return any(l.real > 0 for l, _ in values)


def _weave_speed(sweep):
    """Lowest speed [m/s] above which the weave is stable, and how it stabilises (or None, reason).

    A weave eigenvalue's real part crossing zero is located by Brent's
    method on fresh linearisations (:meth:`_Sweep.tracked_real_part`). Where
    the weave pair splits into two real eigenvalues between two sweep
    speeds, the split is located on fresh linearisations too
    (:meth:`_Sweep.split`): if the pair's real part crosses zero before it
    splits, the weave speed is that crossing (whatever the real eigenvalues
    do after); a pair that splits while unstable stops being an oscillatory
    instability at the split.
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
            if sweep.name[k + 1, t] == "weave" and nxt.imag != 0.0:
                crossing, why = _root(sweep.tracked_real_part(k, t), sweep.speeds[k], sweep.speeds[k + 1])
                return (crossing, "the weave's real part crosses zero") if why is None else (None, why)
            # The pair split between the two speeds (two real eigenvalues near where it went).
            pair = [complex(l) for l in sweep.lams[k + 1] if l.imag == 0.0 and abs(l - nxt) < 4 * abs(lam.imag)]
            if not pair:
                return None, (f"the weave pair stops being the weave between {sweep.speeds[k]:g} and "
                              f"{sweep.speeds[k + 1]:g} m/s without turning into two real eigenvalues "
                              f"near it (it continues as {nxt.real:+.3g}{nxt.imag:+.3g}j 1/s, "
                              f"{sweep.name[k + 1, t]}); refine the speed grid there")
            split, why = sweep.split(k, t)
            if split is None:
                return None, why
            if split.real > 0:
                return split.speed, "the weave pair splits into two real eigenvalues while unstable"
            j = int(np.nonzero(sweep.ids[k] == t)[0][0])
            start = (sweep.speeds[k], lam, sweep.vecs[k][:, j], k)
            crossing, why = _root(sweep.follow(start, split.complex_side, real=False),
                                  sweep.speeds[k], split.complex_side[0])
            if why is not None:
                return None, why
            return crossing, "the weave's real part crosses zero before the pair splits"
    return None, "the weave is unstable up to the end of the sweep"


def _capsize_speed(sweep, above=None):
    """Lowest speed [m/s] (from ``above`` up) where a capsize eigenvalue becomes unstable, and how (or None).

    Within a capsize branch the zero crossing is located by Brent's method.
    A capsize branch born from a pair that splits between two sweep speeds
    (located on fresh linearisations, :meth:`_Sweep.split`) is born unstable
    at the split if the pair splits unstable; else it becomes unstable where
    the continuation of the larger of the two real eigenvalues crosses zero
    after the split (Brent's method on fresh linearisations).
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
            if before.imag != 0.0:
                split, why = sweep.split(k, t)
                if split is not None and split.real > 0:
                    found.append((split.speed, "the capsize eigenvalue is born unstable where the weave pair splits"))
                    continue
                if split is not None:
                    j = int(np.nonzero(sweep.ids[k + 1] == t)[0][0])
                    end = (sweep.speeds[k + 1], lam, sweep.vecs[k + 1][:, j], k + 1)
                    crossing, why = _root(sweep.follow(split.real_side, end, real=True),
                                          split.real_side[0], sweep.speeds[k + 1])
                if why is not None:
                    unlocated.append(why)
                    continue
                found.append((crossing, "the capsize eigenvalue crosses zero just after the weave pair splits"))
            elif before.real <= 0:
                crossing, why = _root(sweep.tracked_real_part(k, t), sweep.speeds[k], sweep.speeds[k + 1])
                if why is not None:
                    unlocated.append(why)
                    continue
                found.append((crossing, "the capsize eigenvalue crosses zero" + (
                    "" if sweep.name[k, t] == "capsize" else " (named capsize from there on)")))
            elif sweep.name[k, t] != "capsize":
                found.append((0.5 * (sweep.speeds[k] + sweep.speeds[k + 1]),
                              "an unstable real eigenvalue is named capsize from here on (between two sweep speeds)"))
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
