"""The carcass tyre: a lateral carcass spring in series with a contact patch that slides on the steady curve.

The default tyre transient (``tyre_transient="carcass"``). Per wheel, the
state is the lateral deflection ``y`` [m] of the carcass between the rim and
the contact patch, with a constant stiffness ``c = C_Fa(F_z0) / sigma0``
(the cornering stiffness at the wheel's load in the run's steady motion,
over the relaxation length) and an optional parallel damper ``d``; and the
patch's lagged camber ``g'`` (for the aligning moment). Model convention
(:mod:`whipple_kick.model.magic_formula`): ``F_ss(slip, camber, F_z)`` is the
steady lateral force, falling with the slip on its rising branch.

Force and patch slip (``d = 0``)::

    F = c y,   F_ss(a', camber, F_z) = F  (a' on the rising branch),
    dy/dt = |v_x| tan(a') - v_sy          (the patch slides at |v_x| tan a')

so a steady slide has ``a'`` = the kinematic slip and ``F = F_ss``, and
linearised about zero slip ``(sigma0/|v_x|) dF/dt + F = F_ss``: the thesis'
force lag. The carcass energy is ``c y^2 / 2`` exactly (``c`` is constant),
so the tyre stores only what was done on it, whatever the load does: it
cannot create energy. With a damper ``d > 0`` the patch force balances spring
and damper, ``F_ss(a') = c y + d dy/dt``, solved for ``a'`` with the same
monotone root finder.

Friction limit: ``|F|`` never exceeds the steady curve's extreme on its side,
at the current load and camber, within ``|a'| <= PATCH_SLIP_CAP_DEG``. When
``c y`` reaches it the patch slides faster than the peak slip and the force
stays on the limit: ``carcass_sliding="peak"`` (default) holds it at the
peak (a Coulomb plateau, nothing of the fit past the peak used);
``"curve"`` lets it follow the steady curve at the wheel's kinematic slip
past the peak (steady sliding reproduces the fit's falling branch). Without
a damper the limit is a regularised Coulomb plateau: past it the patch
slides faster than at the limit's own slip on the rising branch ``a_b`` by
the excess force over a small viscosity,
``dy/dt = |v_x| tan(a_b) - v_sy + (F_lim - c y) / SLIDING_VISCOSITY``:
continuous where the patch reaches the limit, passive (it only adds
sliding), stiff, and converged (docs/validation.md). (An exact projection,
the deflection following the limit's own rate while on it, is a Coulomb
sticking mode with rates that jump at the limit; LSODA stalled on it.)
With a damper the patch force is the limit and ``dy/dt = (F_lim - c y) / d``.
A lifted wheel, or a fit whose peak factor D is not positive at the load,
has no grip: its patch slides with the wheel and the force relaxes through
the viscosity alone.

Aligning moment: ``M_z = M_ss(a_M, g', F_z)`` with ``sigma0 dg'/dt = |v_x|
(camber - g')`` and ``a_M`` the patch slip that gives the force ``F`` at the
lagged camber (``F_ss(a_M, g', F_z) = F``). Linearised this is the force
lag of the moment as well, so with symmetric tyres every eigenvalue equals
the force lag's; a steady slide has ``g'`` = camber, ``a_M = a'``.

Sliding dissipation ``-(F - F0) V'`` with ``V' = v_sy + dy/dt`` (the patch's
sliding velocity) and ``F0 = F_ss(0, camber, F_z)``, carcass storage rate
``c y dy/dt``, damper dissipation ``d (dy/dt)^2``: the energy accounting of
:mod:`whipple_kick.model.energy` closes exactly.

This module holds the constants, the C source of the block (printed by
:mod:`whipple_kick.model.symbolic.slip_build`; the curve, its factors and gradients are
generated from the SymPy Magic Formula, the inverse and the limit search are
written here) and :func:`reference_block`, an independent Python
computation of the same block (bracketed root finding on the NumPy curves)
that the tests compare the C code with.
"""
import math

import numpy as np
from scipy.optimize import brentq

from whipple_kick.errors import InputError

#: Largest patch slip [deg] of the rising branch. Beyond it the steady curve's
#: extreme is taken at the cap: T03's 500 kPa fit (C = 1.024) has no peak
#: below 90 deg, and a patch slip near 90 deg would slide at ``|v_x|`` tan(a'),
#: without bound. At 80 deg that is 5.7 ``|v_x|``; the limit of T03 at 500 kPa,
#: 635 N, is then within 0.1 % of the curve's value at 89.9 deg (docs/tyres.md).
PATCH_SLIP_CAP_DEG = 80.0
#: Sliding viscosity [N s/m] past the friction limit (undamped carcass): a
#: patch whose carcass force exceeds the limit by dF slides dF / viscosity
#: faster than at the limit. It regularises the Coulomb plateau (a sliding
#: patch carries its limit plus viscosity x the extra sliding speed: 0.01 N
#: at 2 m/s, 2e-5 of a 500 N limit; 6e-5 in the 40 m/s^2 kick) and keeps the
#: rates continuous where the patch reaches the limit; converged: a tenth of
#: it moves the kick's metrics by < 1e-4 (docs/validation.md).
SLIDING_VISCOSITY = 0.005
#: Sliding laws beyond the peak, by name; the compiled model's ``carcass_sliding`` is the index.
SLIDING_LAWS = ("peak", "curve")
DEFAULT_SLIDING = "peak"
#: Normal load [N] below which the curve's shape (peak slip, inverse) is
#: taken at this load: the Magic-Formula factors are 0/0 at zero load. The
#: forces themselves use the true load (zero unloaded).
FZ_SHAPE_FLOOR = 1.0


def check_sliding(name):
    """Index of the sliding law ``name``; ``InputError`` naming the choices otherwise."""
    if name not in SLIDING_LAWS:
        raise InputError(f"carcass sliding law {name!r} is unknown; choose one of {', '.join(SLIDING_LAWS)}")
    return SLIDING_LAWS.index(name)


# ----------------------------------------------------------------------------- C

_C_GENERIC = r"""
/* ---- carcass tyre: generic helpers (whipple_kick.model.carcass) ---- */
#define WK_CAP_DEG %(cap).17g
#define WK_DEG (180.0 / M_PI)
/* f: B C D E Sh Sv of each set; up: each set's inner value at its peak, which depends on C and E
   only (not on the camber), computed once per evaluation and shared by the curves at both cambers. */
typedef struct { double f1[6], f2[6], w, lam, up[2]; int two; } wk_curve;

/* u with (1 - E) u + E atan(u) = t on the rising part (|u| <= umax): safeguarded Newton. */
static double wk_inner_inverse(double t, double E, double umax)
{
    double s = t < 0.0 ? -1.0 : 1.0, target = fabs(t), lo = 0.0, hi = umax, u;
    /* exact for small u (inner ~ u) and for large u (atan ~ pi/2) when E < 1 */
    u = E < 0.95 ? (target - E * atan(target)) / (1.0 - E) : target;
    if (u > hi) u = isfinite(hi) ? 0.5 * hi : target;
    for (int i = 0; i < 60; i++) {
        double g = (1.0 - E) * u + E * atan(u) - target;
        if (g > 0.0) hi = u; else lo = u;
        double dg = (1.0 - E) + E / (1.0 + u * u);
        double next = u - g / dg;
        if (!(next > lo && next < hi) || !isfinite(next)) next = isfinite(hi) ? 0.5 * (lo + hi) : 2.0 * u + 1.0;
        if (fabs(next - u) <= 1e-15 * (1.0 + fabs(u))) { u = next; break; }
        u = next;
    }
    return s * u;
}

/* Rising branch of one coefficient set in the patch slip alpha [deg]: [lo, hi]; *up caches the inner
   value at the peak (NAN: not computed yet). */
static void wk_set_branch(const double *f, double *up_cache, double *lo, double *hi)
{
    const double B = f[0], C = f[1], E = f[3], Sh = f[4];
    double up = *up_cache;
    if (isnan(up)) {
        double umax = INFINITY;
        up = INFINITY;
        if (E > 1.0) umax = 1.0 / sqrt(E - 1.0);           /* the inner function's maximum */
        if (C > 1.0) up = wk_inner_inverse(tan(M_PI / (2.0 * C)), E, umax);
        if (up > umax) up = umax;
        *up_cache = up;
    }
    double xp = B > 0.0 ? up / B : INFINITY;
    *hi = fmin(xp - Sh, WK_CAP_DEG);
    *lo = fmax(-xp - Sh, -WK_CAP_DEG);
}

static double wk_curve_F(const wk_curve *c, double a_deg)
{
    double v = (1.0 - c->w) * wk_mf_y(a_deg, c->f1);
    if (c->two) v += c->w * wk_mf_y(a_deg, c->f2);
    return -c->lam * v;
}

static double wk_curve_dF(const wk_curve *c, double a_deg)   /* dF/dalpha per degree */
{
    double v = (1.0 - c->w) * wk_mf_dy(a_deg, c->f1);
    if (c->two) v += c->w * wk_mf_dy(a_deg, c->f2);
    return -c->lam * v;
}

static void wk_curve_FdF(const wk_curve *c, double a_deg, double *F, double *dF)   /* both, sharing terms */
{
    double y, dy, y2, dy2;
    wk_mf_ydy(a_deg, c->f1, &y, &dy);
    y *= 1.0 - c->w; dy *= 1.0 - c->w;
    if (c->two) { wk_mf_ydy(a_deg, c->f2, &y2, &dy2); y += c->w * y2; dy += c->w * dy2; }
    *F = -c->lam * y; *dF = -c->lam * dy;
}

/* The friction limit on the side of F [N] of one set whose peak lies inside the cap, as wk_curve_F gives it
   at the end wk_curve_end finds, without finding the end: there C atan(inner) = +-pi/2 to round-off, whose
   sine is exactly +-1, so the curve is Sv +- D. The peak is inside when the inner function at the cap has
   passed the peak's value tan(pi/2C) (it rises with the slip for E <= 1). Returns 0 for a blend, no peak
   (C <= 1), a turning inner function (E > 1) or a peak within 1e-9 of the cap: the search decides there. */
static int wk_curve_peak(const wk_curve *c, double F, double *lim)
{
    const double B = c->f1[0], C = c->f1[1], D = c->f1[2], E = c->f1[3], Sh = c->f1[4], Sv = c->f1[5];
    if (c->two || !(C > 1.0) || !(E <= 1.0) || !(B > 0.0)) return 0;
    const double x = B * (F >= 0.0 ? WK_CAP_DEG - Sh : WK_CAP_DEG + Sh);   /* the cap on the force's side */
    if (!((1.0 - E) * x + E * atan(x) > tan(M_PI / (2.0 * C)) * (1.0 + 1e-9))) return 0;
    /* F >= 0: wk_curve_F at the lower end (sine -1); F < 0: minus it at the upper end (sine +1) */
    *lim = F >= 0.0 ? -c->lam * ((1.0 - c->w) * (Sv - D)) : c->lam * ((1.0 - c->w) * (D + Sv));
    return 1;
}

/* One end of the rising branch of the (blended) curve [deg]: side 0 where F is largest (lo), side 1 where
   it is smallest (hi). Each end is found on its own (the friction limit on a force's side needs one). */
static double wk_curve_end(wk_curve *c, int side)
{
    double l1, h1;
    wk_set_branch(c->f1, &c->up[0], &l1, &h1);
    if (!c->two) return side ? h1 : l1;
    double l2, h2;
    wk_set_branch(c->f2, &c->up[1], &l2, &h2);
    /* The blend's extreme lies between the sets' own: the root of its slope there (Illinois). */
    double a = side ? fmin(h1, h2) : fmax(l1, l2), b = side ? fmax(h1, h2) : fmin(l1, l2);
    double ga = wk_curve_dF(c, a), gb = wk_curve_dF(c, b);
    double x = b;
    if (ga * gb < 0.0) {
        for (int i = 0; i < 100; i++) {
            x = b - gb * (b - a) / (gb - ga);
            const double g = wk_curve_dF(c, x);
            if (g == 0.0 || fabs(x - b) <= 1e-11 * (1.0 + fabs(x))) break;
            if ((g < 0.0) != (gb < 0.0)) { a = b; ga = gb; } else ga *= 0.5;
            b = x; gb = g;
        }
    } else if (fabs(ga) < fabs(gb)) x = a;
    return x;
}

/* Rising branch of the (blended) curve: [lo, hi] deg, F(lo) the largest, F(hi) the smallest force. */
static void wk_curve_branch(wk_curve *c, double *lo, double *hi)
{
    *lo = wk_curve_end(c, 0);
    *hi = wk_curve_end(c, 1);
}

/* alpha in [lo, hi] with F(alpha) - k tan(alpha) = target (decreasing in alpha): safeguarded Newton. */
static double wk_curve_solve(const wk_curve *c, double target, double k, double lo, double hi, double guess)
{
    double a = fmin(fmax(guess, lo), hi);
    for (int i = 0; i < 100; i++) {
        double ar = a / WK_DEG, ta = k != 0.0 ? tan(ar) : 0.0, Fa, dFa;
        wk_curve_FdF(c, a, &Fa, &dFa);
        double g = Fa - k * ta - target;
        if (g > 0.0) lo = a; else hi = a;
        double dg = dFa - k * (1.0 + ta * ta) / WK_DEG;
        double next = dg < 0.0 ? a - g / dg : 0.5 * (lo + hi);
        /* Converged (g == 0 exactly included): return before the bracket test, which would bisect away
           from a root sitting on the bracket's end (half of a blend's solves did: ~25 steps instead of 3). */
        if (dg < 0.0 && fabs(next - a) <= 1e-13 * (1.0 + fabs(a))) return next;
        if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
        if (fabs(next - a) <= 1e-13 * (1.0 + fabs(a)) || hi - lo <= 1e-13) { a = next; break; }
        a = next;
    }
    return a;
}

/* Whether the slip a [deg] lies inside the cap on the rising branch of one set with C > 1 and E <= 1, as
   wk_set_branch's ends say, without finding them: the inner function rises with the slip there, and the
   curve with it while |C atan(inner)| < pi/2. */
static int wk_set_rises(const double *f, double a)
{
    const double B = f[0], C = f[1], E = f[3], x = B * (a + f[4]);
    if (!(B > 0.0)) return fabs(a) < WK_CAP_DEG;   /* no peak: the branch is the whole cap */
    return fabs(a) < WK_CAP_DEG && fabs((1.0 - E) * x + E * atan(x)) < tan(M_PI / (2.0 * C));
}

/* Closed-form patch slip [deg] of one set for the force F (d = 0), clamped to [lo, hi]. */
static double wk_set_inverse(const double *f, double lam, double F, double lo, double hi)
{
    const double B = f[0], C = f[1], D = f[2], E = f[3], Sh = f[4], Sv = f[5];
    double s = (-F / lam - Sv) / D;
    if (s >= 1.0) return hi;
    if (s <= -1.0) return lo;
    double umax = E > 1.0 ? 1.0 / sqrt(E - 1.0) : INFINITY;
    double u = wk_inner_inverse(tan(asin(s) / C), E, umax);
    return fmin(fmax(u / B - Sh, lo), hi);
}

/* Patch slip [deg] on the rising branch [lo, hi] giving F - k tan(a) = target. */
static double wk_curve_inverse(const wk_curve *c, double target, double k, double lo, double hi)
{
    /* The closed form of the first set starts a safeguarded Newton on the whole (blended) curve;
       for one set it is the answer already and the Newton only confirms it. */
    return wk_curve_solve(c, target, k, lo, hi, wk_set_inverse(c->f1, c->lam, target, lo, hi));
}
"""

#: One wheel's block. Inputs: vsy, vx, camber, fz, y (deflection), gl (lagged
#: camber), the compiled curve functions of the wheel; outputs in ``wk_carcass_state``.
_C_WHEEL = r"""
/* The rising-branch slip [deg] giving the force F, with saturation: *sat = +1 / -1 when F is at or past
   the limit on its side (then *lim is that limit and the slip returned is where the rising branch
   reaches it), 0 inside. Fast path: one set with C > 1 and E <= 1 (every table7_9 fit) whose closed
   form lands inside the cap needs no branch search. */
static double wk_carcass_slip_%(w)s(wk_curve *c, double F, int curve_law, double vsy, double speed, double loaded,
                                   int *sat, double *lim, int search)
{
    *sat = 0; *lim = 0.0;
    if (!(loaded > 0.0) || !(c->f1[2] > 0.0) || (c->two && !(c->f2[2] > 0.0))) {
        /* A lifted wheel's patch has no grip, and neither has a fit whose peak factor
           D = a1 Fz^2 + a2 Fz has fallen to zero at this load (table7_9: from 1.6-3.2 kN): it slides
           with the wheel and the carcass force relaxes through the viscosity alone. */
        *sat = (F > 0.0) - (F < 0.0);
        return atan2(vsy, speed) * WK_DEG;   /* the kinematic slip */
    }
    if (!c->two && !curve_law && c->f1[1] > 1.0 && c->f1[3] <= 1.0 && loaded > 0.0) {
        const double *f = c->f1;
        const double s = (-F / c->lam - f[5]) / f[2];
        if (s > -1.0 && s < 1.0) {
            const double a = wk_inner_inverse(tan(asin(s) / f[1]), f[3], INFINITY) / f[0] - f[4];
            if (a > -WK_CAP_DEG && a < WK_CAP_DEG) return a;
        }
    }
    if (c->two && !curve_law && c->f1[1] > 1.0 && c->f1[3] <= 1.0 && c->f2[1] > 1.0 && c->f2[3] <= 1.0) {
        /* A pressure blend: where both sets rise, so does the blend, and its root lies between the two
           sets' own roots; only a force beyond that common part needs the blend's own extremes. Each
           set's own root (closed form, unclamped) lies on its own rising branch (|asin| < pi/2); whether
           each lies on the other's too is one evaluation of its inner function (search: by both sets'
           branch ends, the reference, with a Newton solve for each set's peak). */
        const double a1 = wk_set_inverse(c->f1, c->lam, F, -INFINITY, INFINITY);
        const double a2 = wk_set_inverse(c->f2, c->lam, F, -INFINITY, INFINITY);
        int common;
        if (search) {
            double l1, h1, l2, h2;
            wk_set_branch(c->f1, &c->up[0], &l1, &h1);
            wk_set_branch(c->f2, &c->up[1], &l2, &h2);
            const double lo_in = fmax(l1, l2), hi_in = fmin(h1, h2);
            common = lo_in < hi_in && a1 > lo_in && a1 < hi_in && a2 > lo_in && a2 < hi_in;
        } else common = fabs(a1) < WK_CAP_DEG && fabs(a2) < WK_CAP_DEG && wk_set_rises(c->f2, a1)
                        && wk_set_rises(c->f1, a2);
        /* when both lie where both sets rise, the blend's root is between them and the blend is monotone there */
        if (common) return wk_curve_solve(c, F, 0.0, fmin(a1, a2), fmax(a1, a2), (1.0 - c->w) * a1 + c->w * a2);
    }
    double lo = NAN, hi = NAN, lim_pos = NAN, lim_neg = NAN;
    int have_lo = 0, have_hi = 0;
    if (!curve_law && !search) {
        /* The sliding law "peak": a force past the branch end on its own side saturates there (the tests
           below decide the same), so that end is searched first and the other one only for a force inside,
           as the inverse's bracket (search: both ends first, the reference). A negative force counts as
           past only strictly below its end: at the end itself the test of the positive side comes first. */
        if (F >= 0.0) {
            lo = wk_curve_end(c, 0); lim_pos = wk_curve_F(c, lo); have_lo = 1;
            if (F >= lim_pos) { *sat = 1; *lim = lim_pos; return lo; }
        } else {
            hi = wk_curve_end(c, 1); lim_neg = wk_curve_F(c, hi); have_hi = 1;
            if (F < lim_neg) { *sat = -1; *lim = lim_neg; return hi; }
        }
    }
    if (!have_lo) { lo = wk_curve_end(c, 0); lim_pos = wk_curve_F(c, lo); }
    if (!have_hi) { hi = wk_curve_end(c, 1); lim_neg = wk_curve_F(c, hi); }
    double a_pos = lo, a_neg = hi;
    /* "curve": past the peak the limit is the steady curve at the kinematic slip, reached on the rising
       branch where the curve gives the same force. */
    const double kslip = curve_law ? atan2(vsy, speed) * WK_DEG : 0.0;   /* the kinematic slip [deg] */
    if (curve_law && kslip < lo) { lim_pos = fmax(0.0, wk_curve_F(c, kslip)); a_pos = wk_curve_inverse(c, lim_pos, 0.0, lo, hi); }
    if (curve_law && kslip > hi) { lim_neg = fmin(0.0, wk_curve_F(c, kslip)); a_neg = wk_curve_inverse(c, lim_neg, 0.0, lo, hi); }
    if (F >= lim_pos) { *sat = 1; *lim = lim_pos; return a_pos; }
    if (F <= lim_neg) { *sat = -1; *lim = lim_neg; return a_neg; }
    return wk_curve_inverse(c, F, 0.0, lo, hi);
}

/* need: bit 1 the zero-slip force F0 (only the quadrature rates read it), bit 2 the aligning moment (its
   solve at the lagged camber, the dearer half of the block); what is not needed is NAN. The right-hand side
   needs both; an outputs call needs no F0, and the moment only where it asks for it. */
static void wk_carcass_%(w)s(double vsy, double vx, double camber, double fz, double y, double gl,
                             const double *p, int need, wk_carcass_state *o)
{
    const double cc = p[%(cc)d], dc = p[%(dc)d], sig = p[%(sig)d];
    const int curve_law = p[%(law)d] > 0.5;
    const double speed = fabs(vx);
    /* the kinematic slip [deg], computed only where it is used (the sliding law "curve", no grip) */
#define WK_KSLIP (atan2(vsy, speed) * WK_DEG)
    const double fzs = fmax(fz, %(floor).17g);
    const double loaded = fz > 0.0 ? 1.0 : 0.0;
    wk_curve c, cl;   /* the curve at the camber and at the lagged camber */
    c.w = cl.w = p[%(wgt)d]; c.lam = cl.lam = p[%(lam)d]; c.two = cl.two = c.w != 0.0;
    c.up[0] = c.up[1] = NAN;
    if (need & 2) {   /* the factors at the lagged camber too, for the moment */
        wk_fyfac2_%(w)s_1(camber, gl, fzs, p, c.f1, cl.f1);
        if (c.two) wk_fyfac2_%(w)s_2(camber, gl, fzs, p, c.f2, cl.f2);
    } else {
        wk_fyfac1_%(w)s_1(camber, fzs, p, c.f1);
        if (c.two) wk_fyfac1_%(w)s_2(camber, fzs, p, c.f2);
    }
    o->gl_rate = speed * (camber - gl) / sig;
    o->F0 = need & 1 ? loaded * wk_curve_F(&c, 0.0) : NAN;
    o->sat = 0; o->cc = cc; o->dc = dc; o->y = y; o->vsy = vsy;
    if (!(cc > 0.0) || c.lam == 0.0) {     /* no lateral force: the carcass relaxes */
        o->F = 0.0; o->M = 0.0; o->slip = WK_KSLIP / WK_DEG; o->rate = -speed * y / sig;
        o->vslide = vsy + o->rate; return;
    }
    double F, a, lim;
    int sat;
    if (dc > 0.0) {
        /* Spring and damper in parallel: F_ss(a') = c y + d (|vx| tan a' - vsy), monotone in a'; past the
           limit (peak, or the curve at the kinematic slip) the patch force is the limit. */
        const double k = dc * speed, target = cc * y - dc * vsy;
        const int grip = loaded > 0.0 && c.f1[2] > 0.0 && !(c.two && !(c.f2[2] > 0.0));
        const double kslip = curve_law || !grip ? WK_KSLIP : 0.0;
        if (!grip) { sat = 0; F = 0.0; a = kslip; }
        else {
            double lo, hi;
            wk_curve_branch(&c, &lo, &hi);
            double lim_pos = wk_curve_F(&c, lo), lim_neg = wk_curve_F(&c, hi), a_pos = lo, a_neg = hi;
            if (curve_law && kslip < lo) { lim_pos = fmax(0.0, wk_curve_F(&c, kslip)); a_pos = wk_curve_inverse(&c, lim_pos, 0.0, lo, hi); }
            if (curve_law && kslip > hi) { lim_neg = fmin(0.0, wk_curve_F(&c, kslip)); a_neg = wk_curve_inverse(&c, lim_neg, 0.0, lo, hi); }
            if (lim_pos - k * tan(a_pos / WK_DEG) <= target) { sat = 1; a = a_pos; F = lim_pos; }
            else if (lim_neg - k * tan(a_neg / WK_DEG) >= target) { sat = -1; a = a_neg; F = lim_neg; }
            else { sat = 0; a = wk_curve_inverse(&c, target, k, a_pos, a_neg); F = wk_curve_F(&c, a); }
        }
        o->rate = (F - cc * y) / dc;
    } else {
        F = cc * y;
        a = wk_carcass_slip_%(w)s(&c, F, curve_law, vsy, speed, loaded, &sat, &lim, 0);
        /* Past the limit the patch slides faster than at the limit's own slip on the rising branch,
           by (limit - c y) / viscosity: continuous with the rising branch, stiff, and passive. */
        o->rate = speed * tan(a / WK_DEG) - vsy + (sat ? (lim - F) / p[%(visc)d] : 0.0);
    }
    o->sat = sat; o->F = F; o->slip = a / WK_DEG;
    o->vslide = vsy + o->rate;
    if (!(need & 2)) { o->slip_moment = NAN; o->M = NAN; return; }
    /* The moment at the lagged camber: the slip giving F there. */
    double aM = a;
    if (loaded > 0.0 && gl != camber) {
        int sat_l;
        double lim_l;
        cl.up[0] = c.up[0]; cl.up[1] = c.up[1];   /* the peaks' inner values do not depend on the camber */
        aM = wk_carcass_slip_%(w)s(&cl, F, 0, vsy, speed, loaded, &sat_l, &lim_l, 0);
    }
    o->slip_moment = aM / WK_DEG;
    o->M = wk_mz_%(w)s(aM / WK_DEG, gl, fz, p);
}

/* The undamped carcass' patch slips [deg] giving the force F at the camber and at the lagged camber gl, as
   wk_carcass_%(w)s finds them with the sliding law "peak" (search: a blend's common rising branch by the
   sets' branch ends, both branch ends before the saturation tests; the references); what the tests compare. */
static void wk_carcass_slips_%(w)s(double camber, double gl, double fz, double F, const double *p, int search,
                                  double *out)
{
    const double fzs = fmax(fz, %(floor).17g), loaded = fz > 0.0 ? 1.0 : 0.0;
    wk_curve c, cl;
    int sat;
    double lim;
    c.w = cl.w = p[%(wgt)d]; c.lam = cl.lam = p[%(lam)d]; c.two = cl.two = c.w != 0.0;
    c.up[0] = c.up[1] = NAN;
    wk_fyfac2_%(w)s_1(camber, gl, fzs, p, c.f1, cl.f1);
    if (c.two) wk_fyfac2_%(w)s_2(camber, gl, fzs, p, c.f2, cl.f2);
    out[0] = wk_carcass_slip_%(w)s(&c, F, 0, 0.0, 1.0, loaded, &sat, &lim, search);
    cl.up[0] = c.up[0]; cl.up[1] = c.up[1];
    out[1] = wk_carcass_slip_%(w)s(&cl, F, 0, 0.0, 1.0, loaded, &sat, &lim, search);
}
"""

_C_STATE = r"""
typedef struct {
    double F, M, slip, slip_moment, rate, gl_rate, F0, vslide, y, cc, dc, vsy;
    int sat;
} wk_carcass_state;
"""




def c_source(P, mf_y, mf_dy):
    """C source of the carcass block for both wheels.

    Parameters
    ----------
    P : mapping
        Parameter name -> index in the compiled model's parameter array.
    mf_y, mf_dy : str
        C bodies (``static double wk_mf_y(double a_deg, const double *f)`` and
        its slope) generated from the SymPy Magic Formula; the factor and
        gradient functions ``wk_fyfac_<w>_<k>``, ``wk_fyg_<w>`` and the moment
        ``wk_mz_<w>`` must be defined before.
    """
    out = [_C_STATE, mf_y, mf_dy, _C_GENERIC % {"cap": PATCH_SLIP_CAP_DEG}]
    for w in "rf":
        out.append(_C_WHEEL % {"w": w, "cc": P[f"cc{w}"], "dc": P[f"dc{w}"], "sig": P[f"sig{w}"],
                               "law": P["carcass_sliding"], "wgt": P[f"w{w}"], "lam": P[f"lam{w}"],
                               "floor": FZ_SHAPE_FLOOR, "visc": P["carcass_viscosity"]})
    return "\n".join(out)


# ------------------------------------------------------------ Python reference

def reference_branch(curve_fy, camber, fz):
    """Rising branch ``(lo, hi)`` [rad] of ``curve_fy`` at a camber and load: where it is largest and smallest.

    A scan of 16 001 patch slips over the cap, refined around both extremes
    at once by zooming in (257 points a side and step, each step 128 times
    narrower, to 1e-13 rad): a few vectorised calls, nothing of the C code's
    closed form or Newton iteration. An extreme at the cap stays there.
    """
    cap = math.radians(PATCH_SLIP_CAP_DEG)
    load = max(fz, FZ_SHAPE_FLOOR)
    grid = np.linspace(-cap, cap, 16001)
    force = curve_fy(grid, camber, load)
    sign = np.array([1.0, -1.0])   # the largest force, then the smallest
    k = np.array([np.argmax(force), np.argmin(force)])
    inside = (k > 0) & (k < grid.size - 1)
    a0, a1 = grid[np.clip(k - 1, 0, None)], grid[np.clip(k + 1, None, grid.size - 1)]
    steps = np.linspace(0.0, 1.0, 257)
    while inside.any() and np.max((a1 - a0)[inside]) > 1e-13:
        fine = a0[:, None] + (a1 - a0)[:, None] * steps   # both sides in one call
        j = np.argmax(sign[:, None] * curve_fy(fine.ravel(), camber, load).reshape(fine.shape), axis=1)
        rows = np.arange(2)
        a0, a1 = fine[rows, np.clip(j - 1, 0, None)], fine[rows, np.clip(j + 1, None, steps.size - 1)]
    ends = np.where(inside, 0.5 * (a0 + a1), grid[k])
    return float(ends[0]), float(ends[1])


def reference_block(curve_fy, curve_mz, vsy, vx, camber, fz, y, gl, cc, dc, sigma0, sliding="peak",
                    viscosity=SLIDING_VISCOSITY, grip=True, branches=None):
    """The carcass block computed independently in Python (the tests' second computation).

    Bracketed root finding (:func:`scipy.optimize.brentq`) on the steady
    curves, the rising branch from a fine scan refined by zooming
    (:func:`reference_branch`): nothing of the C code's closed form or Newton iteration.

    Parameters
    ----------
    curve_fy, curve_mz : callable
        ``(slip [rad], camber [rad], fz [N]) -> N`` and ``-> N m`` (model convention).
    vsy, vx, camber, fz, y, gl : float
        Sliding velocity [m/s], rolling speed [m/s], camber [rad], load [N],
        carcass deflection [m], lagged camber [rad].
    cc, dc, sigma0 : float
        Carcass stiffness [N/m], damping [N s/m], relaxation length [m].
    sliding : {"peak", "curve"}
    viscosity : float
        :data:`SLIDING_VISCOSITY` [N s/m].
    grip : bool
        False where the fit's peak factor D is not positive at this load
        (the patch then has no grip, as a lifted wheel's).
    branches : dict, optional
        ``{(camber, fz): (lo, hi)}``: rising branches of ``curve_fy`` already
        scanned, filled with this call's (callers share one per curve, so a
        second block or limit at the same camber and load scans nothing).

    Returns
    -------
    dict
        ``F M slip slip_moment rate gl_rate sat fmax fmin branch`` (``branch``:
        the rising branch's ends [rad]).
    """
    speed = abs(vx)
    kslip = math.atan2(vsy, speed)
    branches = {} if branches is None else branches

    def branch(cam):
        if (cam, fz) not in branches:
            branches[cam, fz] = reference_branch(curve_fy, cam, fz)
        return branches[cam, fz]

    lo, hi = branch(camber)
    fmax = curve_fy(lo, camber, fz) if fz > 0 else 0.0
    fmin = curve_fy(hi, camber, fz) if fz > 0 else 0.0
    lim_pos, lim_neg = fmax, fmin
    if sliding == "curve" and kslip < lo:
        lim_pos = max(0.0, float(curve_fy(kslip, camber, fz)))
    if sliding == "curve" and kslip > hi:
        lim_neg = min(0.0, float(curve_fy(kslip, camber, fz)))
    gl_rate = speed * (camber - gl) / sigma0
    sat = 0

    def rising(target):
        return brentq(lambda s: float(curve_fy(s, camber, fz)) - target, lo, hi, xtol=1e-15, rtol=1e-15)

    usable = fz > 0 and grip
    a_pos = rising(lim_pos) if usable and lim_pos != fmax else lo
    a_neg = rising(lim_neg) if usable and lim_neg != fmin else hi
    if dc > 0:
        k = dc * speed
        target = cc * y - dc * vsy
        if fz <= 0 or not grip:
            sat, force, a = 0, 0.0, kslip
        elif lim_pos - k * math.tan(a_pos) <= target:
            sat, force, a = 1, lim_pos, a_pos
        elif lim_neg - k * math.tan(a_neg) >= target:
            sat, force, a = -1, lim_neg, a_neg
        else:
            a = brentq(lambda s: float(curve_fy(s, camber, fz)) - k * math.tan(s) - target, a_pos, a_neg,
                       xtol=1e-15, rtol=1e-15)
            force = float(curve_fy(a, camber, fz))
        rate = (force - cc * y) / dc
    else:
        force = cc * y
        if fz <= 0 or not grip:
            # A lifted wheel (or a fit without grip at this load): the patch slides with the wheel,
            # the force relaxes through the viscosity.
            sat, a = int(np.sign(force)), kslip
            rate = speed * math.tan(a) - force / viscosity - vsy
        elif force >= lim_pos or force <= lim_neg:
            sat = 1 if force >= lim_pos else -1
            lim = lim_pos if sat > 0 else lim_neg
            a = a_pos if sat > 0 else a_neg
            rate = speed * math.tan(a) + (lim - force) / viscosity - vsy
        else:
            a = rising(force)
            rate = speed * math.tan(a) - vsy
    a_moment = a
    if gl != camber:
        llo, lhi = branch(gl)
        fp, fn = float(curve_fy(llo, gl, fz)), float(curve_fy(lhi, gl, fz))
        if force >= fp:
            a_moment = llo
        elif force <= fn:
            a_moment = lhi
        else:
            a_moment = brentq(lambda s: float(curve_fy(s, gl, fz)) - force, llo, lhi, xtol=1e-15, rtol=1e-15)
    return {"F": force, "M": float(curve_mz(a_moment, gl, fz)), "slip": a, "slip_moment": a_moment,
            "rate": rate, "gl_rate": gl_rate, "sat": sat, "fmax": float(fmax), "fmin": float(fmin),
            "branch": (lo, hi)}
