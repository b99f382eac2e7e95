"""The slip model's build side: SymPy expressions, C and NumPy source, compilation.

Run only on a cache miss (and by the tests that exercise it): the symbolic
equations of :func:`whipple_kick.model.symbolic.derivation.slip_equations` are printed
twice from the same expression lists, to C (with common subexpressions
eliminated, compiled with the system C compiler) and to NumPy (the test
oracle and speed baseline, :func:`numpy_rhs`). :func:`build_library` writes
the C source, the compiled library and its plain-data metadata (the layouts
of states, parameters and outputs with units) into the cache;
:mod:`whipple_kick.model.slip` loads them at run time without importing SymPy.

The C function does everything for one evaluation: the kick-plate profile,
the constraint matrix and the dependent speeds, slip and camber, normal
forces, the tyre block of the active transient form
(:mod:`whipple_kick.model.transient`, chosen by the ``tyre_transient`` parameter:
only its branch runs), the steer controller, Kane's equations and their
reduction by pivoted LU, and the rates of the energy quadratures
(:mod:`whipple_kick.model.energy`). The Magic-Formula curves are C functions that
skip a pressure-blend set of weight 0; the named outputs
(:data:`whipple_kick.model.slip.OUTPUT_NAMES`) are computed only when asked for.
"""
import functools
import json
import sys
import warnings

import numpy as np
import sympy as sm
from sympy.printing.c import C99CodePrinter

from whipple_kick import fileio
from whipple_kick.errors import PerformanceWarning
from whipple_kick.model import cache, carcass, energy, kane, magic_formula, reflex, transient
from whipple_kick.model import compiler as compilers
from whipple_kick.model import symbols as S
import whipple_kick.model.slip.layout as layouts  # the module by its full name, not through the package
from whipple_kick.model.slip.layout import (
    _SOURCES,
    IGNORABLE,
    PATCH_STATES,
    QUADRATURE_STATES,
    REFLEX_STATES,
    SPEEDS,
    P,
    X,
)
from whipple_kick.model.symbolic import codegen, derivation

#: Status of the C functions when a reflex delay is set in a model without the delay filter.
STATUS_NEEDS_DELAY = 3
#: Tyre-block inputs computed with Kane's terms (plain symbols, registered in :mod:`symbols`).
_KINEMATICS = ("vsy_r", "vsy_f", "vx_r", "vx_f", "camber_r", "camber_f", "fz_r", "fz_f",
               "vplate_r", "wz_r", "wz_f", "T7")
_APPLIED = ("Fy_r", "Fy_f", "Mz_r", "Mz_f")
#: What each tyre block returns, in order (beyond the applied loads): the four
#: state rates, then the form-dependent quadrature rates and relaxation lengths.
_BLOCK_EXTRAS = ("W0", "D_slide", "P_carcass_r", "P_carcass_f", "D_carcass", "sigma_r", "sigma_f",
                 "patch_slip_r", "patch_slip_f")
#: Output names the C code copies from the tyre block rather than computing.
_BLOCK_OUTPUTS = {"fy_r": "Fy_r", "fy_f": "Fy_f", "mz_r": "Mz_r", "mz_f": "Mz_f",
                  "sigma_r": "sigma_r", "sigma_f": "sigma_f", "patch_slip_r": "patch_slip_r",
                  "patch_slip_f": "patch_slip_f"}
#: Outputs computed by a compiled helper for every form: the friction limit on the force's side.
_LIMIT_OUTPUTS = ("fy_limit_r", "fy_limit_f")


# ------------------------------------------------------------ tyre curves

def _wheel_parameters(wheel, letter):
    """(coefficient symbol lists of both sets, weight, friction scale, curve scale) of one wheel."""
    sets = [list(S.syms([f"{letter}{wheel}{k}_{i}" for i in range(14 if letter == "a" else 18)])) for k in (1, 2)]
    w, mu, lam = S.syms([f"w{wheel}", f"mu{wheel}", f"lam{wheel}"])
    return sets, w, mu, lam


def _set_curve(kind, wheel, k, slip, camber, fz):
    """One coefficient set's raw steady curve (friction scale applied, no blend weight or curve scale)."""
    mf = magic_formula
    letter = "a" if kind == "fy" else "c"
    sets, _, mu, _ = _wheel_parameters(wheel, letter)
    builder = mf.lateral_force_model if kind == "fy" else mf.aligning_moment_model
    return builder(slip, camber, fz, sets[k - 1], friction_scale=mu)


def _set_secant(wheel, k, slip, fz):
    """(slope, secant ratio) of one coefficient set (:func:`magic_formula.lateral_secant_model`)."""
    sets, _, mu, _ = _wheel_parameters(wheel, "a")
    return magic_formula.lateral_secant_model(slip, fz, sets[k - 1], friction_scale=mu)


def _inline_curves():
    """Curve builders giving full expressions (the NumPy oracle prints these)."""
    def blend(kind):
        def curve(wheel, slip, camber, fz):
            _, w, _, lam = _wheel_parameters(wheel, "a")
            return lam * ((1 - w) * _set_curve(kind, wheel, 1, slip, camber, fz)
                          + w * _set_curve(kind, wheel, 2, slip, camber, fz))
        return curve

    def secant(wheel, slip, fz):
        _, w, _, _ = _wheel_parameters(wheel, "a")
        (c1, g1), (c2, g2) = _set_secant(wheel, 1, slip, fz), _set_secant(wheel, 2, slip, fz)
        return ((1 - w) * c1 * g1 + w * c2 * g2) / ((1 - w) * c1 + w * c2)
    return {"fy": blend("fy"), "mz": blend("mz"), "secant": secant}


def _called_curves():
    """Curve builders giving calls of the compiled curve functions (``wk_fy_r(...)``)."""
    def call(kind):
        return lambda wheel, *args: sm.Function(f"wk_{kind}_{wheel}")(*args)
    return {"fy": call("fy"), "mz": call("mz"), "secant": call("sec")}


def _factor_symbols():
    """Symbols printing as ``f[0]`` .. ``f[5]``: the factors B C D E Sh Sv in the generic C curve."""
    return [sm.Symbol(f"f[{i}]", real=True) for i in range(6)]


def _c_carcass_curves():
    """C of the Magic-Formula pieces the carcass tyre needs, generated from :mod:`magic_formula`.

    ``wk_mf_y``/``wk_mf_dy``: the formula-convention curve of given factors
    and its slope per degree; per wheel and set, ``wk_fyfac_<w>_<k>`` (the
    factors at a camber and load, as :func:`magic_formula.lateral_force_model_factors`)
    and ``wk_fyg_<w>_<k>`` (the set's model force and its derivatives in
    slip, camber and load); per wheel the blend ``wk_fyg_<w>`` and the
    friction limit on a force's side ``wk_fylim_<w>`` (an output).
    """
    a_deg = sm.Symbol("a_deg", real=True)
    f = _factor_symbols()
    factors = dict(zip(("B", "C", "D", "E", "Sh", "Sv"), f, strict=True))
    y = magic_formula._curve(a_deg, factors)
    printer = _Printer()
    mf_y = ("static double wk_mf_y(double a_deg, const double *f)\n{\n"
            f"    return {printer.doprint(y)};\n}}")
    mf_dy = ("static double wk_mf_dy(double a_deg, const double *f)\n{\n"
             f"    return {printer.doprint(sm.diff(y, a_deg))};\n}}")
    # Value and slope together (the Newton iterations need both): their common terms computed once.
    mf_dy += ("\nstatic void wk_mf_ydy(double a_deg, const double *f, double *y, double *dy)\n{\n"
              + _c_block([y, sm.diff(y, a_deg)], ["*y", "*dy"]) + "\n}")
    slip, camber, fz = sm.symbols("slip camber fz", real=True)
    lines = []
    for wheel in "rf":
        for k in (1, 2):
            sets, _, mu, _ = _wheel_parameters(wheel, "a")
            fac = magic_formula.lateral_force_model_factors(camber, fz, sets[k - 1], friction_scale=mu)
            exprs = [fac[n] for n in ("B", "C", "D", "E", "Sh", "Sv")]
            lines += [f"static void wk_fyfac_{wheel}_{k}(double camber, double fz, const double *p, double *fac)",
                      "{", *_parameter_locals(exprs), _c_block(exprs, [f"fac[{i}]" for i in range(6)]), "}"]
            # The factors at two cambers in one CSE'd block (the load terms shared).
            lagged = sm.Symbol("gl", real=True)
            fac2 = magic_formula.lateral_force_model_factors(lagged, fz, sets[k - 1], friction_scale=mu)
            both = exprs + [fac2[n] for n in ("B", "C", "D", "E", "Sh", "Sv")]
            targets = [f"fac[{i}]" for i in range(6)] + [f"fac2[{i}]" for i in range(6)]
            lines += [f"static void wk_fyfac2_{wheel}_{k}(double camber, double gl, double fz, const double *p, "
                      "double *fac, double *fac2)", "{", *_parameter_locals(both), _c_block(both, targets), "}"]
            # The first camber's factors alone (a carcass block that needs no moment), as the pair's block prunes
            # them: the same statements, so the same bits as wk_fyfac2's fac.
            lines += [f"static void wk_fyfac1_{wheel}_{k}(double camber, double fz, const double *p, double *fac)",
                      "{", *_parameter_locals(exprs), _c_block(both, targets, keep=range(6)), "}"]
            e = _set_curve("fy", wheel, k, slip, camber, fz)
            grad = [e, sm.diff(e, slip), sm.diff(e, camber), sm.diff(e, fz)]
            lines += [f"static void wk_fyg_{wheel}_{k}(double slip, double camber, double fz, const double *p, "
                      "double *g)", "{", *_parameter_locals(grad), _c_block(grad, [f"g[{i}]" for i in range(4)]),
                      "}"]
        lines += [f"static void wk_fyg_{wheel}(double slip, double camber, double fz, const double *p, double *g)",
                  "{", f"    const double w = p[{P['w' + wheel]}], lam = p[{P['lam' + wheel]}];",
                  "    double g2[4];",
                  f"    wk_fyg_{wheel}_1(slip, camber, fz, p, g);",
                  "    for (int i = 0; i < 4; i++) g[i] *= (1.0 - w);",
                  f"    if (w != 0.0) {{ wk_fyg_{wheel}_2(slip, camber, fz, p, g2); "
                  "for (int i = 0; i < 4; i++) g[i] += w * g2[i]; }",
                  "    for (int i = 0; i < 4; i++) g[i] *= lam;", "}"]
    return mf_y, mf_dy, lines


def _c_limit_functions():
    """Per wheel ``wk_fylim_<w>(camber, fz, F, p)``: the friction limit on the side of ``F`` [N] (an output).

    ``wk_fylim_<w>_by(..., search)``: with ``search`` by the branch search alone, the reference of the
    shortcut one set's interior peak takes (``wk_curve_peak``; the same value bit for bit, a test checks it).
    """
    lines = []
    for wheel in "rf":
        lines += [f"static double wk_fylim_{wheel}_by(double camber, double fz, double F, const double *p, "
                  "int search)", "{",
                  "    if (!(fz > 0.0)) return 0.0;",
                  "    wk_curve c;", "    c.up[0] = c.up[1] = NAN;",
                  f"    c.w = p[{P['w' + wheel]}]; c.lam = p[{P['lam' + wheel]}]; c.two = c.w != 0.0;",
                  f"    wk_fyfac_{wheel}_1(camber, fmax(fz, {carcass.FZ_SHAPE_FLOOR!r}), p, c.f1);",
                  f"    if (c.two) wk_fyfac_{wheel}_2(camber, fmax(fz, {carcass.FZ_SHAPE_FLOOR!r}), p, c.f2);",
                  "    if (!(c.f1[2] > 0.0) || (c.two && !(c.f2[2] > 0.0))) return 0.0;   /* no grip in the fit */",
                  "    double peak;",
                  "    if (!search && wk_curve_peak(&c, F, &peak)) return peak;",
                  "    /* only the end on the force's side (a blend searches each end on its own) */",
                  "    return F >= 0.0 ? wk_curve_F(&c, wk_curve_end(&c, 0)) : -wk_curve_F(&c, wk_curve_end(&c, 1));",
                  "}",
                  f"static double wk_fylim_{wheel}(double camber, double fz, double F, const double *p)",
                  f"{{ return wk_fylim_{wheel}_by(camber, fz, F, p, 0); }}"]
    return lines


# ---------------------------------------------------------------- expressions

def _expressions(part_names=()):
    """Everything both printers need, as plain-symbol SymPy expressions (:func:`_expressions_of`), once per model
    and set of declared tyre forms (a form declared later changes the blocks)."""
    return _expressions_of(tuple(part_names), transient.fingerprint())


@functools.cache
def _expressions_of(part_names, forms):
    """Everything both printers need, as plain-symbol SymPy expressions (``forms``: the forms' fingerprint).

    Returns
    -------
    dict
        ``stage1`` (constraint matrix and offset), ``stage2`` (mass matrix,
        forcing without tyre loads ``f0``, its derivative ``G`` with respect
        to the applied loads, acceleration remainder, tyre-block inputs),
        ``blocks`` (per transient form and curve style), ``common`` (the
        form-independent quadrature rates), ``outputs`` (named outputs by
        name, the block's copies excluded), ``mass`` (the mass matrix alone)
        and ``symbols``; of the model with the parts ``part_names``.
    """
    L = layouts.for_parts(part_names)
    eom = derivation.slip_equations(part_names)
    dyn = list(eom.q) + list(eom.u)
    t = sm.Symbol("t", real=True)
    vp_s, ap_s = eom.inputs[:2]
    applied = sm.Matrix(eom.inputs[2:])
    ex = eom.extra
    profile = {vp_s: ex["vp"], ap_s: ex["ap"]}

    def plain(e):
        return codegen.plain(sm.sympify(e) if not isinstance(e, sm.MatrixBase) else e, dyn).xreplace(profile)

    forcing = plain(eom.forcing)
    G = forcing.jacobian(applied)
    if G.free_symbols & set(applied):
        raise RuntimeError("Kane's forcing is not linear in the tyre loads")
    f0 = forcing.xreplace(dict.fromkeys(applied, 0))
    kin = {name: plain(ex[name]) for name in _KINEMATICS}
    u = {f"u{i + 1}": codegen.plain_symbol(s) for i, s in enumerate(eom.u)}
    sigma0 = {"r": S.sym("sigr"), "f": S.sym("sigf")}
    blocks = {style: {name: transient.tyre_block(name, curves(), sigma0) for name in transient.symbolic()}
              for style, curves in (("inline", _inline_curves), ("called", _called_curves))}
    common = {k: plain(v) for k, v in energy.common_rates(ex, u, S.sym("T6c")).items()}
    k_sym = {name: S.sym(name) for name in _KINEMATICS + _APPLIED}
    slip = {w: sm.atan2(k_sym[f"vsy_{w}"], sm.Abs(k_sym[f"vx_{w}"])) for w in "rf"}
    outputs = {name: plain(ex[name]) for name in ("yp", "vp", "ap")}
    for w in "rf":
        outputs[f"slip_{w}"] = slip[w]
    for name in ("camber_r", "camber_f", "vx_r", "vx_f", "fz_r", "fz_f"):
        outputs[name] = k_sym[name]
    for style in ("inline", "called"):
        curves = (_inline_curves if style == "inline" else _called_curves)()
        outputs[f"steady_{style}"] = {
            f"{kind}_ss_{w}": curves[kind](w, slip[w], k_sym[f"camber_{w}"], k_sym[f"fz_{w}"])
            for kind in ("fy", "mz") for w in "rf"}
    outputs.update({
        # The reflex's torques are locals of the right-hand side (and arguments of the NumPy outputs).
        "T7": k_sym["T7"], "T_reflex": S.sym("T_reflex"), "reflex_input": sm.Symbol("reflex_input", real=True),
        **{name: plain(ex[name]) for name in L.PART_OUTPUTS},
        "kinetic_energy": plain(eom.kinetic_energy),
        "potential_energy": plain(eom.potential_energy), "spring_energy": plain(ex["spring_energy"]),
        "holonomic": plain(eom.holonomic),
        "sliding_power": k_sym["Fy_r"] * k_sym["vsy_r"] + k_sym["Fy_f"] * k_sym["vsy_f"],
    })
    return {
        "stage1": {"A": plain(eom.constraint_matrix), "a0": plain(eom.constraint_offset)},
        "stage2": {"M": plain(eom.mass_matrix), "f0": f0, "G": G, "b": plain(eom.constraint_accel),
                   "kinematics": sm.Matrix([kin[n] for n in _KINEMATICS])},
        "blocks": blocks, "common": common, "outputs": outputs,
        "reflex_input": plain(ex["reflex_input"]),
        "symbols": {
            "t": t,
            "q": [codegen.plain_symbol(s) for s in eom.q],
            "u": [codegen.plain_symbol(s) for s in eom.u],
            "s": {name: [sm.Symbol(n, real=True) for n in transient.FORMS[name].states] for name in transient.transients()},
            "p": list(S.syms(L.PARAMETER_NAMES)),
            "kinematics": [k_sym[n] for n in _KINEMATICS],
            "applied": [k_sym[n] for n in _APPLIED],
            "reflex": [S.sym("T_reflex")],
            "reflex_outputs": [S.sym("T_reflex"), sm.Symbol("reflex_input", real=True)],
        },
    }


def _block_list(block):
    """A tyre block's expressions in the fixed order: applied loads, 4 rates, :data:`_BLOCK_EXTRAS`."""
    return [block[n] for n in _APPLIED] + list(block["rates"]) + [block[n] for n in _BLOCK_EXTRAS]


def _output_list(ex, style, L):
    """Output expressions in ``L.OUTPUT_NAMES`` order after the base speeds, block copies as their symbols."""
    steady = ex["outputs"][f"steady_{style}"]
    out = []
    for name in L.OUTPUT_NAMES[len(SPEEDS):]:
        if name in L.SPEEDS:   # a part's speed
            out.append(sm.Symbol(name, real=True))
        elif name in _BLOCK_OUTPUTS:
            out.append(sm.Symbol(_BLOCK_OUTPUTS[name], real=True))
        elif name in _LIMIT_OUTPUTS:
            w = name[-1]
            args = [sm.Symbol(f"camber_{w}", real=True), sm.Symbol(f"fz_{w}", real=True),
                    sm.Symbol(f"Fy_{w}", real=True)]
            out.append(sm.Function(f"wk_fylim_{w}")(*args) if style == "called" else sm.Symbol(name, real=True))
        else:
            out.append(steady[name] if name in steady else ex["outputs"][name])
    return out


# --------------------------------------------------------------------------- C

_C_HELPERS = r"""
#include <math.h>
#include <string.h>
/* Not defined by strict C99 <math.h>; SymPy's printer uses them. */
#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif
#ifndef M_1_PI
#define M_1_PI 0.31830988618379067154
#endif
#ifndef M_PI_2
#define M_PI_2 1.57079632679489661923
#endif

/* Solve A X = B in place by LU with partial pivoting. A is n x n, B is
   n x m, both row-major. Returns 0 on success, 1 if A is singular. */
static int lu_solve(int n, double *A, int m, double *B)
{
    for (int k = 0; k < n; k++) {
        int piv = k;
        double big = fabs(A[k * n + k]);
        for (int i = k + 1; i < n; i++) {
            double v = fabs(A[i * n + k]);
            if (v > big) { big = v; piv = i; }
        }
        if (!(big > 0.0)) return 1;
        if (piv != k) {
            for (int j = 0; j < n; j++) { double tmp = A[k * n + j]; A[k * n + j] = A[piv * n + j]; A[piv * n + j] = tmp; }
            for (int j = 0; j < m; j++) { double tmp = B[k * m + j]; B[k * m + j] = B[piv * m + j]; B[piv * m + j] = tmp; }
        }
        for (int i = k + 1; i < n; i++) {
            double l = A[i * n + k] / A[k * n + k];
            A[i * n + k] = l;
            for (int j = k + 1; j < n; j++) A[i * n + j] -= l * A[k * n + j];
            for (int j = 0; j < m; j++) B[i * m + j] -= l * B[k * m + j];
        }
    }
    for (int i = n - 1; i >= 0; i--) {
        for (int j = 0; j < m; j++) {
            double s = B[i * m + j];
            for (int k = i + 1; k < n; k++) s -= A[i * n + k] * B[k * m + j];
            B[i * m + j] = s / A[i * n + i];
        }
    }
    return 0;
}
"""


class _Printer(C99CodePrinter):
    """C printer: plain symbols print as their names (declared as locals); the
    compiled curve functions ``wk_*`` get the parameter pointer ``p``."""

    def _print_Symbol(self, expr):
        return expr.name

    def _print_Function(self, expr):
        name = expr.func.__name__
        if name.startswith("wk_"):
            return f"{name}({', '.join(self._print(a) for a in expr.args)}, p)"
        return super()._print_Function(expr)


@functools.lru_cache(maxsize=64)
def _cse(exprs):
    """``sympy.cse`` of the tuple ``exprs``, once per build: a block and its pruned copy share one elimination."""
    return sm.cse(list(exprs), symbols=sm.numbered_symbols("x_"), order="none")


def _c_block(exprs, targets, indent="    ", keep=None):
    """C statements computing ``exprs`` (CSE'd) into the C lvalues ``targets``.

    With ``keep`` (positions in ``exprs``) only those targets are written, and
    only the common subexpressions they need are computed: the statements left
    are the full block's own, unchanged, so the kept values are bit for bit the
    full block's (the outputs function leaves Kane's mass matrix out this way).
    """
    printer = _Printer()
    replacements, reduced = _cse(tuple(exprs))
    pairs = list(zip(targets, reduced, strict=True))
    if keep is not None:
        pairs = [pairs[i] for i in keep]
        needed = set().union(*(e.free_symbols for _, e in pairs))
        kept = []
        for lhs, rhs in reversed(replacements):
            if lhs in needed:
                kept.append((lhs, rhs))
                needed |= rhs.free_symbols
        replacements = kept[::-1]
    lines = [f"{indent}const double {lhs} = {printer.doprint(rhs)};" for lhs, rhs in replacements]
    lines += [f"{indent}{target} = {printer.doprint(e)};" for target, e in pairs]
    return "\n".join(lines)


def _parameter_locals(exprs, indent="    ", L=layouts.BASE):
    """``const double name = p[i];`` for the parameters ``exprs`` use (of the layout ``L``)."""
    used = set().union(*(sm.sympify(e).free_symbols for e in exprs))
    return [f"{indent}const double {s.name} = p[{L.P[s.name]}];" for s in S.syms(L.PARAMETER_NAMES) if s in used]


def _c_curve_functions():
    """Static C functions of the Magic-Formula curves, per wheel; a set of weight 0 is skipped."""
    slip, camber, fz = sm.symbols("slip camber fz", real=True)
    lines = []
    for wheel in "rf":
        for kind in ("fy", "mz"):
            for k in (1, 2):
                e = _set_curve(kind, wheel, k, slip, camber, fz)
                lines += [f"static double wk_{kind}_{wheel}_{k}(double slip, double camber, double fz, const double *p)",
                          "{", *_parameter_locals([e]), "    double v;", _c_block([e], ["v"]), "    return v;", "}"]
            lines += [f"static double wk_{kind}_{wheel}(double slip, double camber, double fz, const double *p)", "{",
                      f"    const double w = p[{P['w' + wheel]}];",
                      f"    double v = (1.0 - w) * wk_{kind}_{wheel}_1(slip, camber, fz, p);",
                      f"    if (w != 0.0) v += w * wk_{kind}_{wheel}_2(slip, camber, fz, p);",
                      f"    return p[{P['lam' + wheel]}] * v;", "}"]
        for k in (1, 2):
            slope, ratio = _set_secant(wheel, k, slip, fz)
            lines += [f"static void wk_sec_{wheel}_{k}(double slip, double fz, const double *p, double *c0, double *g)",
                      "{", *_parameter_locals([slope, ratio]), _c_block([slope, ratio], ["*c0", "*g"]), "}"]
        lines += [f"static double wk_sec_{wheel}(double slip, double fz, const double *p)", "{",
                  f"    const double w = p[{P['w' + wheel]}];",
                  "    double c1, g1, c2, g2;",
                  f"    wk_sec_{wheel}_1(slip, fz, p, &c1, &g1);",
                  "    if (w == 0.0) return g1;",
                  f"    wk_sec_{wheel}_2(slip, fz, p, &c2, &g2);",
                  "    return ((1.0 - w) * c1 * g1 + w * c2 * g2) / ((1.0 - w) * c1 + w * c2);", "}"]
    return lines


#: Quadrature states whose rates the tyre block gives, and the block's local names for them.
_BLOCK_QUADRATURES = (("W_zero_slip", "W0"), ("D_slide", "D_slide"), ("E_carcass_r", "P_carcass_r"),
                      ("E_carcass_f", "P_carcass_f"), ("D_carcass", "D_carcass"))


def _c_prologue(ex, dynamics, L, carcass_need="3"):
    """C statements of one evaluation up to the tyre block: the locals every later part reads.

    Parameters, coordinates and tyre states as locals, the constraint matrix
    and the dependent speeds, the reflex, the tyre-block inputs (with Kane's
    mass matrix, forcing and constraint remainder when ``dynamics``) and the
    active transient form's tyre block. Without ``dynamics`` the stage-2 block
    is the same CSE'd block pruned to the tyre-block inputs (:func:`_c_block`'s
    ``keep``): the outputs function computes them bit for bit as the
    right-hand side does, without the mass matrix. ``carcass_need``: the C
    expression of what the carcass block computes beyond the force and the
    patch slip (bit 1 the zero-slip force, bit 2 the aligning moment;
    :mod:`whipple_kick.model.carcass`), left NaN otherwise.
    """
    sy = ex["symbols"]
    n, m, k = len(L.SPEEDS), len(L.DEPENDENT), len(L.INDEPENDENT)
    nt, nr = len(PATCH_STATES), len(L.REFLEX_STATES)
    dep = [L.SPEEDS.index(x) for x in L.DEPENDENT]
    ind = [L.SPEEDS.index(x) for x in L.INDEPENDENT]
    lines = []
    for i, s in enumerate(sy["p"]):
        lines.append(f"    const double {s.name} = p[{i}];")
    for s in sy["q"]:
        lines.append(f"    const double {s.name} = x[{L.X[s.name]}];")
    declared = set()   # forms share slot names (slip_lag's are contact_patch's, the carcass' camber too)
    for name in transient.transients():
        for slot, s in enumerate(sy["s"][name]):
            if s.name not in declared:
                declared.add(s.name)
                lines.append(f"    const double {s.name} = x[{X[PATCH_STATES[slot]]}];")
    lines.append(f"    double A[{m * n}], a0[{m}];")
    stage1 = ex["stage1"]
    lines += ["    {", _c_block(list(stage1["A"]) + list(stage1["a0"]),
                                 [f"A[{i}]" for i in range(m * n)] + [f"a0[{i}]" for i in range(m)], "        "), "    }"]
    # Dependent speeds: A_dep u_dep = -(A_ind u_ind + a0).
    lines.append(f"    double u[{n}];")
    for name, idx in zip(L.INDEPENDENT, ind, strict=True):
        lines.append(f"    u[{idx}] = x[{L.X[name]}];")
    # With the dynamics, one LU of A_dep serves both the speeds (last column) and T (the rest); without them
    # only the speeds' column is solved for: lu_solve treats each column on its own, so the speeds are the
    # same bit for bit (and the outputs some 3% cheaper per sample).
    width = k + 1 if dynamics else 1
    lines.append(f"    double Adep[{m * m}], rhs1[{m * width}];")
    lines.append(f"    for (int i = 0; i < {m}; i++) {{")
    lines.append("        double s = a0[i];")
    for jj, idx in enumerate(dep):
        lines.append(f"        Adep[i * {m} + {jj}] = A[i * {n} + {idx}];")
    for jj, idx in enumerate(ind):
        lines.append(f"        s += A[i * {n} + {idx}] * u[{idx}];")
        if dynamics:
            lines.append(f"        rhs1[i * {k + 1} + {jj}] = A[i * {n} + {idx}];")
    lines.append(f"        rhs1[i * {width} + {width - 1}] = -s;")
    lines.append("    }")
    lines.append(f"    if (lu_solve({m}, Adep, {width}, rhs1)) return 1;")
    for jj, idx in enumerate(dep):
        lines.append(f"    u[{idx}] = rhs1[{jj} * {width} + {width - 1}];")
    for i, s in enumerate(sy["u"]):
        lines.append(f"    const double {s.name} = u[{i}];")
    # The rider's reflex: its undelayed torque through the delay filter (whipple_kick.model.reflex), in the
    # model with the filter; without it the reflex acts undelayed (what the filter gives for a zero delay).
    lines += ["    double reflex_input;",
              "    {", _c_block([ex["reflex_input"]], ["reflex_input"], "        "), "    }"]
    if L.delayed_reflex:
        zr = ", ".join(f"x[{L.X[name]}]" for name in L.REFLEX_STATES)
        lines += [f"    const double zr[{nr}] = {{{zr}}};",
                  "    const double T_reflex = wk_reflex_output(reflex_delay, zr, reflex_input);"]
        if dynamics:
            lines += [f"    double dzr[{nr}];", "    wk_reflex_rates(reflex_delay, zr, reflex_input, dzr);"]
    else:
        lines += [f"    if (reflex_delay != 0.0) return {STATUS_NEEDS_DELAY};   /* a delay needs the filter's model */",
                  "    const double T_reflex = reflex_input;"]
    # Kane's terms and the tyre block's inputs in one CSE'd block.
    st2 = ex["stage2"]
    kin = [s.name for s in sy["kinematics"]]
    exprs = list(st2["M"]) + list(st2["f0"]) + list(st2["G"]) + list(st2["b"]) + list(st2["kinematics"])
    if dynamics:
        lines.append(f"    double M[{n * n}], f[{n}], G[{n * 4}], b[{m}], {', '.join(kin)};")
    else:
        lines.append(f"    double {', '.join(kin)};")
    lines += ["    {", _c_block(exprs, [f"M[{i}]" for i in range(n * n)] + [f"f[{i}]" for i in range(n)]
                                 + [f"G[{i}]" for i in range(n * 4)] + [f"b[{i}]" for i in range(m)] + kin,
                                 "        ", keep=None if dynamics else range(len(exprs) - len(kin), len(exprs))),
              "    }"]
    # The active transient form's tyre block (only its branch runs).
    block_targets = list(_APPLIED) + [f"trate[{i}]" for i in range(nt)] + list(_BLOCK_EXTRAS)
    lines.append(f"    double {', '.join(_APPLIED)}, trate[{nt}], {', '.join(_BLOCK_EXTRAS)};")
    lines.append("    const int mode = (int)tyre_transient;")
    lines.append("    wk_carcass_state cr, cf;")
    for code, name in enumerate(transient.symbolic()):
        head = "if" if code == 0 else "else if"
        lines += [f"    {head} (mode == {transient.transients().index(name)}) {{",
                  _c_block(_block_list(ex["blocks"]["called"][name]), block_targets, "        "), "    }"]
    # The carcass tyre (whipple_kick.model.carcass): written in C, not a SymPy expression.
    lines += ["    else {",
              f"        wk_carcass_r(vsy_r, vx_r, camber_r, fz_r, carcass_y_r, camber_patch_r, p, {carcass_need}, &cr);",
              f"        wk_carcass_f(vsy_f, vx_f, camber_f, fz_f, carcass_y_f, camber_patch_f, p, {carcass_need}, &cf);",
              "        Fy_r = cr.F; Fy_f = cf.F; Mz_r = cr.M; Mz_f = cf.M;",
              "        trate[0] = cr.rate; trate[1] = cf.rate; trate[2] = cr.gl_rate; trate[3] = cf.gl_rate;",
              "        W0 = cr.F0 * cr.vslide + cf.F0 * cf.vslide;",
              "        D_slide = -(cr.F - cr.F0) * cr.vslide - (cf.F - cf.F0) * cf.vslide;",
              "        P_carcass_r = cr.cc * cr.y * cr.rate; P_carcass_f = cf.cc * cf.y * cf.rate;",
              "        D_carcass = cr.dc * cr.rate * cr.rate + cf.dc * cf.rate * cf.rate;",
              "        sigma_r = sigr; sigma_f = sigf; patch_slip_r = cr.slip; patch_slip_f = cf.slip;",
              "    }"]
    return lines


def _c_outputs(ex, indent, L, names=None):
    """C statements writing the named outputs (``L.OUTPUT_NAMES``) into ``out`` from the prologue's locals.

    With ``names`` only those outputs (the speeds always): the full block pruned by :func:`_c_block`'s ``keep``,
    so each is bit for bit the full block's.
    """
    n = len(SPEEDS)
    keep = None if names is None else [i - n for i, o in enumerate(L.OUTPUT_NAMES) if i >= n and o in names]
    return [f"{indent}for (int i = 0; i < {n}; i++) out[i] = u[i];", f"{indent}{{",
            _c_block(_output_list(ex, "called", L), [f"out[{n + i}]" for i in range(len(L.OUTPUT_NAMES) - n)],
                     indent + "    ", keep=keep), f"{indent}}}"]


def _c_outputs_some(ex, L):
    """C function ``wk_slip_sample_some``: the outputs function's prologue and outputs, the optional groups
    (:data:`whipple_kick.model.slip.layout.OPTIONAL_OUTPUTS`) only where bit ``k`` of ``groups`` asks for group ``k``.

    Each group is its own pruned copy of the output block (its common subexpressions computed again, the
    same statements): every value is bit for bit the full block's. The outputs left out are not written.
    """
    optional = {name for group in layouts.OPTIONAL_OUTPUTS for name in group}
    moment = 1 << next(k for k, group in enumerate(layouts.OPTIONAL_OUTPUTS) if "mz_r" in group)
    lines = ["static int wk_slip_sample_some(double t, const double *x, const double *p, int groups, double *out)",
             "{", *_c_prologue(ex, dynamics=False, L=L, carcass_need=f"(groups & {moment} ? 2 : 0)"),
             *_c_outputs(ex, "    ", L, [o for o in L.OUTPUT_NAMES if o not in optional])]
    for k, group in enumerate(layouts.OPTIONAL_OUTPUTS):
        keep = [i - len(SPEEDS) for i, o in enumerate(L.OUTPUT_NAMES) if o in group]
        lines += [f"    if (groups & {1 << k}) {{",
                  _c_block(_output_list(ex, "called", L),
                           [f"out[{len(SPEEDS) + i}]" for i in range(len(L.OUTPUT_NAMES) - len(SPEEDS))],
                           "        ", keep=keep), "    }"]
    return [*lines, "    return 0;", "}"]


def c_source(part_names=(), delayed_reflex=False):
    """Full C source of the slip model: right-hand side, outputs (with and without the dynamics), Jacobian,
    impulse terms, of the model with the parts ``part_names`` (and the reflex's delay filter with
    ``delayed_reflex``)."""
    L = layouts.for_parts(part_names, delayed_reflex)
    ex = _expressions(part_names)
    sy = ex["symbols"]
    n, m, k = len(L.SPEEDS), len(L.DEPENDENT), len(L.INDEPENDENT)
    ns, nd = len(L.STATE_NAMES), len(L.DYNAMIC_STATES)
    nt = len(PATCH_STATES)
    dep = [L.SPEEDS.index(x) for x in L.DEPENDENT]
    ind = [L.SPEEDS.index(x) for x in L.INDEPENDENT]
    mf_y, mf_dy, carcass_curves = _c_carcass_curves()
    lines = [_C_HELPERS, "/* Generated by whipple_kick.model.slip; do not edit. */", *_c_curve_functions(),
             *carcass_curves, carcass.c_source(P, mf_y, mf_dy), *_c_limit_functions(), reflex.c_source()]
    lines += ["int wk_slip_rhs(double t, const double *x, const double *p, double *dx, double *out)", "{"]
    lines += _c_prologue(ex, dynamics=True, L=L)
    lines.append(f"    for (int i = 0; i < {n}; i++) f[i] += G[i * 4] * Fy_r + G[i * 4 + 1] * Fy_f"
                 " + G[i * 4 + 2] * Mz_r + G[i * 4 + 3] * Mz_f;")
    # Kane's reduced equations: T = [I; C], C = -A_dep^-1 A_ind, t0 = [0; d], d = -A_dep^-1 b.
    lines.append(f"    double T[{n * k}], t0[{n}], d[{m}];")
    lines.append("    memset(T, 0, sizeof T); memset(t0, 0, sizeof t0);")
    for jj, idx in enumerate(ind):
        lines.append(f"    T[{idx} * {k} + {jj}] = 1.0;")
    lines.append(f"    double Adep2[{m * m}], rhs2[{m}];")
    lines.append(f"    for (int i = 0; i < {m}; i++) {{")
    for jj, idx in enumerate(dep):
        lines.append(f"        Adep2[i * {m} + {jj}] = A[i * {n} + {idx}];")
    lines.append("        rhs2[i] = b[i];")
    lines.append("    }")
    lines.append(f"    if (lu_solve({m}, Adep2, 1, rhs2)) return 1;")
    lines.append(f"    for (int i = 0; i < {m}; i++) d[i] = -rhs2[i];")
    # rhs1 now holds A_dep^-1 A_ind in its first k columns.
    for ii, idx in enumerate(dep):
        lines.append(f"    for (int j = 0; j < {k}; j++) T[{idx} * {k} + j] = -rhs1[{ii} * {k + 1} + j];")
        lines.append(f"    t0[{idx}] = d[{ii}];")
    lines.append(f"    double MT[{n * k}], Mr[{k * k}], r[{k}];")
    lines.append(f"    for (int i = 0; i < {n}; i++) for (int j = 0; j < {k}; j++) {{")
    lines.append(f"        double s = 0.0; for (int l = 0; l < {n}; l++) s += M[i * {n} + l] * T[l * {k} + j]; MT[i * {k} + j] = s; }}")
    lines.append(f"    for (int i = 0; i < {k}; i++) {{")
    lines.append(f"        for (int j = 0; j < {k}; j++) {{ double s = 0.0; for (int l = 0; l < {n}; l++) s += T[l * {k} + i] * MT[l * {k} + j]; Mr[i * {k} + j] = s; }}")
    lines.append("        double s = 0.0;")
    lines.append(f"        for (int l = 0; l < {n}; l++) {{ double g = f[l]; for (int c = 0; c < {n}; c++) g -= M[l * {n} + c] * t0[c]; s += T[l * {k} + i] * g; }}")
    lines.append("        r[i] = s;")
    lines.append("    }")
    lines.append(f"    if (lu_solve({k}, Mr, 1, r)) return 1;")
    # Each coordinate's rate is its speed (the layouts pair them in order); the base model's states
    # are contiguous as in its layout, the parts' follow the quadratures.
    nb = len(SPEEDS)
    lines.append(f"    for (int i = 0; i < {nb}; i++) dx[i] = u[i];")
    lines += [f"    dx[{L.X[q]}] = u[{i}];" for i, q in enumerate(L.COORDINATES) if i >= nb]
    lines += [f"    dx[{L.X[name]}] = r[{i}];" for i, name in enumerate(L.INDEPENDENT)]
    lines.append(f"    for (int i = 0; i < {nt}; i++) dx[{X[PATCH_STATES[0]]} + i] = trate[i];")
    lines += [f"    dx[{L.X[name]}] = dzr[{i}];" for i, name in enumerate(L.REFLEX_STATES)]
    # Quadrature rates: the form-independent ones, then the tyre block's.
    q0 = X[QUADRATURE_STATES[0]]
    common = ex["common"]
    lines += ["    {", _c_block([common[nm] for nm in ("W_plate", "W_steer", "W_wheel", "W_moment", "D_damper")],
                                 [f"dx[{q0 + QUADRATURE_STATES.index(nm)}]"
                                  for nm in ("W_plate", "W_steer", "W_wheel", "W_moment", "D_damper")], "        "),
              "    }"]
    for nm, local in _BLOCK_QUADRATURES:
        lines.append(f"    dx[{q0 + QUADRATURE_STATES.index(nm)}] = {local};")
    # Work of the rear no-slip constraint's force while the plate moves:
    # u . (M du/dt - f) = -lambda . a0 (zero when a0 = 0, so skipped then).
    lines.append("    if (a0[0] != 0.0 || a0[1] != 0.0 || a0[2] != 0.0) {")
    lines.append(f"        double ud[{n}], pc = 0.0;")
    lines.append(f"        for (int i = 0; i < {n}; i++) {{ double s = t0[i]; for (int j = 0; j < {k}; j++) s += T[i * {k} + j] * r[j]; ud[i] = s; }}")
    lines.append(f"        for (int i = 0; i < {n}; i++) {{ double s = -f[i]; for (int j = 0; j < {n}; j++) s += M[i * {n} + j] * ud[j]; pc += u[i] * s; }}")
    lines.append(f"        dx[{q0 + QUADRATURE_STATES.index('W_plate')}] += pc;")
    lines.append("    }")
    lines += ["    if (out) {", *_c_outputs(ex, "        ", L), "    }"]
    lines.append(f"    for (int i = 0; i < {ns}; i++) if (!isfinite(dx[i])) return 2;")
    lines.append("    return 0;")
    lines.append("}")
    # Outputs at many samples in one call (post-processing a trajectory).
    lines += ["int wk_slip_outputs(int n, const double *t, const double *x, const double *p, double *out)", "{",
              f"    double dx[{ns}];",
              "    for (int i = 0; i < n; i++) {",
              f"        int status = wk_slip_rhs(t[i], x + (long)i * {ns}, p, dx, out + (long)i * {len(L.OUTPUT_NAMES)});",
              "        if (status) return status;", "    }", "    return 0;", "}"]
    # The same outputs without the dynamics: the prologue without Kane's mass matrix, forcing and solve
    # (nothing in the outputs needs the accelerations), bit for bit the right-hand side's outputs; the optional
    # groups only where a call asks for them (a study's summary reads none of them).
    lines += _c_outputs_some(ex, L)
    lines += ["int wk_slip_outputs_only(int n, const double *t, const double *x, const double *p, double *out)", "{",
              "    for (int i = 0; i < n; i++) {",
              f"        int status = wk_slip_sample_some(t[i], x + (long)i * {ns}, p, {layouts.EVERY_OPTIONAL_GROUP}, "
              f"out + (long)i * {len(L.OUTPUT_NAMES)});",
              "        if (status) return status;", "    }", "    return 0;", "}"]
    lines += ["int wk_slip_outputs_some(int n, const double *t, const double *x, const double *p, int groups, "
              "double *out)", "{",
              "    for (int i = 0; i < n; i++) {",
              f"        int status = wk_slip_sample_some(t[i], x + (long)i * {ns}, p, groups, "
              f"out + (long)i * {len(L.OUTPUT_NAMES)});",
              "        if (status) return status;", "    }", "    return 0;", "}"]
    # Jacobian by forward differences over the dynamic states (the
    # quadratures feed nothing back and nothing depends on the ignorable
    # coordinates: their columns are exactly zero).
    quadratures = f"(j >= {X[QUADRATURE_STATES[0]]} && j <= {X[QUADRATURE_STATES[-1]]})"
    skipped = " || ".join([quadratures] + [f"j == {X[name]}" for name in IGNORABLE])
    lines += ["int wk_slip_jacobian(double t, const double *x, const double *p, const double *scale, double *J)", "{",
              f"    double f0[{ns}], f1[{ns}], xp[{ns}];",
              "    int status = wk_slip_rhs(t, x, p, f0, 0);", "    if (status) return status;",
              "    memcpy(xp, x, sizeof xp);",
              f"    for (int j = 0; j < {ns}; j++) {{",
              f"        if ({skipped}) {{ for (int i = 0; i < {ns}; i++) J[i * {ns} + j] = 0.0; continue; }}",
              "        volatile double moved = x[j] + 1.4901161193847656e-08 * fmax(fabs(x[j]), scale[j]);",
              "        const double h = moved - x[j];",
              "        xp[j] = moved;",
              "        status = wk_slip_rhs(t, xp, p, f1, 0);", "        if (status) return status;",
              f"        for (int i = 0; i < {ns}; i++) J[i * {ns} + j] = (f1[i] - f0[i]) / h;",
              "        xp[j] = x[j];", "    }", "    return 0;", "}"]
    # Mass matrix, constraint matrix and offset (the plate stop's impulse).
    stage1, mass = ex["stage1"], list(ex["stage2"]["M"])
    lines += ["int wk_slip_impulse_terms(double t, const double *x, const double *p, double *M, double *A, double *a0)",
              "{", *_parameter_locals(list(stage1["A"]) + list(stage1["a0"]) + mass, L=L)]
    for s in sy["q"]:
        lines.append(f"    const double {s.name} = x[{L.X[s.name]}];")
    lines += ["    {", _c_block(list(stage1["A"]) + list(stage1["a0"]),
                                 [f"A[{i}]" for i in range(m * n)] + [f"a0[{i}]" for i in range(m)], "        "), "    }",
              "    {", _c_block(mass, [f"M[{i}]" for i in range(n * n)], "        "), "    }",
              "    return 0;", "}"]
    # Cornering stiffness -dF/dslip at zero slip and camber per wheel (the carcass stiffness' numerator).
    lines += ["int wk_slip_cornering_stiffness(double fzr, double fzf, const double *p, double *out)", "{",
              "    double g[4];", "    wk_fyg_r(0.0, 0.0, fzr, p, g); out[0] = -g[1];",
              "    wk_fyg_f(0.0, 0.0, fzf, p, g); out[1] = -g[1];", "    return 0;", "}"]
    # The friction-limit outputs at n points of one wheel (0 rear, 1 front), by the search alone or not.
    lines += ["int wk_slip_friction_limits(int n, int wheel, const double *camber, const double *fz, const double *F, "
              "const double *p, int search, double *out)", "{",
              "    for (int i = 0; i < n; i++)",
              "        out[i] = wheel ? wk_fylim_f_by(camber[i], fz[i], F[i], p, search) "
              ": wk_fylim_r_by(camber[i], fz[i], F[i], p, search);", "    return 0;", "}"]
    # The undamped carcass' patch slips at n points of one wheel, its blend's common branch found either way.
    lines += ["int wk_slip_carcass_slips(int n, int wheel, const double *camber, const double *gl, const double *fz, "
              "const double *F, const double *p, int search, double *out)", "{",
              "    for (int i = 0; i < n; i++)",
              "        (wheel ? wk_carcass_slips_f : wk_carcass_slips_r)(camber[i], gl[i], fz[i], F[i], p, search, "
              "out + 2 * i);", "    return 0;", "}"]
    lines.append(f"int wk_slip_sizes(int *sizes) {{ sizes[0] = {ns}; sizes[1] = {len(L.PARAMETER_NAMES)}; "
                 f"sizes[2] = {len(L.OUTPUT_NAMES)}; sizes[3] = {nd}; return 0; }}")
    return "\n".join(lines) + "\n"


# ----------------------------------------------------------------------- NumPy

def numpy_source(part_names=()):
    """NumPy module source of the same expressions (oracle and baseline), of the model with ``part_names``."""
    L = layouts.for_parts(part_names)
    ex = _expressions(part_names)
    sy = ex["symbols"]
    t = [sy["t"]]
    st2 = ex["stage2"]
    parts = [
        '"""Generated by whipple_kick.model.slip (NumPy oracle); do not edit."""',
        "import functools\nimport numpy",
        codegen.numpy_function("stage1", [("t", t), ("q", sy["q"]), ("p", sy["p"])],
                               [ex["stage1"]["A"], ex["stage1"]["a0"]], doc="Constraint matrix and offset."),
        codegen.numpy_function("reflex_input", [("t", t), ("q", sy["q"]), ("u", sy["u"]), ("p", sy["p"])],
                               [sm.Matrix([ex["reflex_input"]])], doc="The reflex's undelayed torque."),
        codegen.numpy_function("stage2", [("t", t), ("q", sy["q"]), ("u", sy["u"]), ("r", sy["reflex"]),
                                          ("p", sy["p"])],
                               [st2["M"], st2["f0"], st2["G"], st2["b"], st2["kinematics"]],
                               doc="Mass matrix, forcing without tyre loads, its tyre-load derivative, "
                                   "constraint remainder, tyre-block inputs."),
    ]
    for name in transient.symbolic():
        parts.append(codegen.numpy_function(
            f"tyre_{name}", [("t", t), ("k", sy["kinematics"]), ("s", sy["s"][name]), ("p", sy["p"])],
            [sm.Matrix(_block_list(ex["blocks"]["inline"][name]))], doc=f"Tyre block of {name}."))
    common = ex["common"]
    parts.append(codegen.numpy_function(
        "common", [("t", t), ("q", sy["q"]), ("u", sy["u"]), ("k", sy["kinematics"]), ("a", sy["applied"]),
                   ("p", sy["p"])],
        [sm.Matrix([common[nm] for nm in ("W_plate", "W_steer", "W_wheel", "W_moment", "D_damper")])],
        doc="Form-independent quadrature rates."))
    block_symbols = [sm.Symbol(n, real=True) for n in _BLOCK_EXTRAS + _LIMIT_OUTPUTS]
    parts.append(codegen.numpy_function(
        "outputs", [("t", t), ("q", sy["q"]), ("u", sy["u"]), ("k", sy["kinematics"]), ("a", sy["applied"]),
                    ("e", block_symbols), ("r", sy["reflex_outputs"]), ("p", sy["p"])],
        [sm.Matrix(_output_list(ex, "inline", L))], doc="Named outputs after the speeds."))
    return "\n\n".join(parts)


def numpy_module(part_names=()):
    """The generated NumPy oracle module of the model with ``part_names`` (cached like the C library)."""
    return _numpy_module(tuple(part_names), transient.fingerprint())


@functools.cache
def _numpy_module(part_names, forms):
    """:func:`numpy_module` with the declared tyre forms whose fingerprint is ``forms``."""
    L = layouts.for_parts(part_names)
    key = cache.source_hash(_SOURCES, extra=f"numpy {L.fingerprint()} forms {forms}")
    path = cache.build_once(f"slip_numpy_{L.key}_{key}.py", lambda tmp: tmp.write_text(numpy_source(part_names)))
    return cache.load_module(path, f"whipple_kick_generated_slip_{L.key.replace('+', '_')}_{key}")


def numpy_rhs(t, x, p, model, with_outputs=False):
    """Right-hand side of ``model`` evaluated with NumPy (slow; the oracle for the C code).

    ``p`` is its parameter vector (:func:`whipple_kick.model.slip.parameter_vector`) and ``model`` the
    :class:`whipple_kick.model.slip.Model` it is for (``params.model``): its parts, delay filter and tyre form.
    """
    part_names = model.parts
    L = model.layout
    if len(x) != len(L.STATE_NAMES) or len(p) != len(L.PARAMETER_NAMES):
        raise ValueError(f"numpy_rhs: {len(x)} states and {len(p)} parameters are not the layout {L.key!r}'s")
    mod = numpy_module(part_names)
    q = x[[L.X[n] for n in L.COORDINATES]]
    u_ind = x[[L.X[n] for n in L.INDEPENDENT]]
    s = x[[X[n] for n in PATCH_STATES]]
    z = x[[L.X[n] for n in L.REFLEX_STATES]] if L.delayed_reflex else np.zeros(len(REFLEX_STATES))
    name = model.transient
    tau = p[P["reflex_delay"]]
    # numpy.select evaluates every branch of a Piecewise, including the
    # unloaded-tyre branch's 0/0 that C never takes; the selected values are finite.
    with np.errstate(invalid="ignore", divide="ignore"):
        A, a0 = mod.stage1([t], q, p)
        u = L.PARTITION.dependent_speeds(A, a0, u_ind)
        r_in = mod.reflex_input([t], q, u, p)[0][0]
        t_reflex = reflex.output(z, r_in, tau)
        M, f0, G, b, kin = mod.stage2([t], q, u, [t_reflex], p)
        branches = {"r": {}, "f": {}}   # each wheel's curve scanned once per camber (block and limit share it)
        block = (_carcass_block(kin, s, p, branches) if transient.FORMS[name].wheel is None
                 else getattr(mod, f"tyre_{name}")([t], kin, s, p)[0])
        applied = block[:4]
        f = f0 + G @ applied
        udot = L.PARTITION.accelerations(M, f, A, b)
        rates = np.zeros(len(QUADRATURE_STATES))
        common = mod.common([t], q, u, kin, applied, p)[0]
        for value, nm in zip(common, ("W_plate", "W_steer", "W_wheel", "W_moment", "D_damper"), strict=True):
            rates[QUADRATURE_STATES.index(nm)] = value
        extras = dict(zip(_BLOCK_EXTRAS, block[8:], strict=True))
        for nm, local in _BLOCK_QUADRATURES:
            rates[QUADRATURE_STATES.index(nm)] = extras[local]
        if np.any(a0 != 0.0):
            rates[QUADRATURE_STATES.index("W_plate")] += kane.constraint_power(M, f, u, udot)
        dx = np.empty(len(L.STATE_NAMES))
        dx[[L.X[n] for n in L.COORDINATES]] = u
        dx[[L.X[n] for n in L.INDEPENDENT]] = udot[L.PARTITION.ind]
        dx[[X[n] for n in PATCH_STATES]] = block[4:8]
        if L.delayed_reflex:
            dx[[L.X[n] for n in L.REFLEX_STATES]] = reflex.rates(z, r_in, tau)
        dx[[X[n] for n in QUADRATURE_STATES]] = rates
        if with_outputs:
            limits = [_reference_limit(p, w, kin, applied[k], branches[w]) for k, w in enumerate("rf")]
            outputs = mod.outputs([t], q, u, kin, applied, np.concatenate([block[8:], limits]), [t_reflex, r_in],
                                  p)[0]
            return dx, np.concatenate([u[:len(SPEEDS)], outputs])
    return dx


def _reference_curves(p, wheel):
    """(F_ss, M_ss) of one wheel from a parameter array, by the NumPy Magic Formula (blend and scale applied)."""
    w, mu, lam = p[P[f"w{wheel}"]], p[P[f"mu{wheel}"]], p[P[f"lam{wheel}"]]
    sets = [(1.0 - w, [p[P[f"a{wheel}{k}_{i}"]] for i in range(14)], [p[P[f"c{wheel}{k}_{i}"]] for i in range(18)])
            for k in (1, 2)]
    sets[1] = (w, *sets[1][1:])

    def fy(slip, camber, fz):
        return lam * sum(wt * magic_formula.lateral_force_numpy(slip, camber, fz, a, mu) for wt, a, _ in sets if wt)

    def mz(slip, camber, fz):
        return lam * sum(wt * magic_formula.aligning_moment_numpy(slip, camber, fz, c, mu) for wt, _, c in sets if wt)
    return fy, mz


def _grip(p, wheel, camber, fz):
    """Whether every coefficient set of a wheel has a positive peak factor D at this load (NumPy factors)."""
    w, mu = p[P[f"w{wheel}"]], p[P[f"mu{wheel}"]]
    sets = [k for k, weight in ((1, 1.0 - w), (2, w)) if weight]
    return all(magic_formula.lateral_force_factors_numpy(camber, max(fz, carcass.FZ_SHAPE_FLOOR),
                                                         [p[P[f"a{wheel}{k}_{i}"]] for i in range(14)], mu)["D"] > 0
               for k in sets)


def _kin_of(kin, wheel):
    return tuple(float(kin[_KINEMATICS.index(f"{n}_{wheel}")]) for n in ("vsy", "vx", "camber", "fz"))


def _carcass_block(kin, s, p, branches):
    """Both wheels' carcass blocks by :func:`whipple_kick.model.carcass.reference_block`, in the C block's layout."""
    sliding = carcass.SLIDING_LAWS[int(p[P["carcass_sliding"]])]
    extras = dict.fromkeys(_BLOCK_EXTRAS, 0.0)
    out = {}
    for k, wheel in enumerate("rf"):
        fy, mz = _reference_curves(p, wheel)
        vsy, vx, camber, fz = _kin_of(kin, wheel)
        cc, dc = p[P[f"cc{wheel}"]], p[P[f"dc{wheel}"]]
        o = carcass.reference_block(fy, mz, vsy, vx, camber, fz, s[k], s[k + 2], cc, dc, p[P[f"sig{wheel}"]],
                                    sliding, viscosity=p[P["carcass_viscosity"]], grip=_grip(p, wheel, camber, fz),
                                    branches=branches[wheel])
        out[wheel] = o
        f0 = float(fy(0.0, camber, fz)) if fz > 0 else 0.0
        vslide = vsy + o["rate"]
        extras["W0"] += f0 * vslide
        extras["D_slide"] += -(o["F"] - f0) * vslide
        extras[f"P_carcass_{wheel}"] = cc * s[k] * o["rate"]
        extras["D_carcass"] += dc * o["rate"] ** 2
        extras[f"sigma_{wheel}"] = p[P[f"sig{wheel}"]]
        extras[f"patch_slip_{wheel}"] = o["slip"]
    r, f = out["r"], out["f"]
    return np.array([r["F"], f["F"], r["M"], f["M"], r["rate"], f["rate"], r["gl_rate"], f["gl_rate"],
                     *(extras[n] for n in _BLOCK_EXTRAS)])


def _reference_limit(p, wheel, kin, force, branches):
    """The friction limit [N] on the side of ``force`` by the reference scan (an output; ``branches`` as
    :func:`whipple_kick.model.carcass.reference_block`'s, shared with the wheel's block)."""
    fy, _ = _reference_curves(p, wheel)
    vsy, vx, camber, fz = _kin_of(kin, wheel)
    if fz <= 0 or not _grip(p, wheel, camber, fz):
        return 0.0
    if (camber, fz) not in branches:
        branches[camber, fz] = carcass.reference_branch(fy, camber, fz)
    lo, hi = branches[camber, fz]
    return float(fy(lo, camber, fz)) if force >= 0 else -float(fy(hi, camber, fz))


# ------------------------------------------------------------------ the build

def metadata(key, compiler, flags, L=layouts.BASE):
    """Plain-data description of the compiled library, written beside it at build time.

    The layouts the C code was generated for (states, parameters, outputs,
    by position), each name's unit and description (from the symbol
    registry and :data:`whipple_kick.model.slip.OUTPUTS`), and what generated it.
    :func:`whipple_kick.model.slip.library` refuses a library whose metadata does
    not match the running code's layouts.
    """
    def described(name):
        info = S.REGISTRY.get(name)
        return {"name": name, "unit": info.unit, "description": info.description} if info else {"name": name}

    outputs = [described(n) if n in L.SPEEDS else {"name": n, "unit": L.OUTPUTS[n][0],
                                                     "description": L.OUTPUTS[n][1]} for n in L.OUTPUT_NAMES]
    return {
        "model": "whipple_kick slip model",
        "key": key,
        "parts": [p.name for p in L.parts],
        "layout": L.record(),
        "states": [described(n) for n in L.STATE_NAMES],
        "parameters": [described(n) for n in L.PARAMETER_NAMES],
        "outputs": outputs,
        "generated_with": {"sympy": cache.sympy_version(), "python": sys.version.split()[0],
                           "compiler": compiler, "flags": list(flags)},
    }


def build_library(path, key, compiler, flags, part_names=(), delayed_reflex=False):
    """Generate, compile and describe the slip model: the library at ``path``, source and metadata beside it.

    Says so first in a :class:`~whipple_kick.errors.PerformanceWarning` (the commands print it as one line): the
    build happens once per version and takes some 20-60 s, by machine and load (README.md gives the
    measurements and their machines).

    Parameters
    ----------
    path : pathlib.Path
        Where to write the shared library (a temporary name in the cache;
        :func:`whipple_kick.model.cache.build_once` renames it into place).
    key : str
        The cache key (names the source and metadata files, with the parts).
    compiler : str
        Path of the C compiler.
    flags : sequence of str
        Compiler flags.
    part_names : tuple of str
        The model's declared parts (:mod:`whipple_kick.model.parts`).
    delayed_reflex : bool
        Whether the model has the reflex's delay filter.

    Raises
    ------
    BuildError
        The compiler failed (one line; its full output saved beside the source).
    """
    what = " with " + ", ".join(part_names + ("the reflex delay",) * delayed_reflex) if part_names or delayed_reflex else ""
    warnings.warn(f"building the slip model{what} once for this version (SymPy derivation, C code "
                  "generation and compilation; 20-60 s)...", PerformanceWarning, stacklevel=2)
    folder = cache.cache_dir()
    src_path = folder / f"slip_{key}.c"
    fileio.write_atomic(src_path, c_source(part_names, delayed_reflex), private=True)   # kept next to the library for inspection
    compilers.compile_shared(compiler, flags, src_path, path, libraries=("-lm",), log=folder / f"slip_{key}.build.log")
    fileio.write_atomic(folder / f"slip_{key}.json", json.dumps(metadata(key, compiler, flags, layouts.for_parts(part_names, delayed_reflex)), indent=1) + "\n",
                        private=True)
