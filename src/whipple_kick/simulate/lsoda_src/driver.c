/* The fast path's chunk loop in C: SciPy's own LSODA (lsoda.c, vendored from SciPy 1.17.1) called exactly as
 * scipy.integrate.odeint calls it, with the compiled slip model's right-hand side and Jacobian by function pointer.
 *
 * One call integrates the consecutive chunks of one smooth piece (whipple_kick.simulate.lsoda_c.fast_chunks)
 * until one of them needs the careful path (a limit passed, LSODA in trouble, a non-finite sample, the budget
 * exceeded): the Python path's per-evaluation crossing and per-chunk odeint set-up are gone, the numbers are
 * not changed (each chunk is a fresh LSODA run with odeint's options, the same LAPACK routines).
 *
 * LAPACK: LSODA factors its iteration matrix with dgetrf/dgetrs. The pointers are SciPy's own
 * (scipy.linalg.cython_lapack, the library odeint's LSODA links to), set once by wk_lsoda_set_lapack, so that no
 * BLAS is needed at build time and the factorisation is the one odeint uses, bit for bit.
 */
#include <stdlib.h>
#include <string.h>
#include <math.h>

/* Built with -fvisibility=hidden (LSODA's own symbols stay inside): the WK_EXPORT functions are its interface. */
#define WK_EXPORT __attribute__((visibility("default")))

typedef void (*getrf_t)(int *, int *, double *, int *, int *, int *);
typedef void (*getrs_t)(char *, int *, int *, double *, int *, int *, double *, int *, int *);
typedef void (*gbtrf_t)(int *, int *, int *, int *, double *, int *, int *, int *);
typedef void (*gbtrs_t)(char *, int *, int *, int *, int *, double *, int *, int *, double *, int *, int *);

static getrf_t p_getrf;
static getrs_t p_getrs;
static gbtrf_t p_gbtrf;
static gbtrs_t p_gbtrs;

/* lsoda.c calls the Fortran names; they are renamed to these forwarders (no symbol clash with any BLAS). */
#define dgetrf_ wk_lsoda_dgetrf
#define dgetrs_ wk_lsoda_dgetrs
#define dgbtrf_ wk_lsoda_dgbtrf
#define dgbtrs_ wk_lsoda_dgbtrs
#define daxpy_ wk_lsoda_daxpy
#define dcopy_ wk_lsoda_dcopy
#define dscal_ wk_lsoda_dscal
#define zaxpy_ wk_lsoda_zaxpy
#define zcopy_ wk_lsoda_zcopy
#define zscal_ wk_lsoda_zscal
#define zgbtrf_ wk_lsoda_zgbtrf
#define zgbtrs_ wk_lsoda_zgbtrs
#define zgetrf_ wk_lsoda_zgetrf
#define zgetrs_ wk_lsoda_zgetrs
#include "lsoda.c"

void wk_lsoda_dgetrf(int *m, int *n, double *a, int *lda, int *ipiv, int *info)
{ p_getrf(m, n, a, lda, ipiv, info); }
void wk_lsoda_dgetrs(char *tr, int *n, int *nrhs, double *a, int *lda, int *ipiv, double *b, int *ldb, int *info)
{ p_getrs(tr, n, nrhs, a, lda, ipiv, b, ldb, info); }
void wk_lsoda_dgbtrf(int *m, int *n, int *kl, int *ku, double *ab, int *ldab, int *ipiv, int *info)
{ p_gbtrf(m, n, kl, ku, ab, ldab, ipiv, info); }
void wk_lsoda_dgbtrs(char *tr, int *n, int *kl, int *ku, int *nrhs, double *ab, int *ldab, int *ipiv, double *b,
                     int *ldb, int *info)
{ p_gbtrs(tr, n, kl, ku, nrhs, ab, ldab, ipiv, b, ldb, info); }

WK_EXPORT void wk_lsoda_set_lapack(void *getrf, void *getrs, void *gbtrf, void *gbtrs)
{
    p_getrf = (getrf_t)getrf;
    p_getrs = (getrs_t)getrs;
    p_gbtrf = (gbtrf_t)gbtrf;
    p_gbtrs = (gbtrs_t)gbtrs;
}

/* wk_slip_rhs(t, x, p, dx, out) and wk_slip_jacobian(t, x, p, scale, J) of the generated model; 0 = success. */
typedef int (*rhs_fn)(double, const double *, const double *, double *, double *);
typedef int (*jac_fn)(double, const double *, const double *, const double *, double *);

typedef struct {
    rhs_fn rhs;
    jac_fn jac;
    const double *p, *scale;
    double *J;              /* row-major Jacobian of the model, transposed into LSODA's column-major matrix */
    int i1, i2;             /* |x[i1]| > lim1 or |x[i2]| > lim2 ends the chunk (the Python guard's test) */
    double lim1, lim2;
    int stop;               /* set by a call that ends the chunk: 1 a limit passed, 2 a model failure */
    int guard;              /* test the limits in f (the fast path); the careful path's f does not */
    long long nfev;         /* calls of f, the failing one included (what scipy's LSODA.nfev counts) */
    int failed_in;          /* the model failure's function: 1 the right-hand side, 2 the Jacobian */
    double failed_t, *failed_x;   /* and where it failed (the careful path reports it), or NULL */
} context;

/* LSODA's f has no user pointer: the context of the running call (one per thread; ctypes releases the GIL). */
static __thread context *current;

/* A model failure ends the call: where it happened is kept for the careful path's message. */
static void model_failed(context *c, int in, double t, const double *y, int n)
{
    c->stop = 2;
    c->failed_in = in;
    c->failed_t = t;
    if (c->failed_x)
        memcpy(c->failed_x, y, sizeof(double) * n);
}

static void f_thunk(int *neq, double *t, double *y, double *ydot)
{
    context *c = current;
    c->nfev++;
    if (c->guard && (fabs(y[c->i1]) > c->lim1 || fabs(y[c->i2]) > c->lim2)) {
        c->stop = 1;
        *neq = -1;
        return;
    }
    if (c->rhs(*t, y, c->p, ydot, NULL)) {
        model_failed(c, 1, *t, y, *neq);
        *neq = -1;
    }
}

static void jac_thunk(int *neq, double *t, double *y, int *ml, int *mu, double *pd, int *nrowpd)
{
    (void)ml;
    (void)mu;
    context *c = current;
    int n = *neq;
    if (c->jac(*t, y, c->p, c->scale, c->J)) {
        model_failed(c, 2, *t, y, n);
        *neq = -1;
        return;
    }
    for (int j = 0; j < n; j++)   /* odeint with col_deriv=False: pd[i + j nrowpd] = J[i][j] */
        for (int i = 0; i < n; i++)
            pd[i + j * *nrowpd] = c->J[i * n + j];
}

/* Whether all count values are finite (odeint's np.all(np.isfinite(y))). A sum of finite values is finite unless
 * it overflows, and a NaN or an infinity makes every sum it enters NaN or infinite: so the values are summed (in
 * two-lane vectors of GCC's and Clang's vector extensions, four of them: about one instruction per value, a
 * fifth of a test value by value) and looked at one by one only where the sum is not finite. */
static int all_finite(const double *v, long count)
{
    typedef double pair __attribute__((vector_size(2 * sizeof(double))));
    pair s0 = {0.0, 0.0}, s1 = s0, s2 = s0, s3 = s0, a, b, c, d;
    long i = 0;
    for (; i + 8 <= count; i += 8) {
        memcpy(&a, v + i, sizeof a);
        memcpy(&b, v + i + 2, sizeof b);
        memcpy(&c, v + i + 4, sizeof c);
        memcpy(&d, v + i + 6, sizeof d);
        s0 += a;
        s1 += b;
        s2 += c;
        s3 += d;
    }
    s0 = (s0 + s1) + (s2 + s3);
    double sum = s0[0] + s0[1];
    for (; i < count; i++)
        sum += v[i];
    if (isfinite(sum))
        return 1;
    for (i = 0; i < count; i++)
        if (!isfinite(v[i]))
            return 0;
    return 1;
}

/* all_finite for the tests (tests/simulate/test_lsoda_c.py). */
WK_EXPORT int wk_lsoda_all_finite(const double *v, long count)
{
    return all_finite(v, count);
}

/* One chunk as odeint(f, x, times, Dfun=jac, rtol, atol, mxstep=mxstep, full_output=True) runs it.
 * Rows 0..m-1 of y get the states at times (row 0 = x). Returns 0 on success (odeint's "Integration successful."),
 * 1 otherwise; nfe, nje: LSODA's counters at the end (info["nfe"][-1], info["nje"][-1]). */
static int one_chunk(context *c, int n, const double *x, const double *times, int m, double rtol, const double *atol,
                     int mxstep, double *rwork, int lrw, int *iwork, int liw, double *y, int *nfe, int *nje)
{
    lsoda_common_struct_t S;
    memset(&S, 0, sizeof S);
    memset(rwork, 0, sizeof(double) * lrw);
    memset(iwork, 0, sizeof(int) * liw);
    iwork[0] = -1;          /* ml, mu: odeint's defaults (full Jacobian) */
    iwork[1] = -1;
    /* odeint's optional inputs (iopt = 1 as mxstep != 0): h0, hmax, hmin 0, ixpr 0, mxhnil 0, mxordn 12, mxords 5 */
    iwork[4] = 0;
    iwork[5] = mxstep;
    iwork[6] = 0;
    iwork[7] = 12;
    iwork[8] = 5;
    int itol = 2, itask = 1, istate = 1, iopt = 1;
    double rt = rtol, t = times[0];
    double *yy = y + (size_t)(m - 1) * n;   /* LSODA's vector, integrated in place as in odeint (the last row) */
    memcpy(y, x, sizeof(double) * n);
    memcpy(yy, x, sizeof(double) * n);
    c->stop = 0;
    int k = 1;
    while (k < m && istate > 0) {
        double tout = times[k];
        lsoda(f_thunk, n, yy, &t, &tout, itol, &rt, (double *)atol, &itask, &istate, &iopt, rwork, lrw, iwork, liw,
              jac_thunk, 1, &S);
        if (c->stop)
            return 1;
        if (k < m - 1)
            memcpy(y + (size_t)k * n, yy, sizeof(double) * n);
        k++;
    }
    *nfe = iwork[11];
    *nje = iwork[12];
    if (istate <= 0)
        return 1;
    return !all_finite(y, (long)m * n);
}

/* Integrate the chunks [grid[cuts[k]], grid[cuts[k+1]]] one after another from x, the fast path of
 * whipple_kick.simulate.lsoda.integrate. Stops before the first chunk that the careful path must redo: LSODA
 * failing or a limit passed inside it, a non-finite sample, a sample with |x[i1]| >= lim1 or |x[i2]| >= lim2, or
 * spent + its evaluations over allowance + per_second max(0, its end - t_start).
 *
 * out: rows cuts[0]..cuts[last done + 1] of the grid's states (row cuts[0] = x); the rows of the chunk that stopped
 * the loop (up to cuts[last done + 2]) are written too, with no meaning. x is left the state at the end of the last
 * chunk done; counts[0..2] (nfev, njev, evaluations) are added to. Returns the number of chunks done, or -1 when
 * memory ran out. */
WK_EXPORT int wk_lsoda_fast_chunks(void *rhs, void *jac, const double *p, const double *scale, int n,
                         const double *grid, const int *cuts, int ncuts, double *x, double rtol, const double *atol,
                         int mxstep, int i1, double lim1, int i2, double lim2, int jac_evaluations,
                         double allowance, double per_second, double t_start, long long *counts, double *out)
{
    /* odeint's work array sizes (compute_lrw_liw, jt = 1, mxordn 12, mxords 5) */
    int lrn = 20 + n * 13 + 3 * n, lrs = 20 + n * 6 + 3 * n + n * n + 2;
    int lrw = lrn > lrs ? lrn : lrs, liw = 20 + n;
    double *rwork = malloc(sizeof(double) * lrw), *J = malloc(sizeof(double) * n * n);
    int *iwork = malloc(sizeof(int) * liw);
    if (!rwork || !J || !iwork) {
        free(rwork); free(J); free(iwork);
        return -1;
    }
    context c = {(rhs_fn)rhs, (jac_fn)jac, p, scale, J, i1, i2, lim1, lim2, 0, 1, 0, 0, 0.0, NULL};
    context *saved = current;
    current = &c;
    int done = 0;
    for (int k = 0; k + 1 < ncuts; k++) {
        int m = cuts[k + 1] - cuts[k] + 1, nfe = 0, nje = 0;
        const double *times = grid + cuts[k];
        /* Straight into the caller's rows (no copy of a chunk's states, the size of the result): a chunk that
         * stops the loop leaves its rows written, rows the caller does not read. */
        double *y = out + (size_t)cuts[k] * n;
        if (one_chunk(&c, n, x, times, m, rtol, atol, mxstep, rwork, lrw, iwork, liw, y, &nfe, &nje))
            break;
        long long used = (long long)nfe + (long long)nje * jac_evaluations;
        if ((double)(counts[2] + used) > allowance + per_second * fmax(0.0, times[m - 1] - t_start))
            break;
        int inside = 1;   /* every sample strictly inside both limits (the Python _within_limits) */
        for (int r = 0; r < m && inside; r++)
            inside = fabs(y[r * n + i1]) < lim1 && fabs(y[r * n + i2]) < lim2;
        if (!inside)
            break;
        counts[0] += nfe;
        counts[1] += nje;
        counts[2] += used;
        memcpy(x, y + (size_t)(m - 1) * n, sizeof(double) * n);
        done++;
    }
    current = saved;
    free(rwork); free(J); free(iwork);
    return done;
}

/* ------------------------------------------------------------------------------------------------------------
 * The careful path in C: one chunk with LSODA stepped one step at a time, the fall event and the budget, as
 * whipple_kick.simulate.lsoda._careful_chunk does it with scipy.integrate.LSODA from Python:
 *
 *  - LSODA as scipy's LSODA solver object sets it up and steps it (scipy.integrate._ode.lsoda.reset and
 *    _ivp/lsoda.py of SciPy 1.17.1): work arrays of its sizes, iopt = 1 with ode's defaults (nsteps 500, orders
 *    12 and 5, no step bounds), itask = 5 (one step, never past tcrit = the chunk's end), the Jacobian of the
 *    model (jt = 1), istate 1 then 2 with the common block kept between steps; so the same steps, evaluations
 *    and Jacobians as the Python path;
 *  - the samples and the fall time from each step's interpolant, the polynomial SciPy's LsodaDenseOutput builds
 *    from LSODA's Nordsieck history (the order of the last step, its last column rescaled when the order drops),
 *    evaluated by Horner's rule as LSODA's own intdy does; np.dot sums the same terms in another order, so the
 *    samples and the fall time agree with the Python path to round-off (tests/simulate/test_lsoda_c.py);
 *  - the fall time by SciPy's brentq (scipy/optimize/Zeros/brentq.c of SciPy 1.17.1, Charles Harris; BSD,
 *    LICENSE-scipy.txt), xtol = rtol = 4 eps, at most 100 iterations, as the Python path calls it;
 *  - the evaluation budget and the stall window checked after every step, as in Python. */

/* How a careful chunk ended (whipple_kick.simulate.lsoda_c.CAREFUL_STATUS lists the same codes). */
enum {
    CAREFUL_COMPLETED = 0, CAREFUL_FELL = 1, CAREFUL_LSODA = 2, CAREFUL_MODEL = 3, CAREFUL_BUDGET = 4,
    CAREFUL_STALL = 5, CAREFUL_ROOT_NAN = 6, CAREFUL_ROOT_SIGNS = 7, CAREFUL_ROOT_ITERATIONS = 8,
    CAREFUL_NO_MEMORY = -1
};

/* The interpolant of the last step: sum_j yh[:, j] ((t - tn) / h)^j, j = 0..order (yh column-major, n rows). */
typedef struct {
    int n, order;
    double tn, h;
    double *yh;
} interpolant;

/* SciPy's LSODA._dense_output_impl: the Nordsieck columns 0..nqu of rwork[20:], the last one rescaled to the
 * step h = rwork[11] when the order to be tried next (iwork[14]) is below the last step's (iwork[13]). */
static void interpolant_of_step(interpolant *d, const double *rwork, const int *iwork, double tn)
{
    int order = iwork[13], n = d->n;
    d->order = order;
    d->tn = tn;
    d->h = rwork[11];
    memcpy(d->yh, rwork + 20, sizeof(double) * (size_t)(order + 1) * n);
    if (iwork[14] < order) {
        double factor = pow(d->h / rwork[10], order);
        for (int i = 0; i < n; i++)
            d->yh[(size_t)order * n + i] *= factor;
    }
}

static void interpolate(const interpolant *d, double t, double *y)
{
    int n = d->n;
    double s = (t - d->tn) / d->h;
    const double *top = d->yh + (size_t)d->order * n;
    for (int i = 0; i < n; i++)
        y[i] = top[i];
    for (int j = d->order - 1; j >= 0; j--) {
        const double *col = d->yh + (size_t)j * n;
        for (int i = 0; i < n; i++)
            y[i] = col[i] + s * y[i];
    }
}

/* The event: the smaller margin of |x[i1]| to lim1 and |x[i2]| to lim2 (Python's min(a, b): b only if b < a). */
static double fall_margin(const context *c, const double *y)
{
    double a = c->lim1 - fabs(y[c->i1]), b = c->lim2 - fabs(y[c->i2]);
    return b < a ? b : a;
}

typedef struct {
    const context *c;
    const interpolant *d;
    double *y;
    int nan;                /* the margin was NaN at nan_t: scipy's brentq raises there */
    double nan_t;
} root_problem;

static double margin_at(double t, root_problem *r)
{
    interpolate(r->d, t, r->y);
    double g = fall_margin(r->c, r->y);
    if (isnan(g) && !r->nan) {
        r->nan = 1;
        r->nan_t = t;
    }
    return g;
}

#define BRENT_MIN(a, b) ((a) < (b) ? (a) : (b))

/* scipy/optimize/Zeros/brentq.c (SciPy 1.17.1) with f = the margin on the interpolant. Returns the root, and in
 * *status CAREFUL_FELL, or CAREFUL_ROOT_NAN / _SIGNS / _ITERATIONS where scipy's brentq raises. */
static double brentq_margin(root_problem *r, double xa, double xb, double xtol, double rtol, int iter, int *status)
{
    double xpre = xa, xcur = xb;
    double xblk = 0., fpre, fcur, fblk = 0., spre = 0., scur = 0., sbis;
    double delta, stry, dpre, dblk;
    *status = CAREFUL_FELL;
    fpre = margin_at(xpre, r);
    if (r->nan) { *status = CAREFUL_ROOT_NAN; return xpre; }
    fcur = margin_at(xcur, r);
    if (r->nan) { *status = CAREFUL_ROOT_NAN; return xcur; }
    if (fpre == 0)
        return xpre;
    if (fcur == 0)
        return xcur;
    if (signbit(fpre) == signbit(fcur)) {
        *status = CAREFUL_ROOT_SIGNS;
        return 0.;
    }
    for (int i = 0; i < iter; i++) {
        if (fpre != 0 && fcur != 0 && (signbit(fpre) != signbit(fcur))) {
            xblk = xpre;
            fblk = fpre;
            spre = scur = xcur - xpre;
        }
        if (fabs(fblk) < fabs(fcur)) {
            xpre = xcur;
            xcur = xblk;
            xblk = xpre;
            fpre = fcur;
            fcur = fblk;
            fblk = fpre;
        }
        delta = (xtol + rtol * fabs(xcur)) / 2;
        sbis = (xblk - xcur) / 2;
        if (fcur == 0 || fabs(sbis) < delta)
            return xcur;
        if (fabs(spre) > delta && fabs(fcur) < fabs(fpre)) {
            if (xpre == xblk) {
                stry = -fcur * (xcur - xpre) / (fcur - fpre);   /* interpolate */
            } else {   /* extrapolate */
                dpre = (fpre - fcur) / (xpre - xcur);
                dblk = (fblk - fcur) / (xblk - xcur);
                stry = -fcur * (fblk * dblk - fpre * dpre) / (dblk * dpre * (fblk - fpre));
            }
            if (2 * fabs(stry) < BRENT_MIN(fabs(spre), 3 * fabs(sbis) - delta)) {
                spre = scur;   /* good short step */
                scur = stry;
            } else {
                spre = sbis;   /* bisect */
                scur = sbis;
            }
        } else {
            spre = sbis;   /* bisect */
            scur = sbis;
        }
        xpre = xcur;
        fpre = fcur;
        if (fabs(scur) > delta)
            xcur += scur;
        else
            xcur += (sbis > 0 ? delta : -delta);
        fcur = margin_at(xcur, r);
        if (r->nan) { *status = CAREFUL_ROOT_NAN; return xcur; }
    }
    *status = CAREFUL_ROOT_ITERATIONS;
    return xcur;
}

typedef struct {
    long long used;         /* evaluations spent in the chunk after a step */
    double t;               /* the time that step reached */
} progress_mark;

/* One chunk of the careful path (whipple_kick.simulate.lsoda._careful_chunk) from x0 at times[0] to times[m-1].
 *
 * samples: rows 0..k-1 get the states at times[0..k-1] (row 0 = x0). end: [t, x (n)] the last time and state
 * reached (the fall's, if it fell; the last accepted step's, if it failed). failed_x (n): where the model failed.
 * counts (int64, 8): nfev, njev, evaluations (nfev + njev jac_evaluations), k, LSODA's istate, the evaluations
 * at the stall window's first mark, the failed model function (1 right-hand side, 2 Jacobian), for the messages.
 * report (double, 4): the last accepted step's time, its size, the time of the stall window's first mark,
 * the model failure's time or the root finder's NaN argument.
 * Returns a CAREFUL_* code. */
WK_EXPORT int wk_lsoda_careful_chunk(void *rhs, void *jac, const double *p, const double *scale, int n,
                                     const double *times, int m, const double *x0, double rtol, const double *atol,
                                     int i1, double lim1, int i2, double lim2, int jac_evaluations,
                                     double allowance, double per_second, double t_start, long long spent,
                                     long long stall_window, double stall_progress,
                                     double *samples, double *end, double *failed_x, long long *counts,
                                     double *report)
{
    /* scipy.integrate._ode.lsoda.reset's work array sizes (jt = 1, max orders 12 and 5) */
    int lrn = 20 + (12 + 4) * n, lrs = 22 + (5 + 4) * n + n * n;
    int lrw = lrn > lrs ? lrn : lrs, liw = 20 + n;
    int capacity = 64;
    double *rwork = calloc((size_t)lrw, sizeof(double)), *J = malloc(sizeof(double) * n * n);
    double *y = malloc(sizeof(double) * n), *y_ok = malloc(sizeof(double) * n);
    double *yh = malloc(sizeof(double) * (size_t)13 * n), *scratch = malloc(sizeof(double) * n);
    int *iwork = calloc((size_t)liw, sizeof(int));
    progress_mark *marks = malloc(sizeof(progress_mark) * capacity);
    int status = CAREFUL_NO_MEMORY;
    memset(counts, 0, sizeof(long long) * 8);
    memset(report, 0, sizeof(double) * 4);
    if (!rwork || !J || !y || !y_ok || !yh || !scratch || !iwork || !marks)
        goto done;

    memcpy(samples, x0, sizeof(double) * n);
    counts[3] = 1;
    context c = {(rhs_fn)rhs, (jac_fn)jac, p, scale, J, i1, i2, lim1, lim2, 0, 0, 0, 0, 0.0, failed_x};
    double g_old = fall_margin(&c, x0);
    end[0] = times[0];
    memcpy(end + 1, x0, sizeof(double) * n);
    if (g_old <= 0.0) {   /* already at or past a limit where the chunk starts: that is the fall */
        status = CAREFUL_FELL;
        goto done;
    }
    interpolant d = {n, 0, 0.0, 0.0, yh};
    double t_bound = times[m - 1], t = times[0], t_ok = times[0], t_old = times[0], rt = rtol;
    memcpy(y, x0, sizeof(double) * n);
    memcpy(y_ok, x0, sizeof(double) * n);
    rwork[0] = t_bound;     /* tcrit, for itask = 5 */
    iwork[5] = 500;         /* ode's nsteps */
    iwork[7] = 12;
    iwork[8] = 5;
    int itol = 2, itask = 5, istate = 1, iopt = 1, nxt = 1, head = 0, count = 1;
    long long njev = 0, used = 0;
    marks[0].used = 0;
    marks[0].t = times[0];
    lsoda_common_struct_t S;
    memset(&S, 0, sizeof S);
    context *saved = current;
    current = &c;
    for (;;) {
        if (t_ok == t_bound) {   /* OdeSolver.step at the bound: finished without a step (a chunk of no length) */
            for (; nxt < m; nxt++)
                memcpy(samples + (size_t)nxt * n, y_ok, sizeof(double) * n);
            status = CAREFUL_COMPLETED;
            break;
        }
        double tout = t_bound;
        lsoda(f_thunk, n, y, &t, &tout, itol, &rt, (double *)atol, &itask, &istate, &iopt, rwork, lrw, iwork, liw,
              jac_thunk, 1, &S);
        if (c.stop || istate < 0) {   /* the Python path's step() failing: the last accepted step is the end */
            status = c.stop ? CAREFUL_MODEL : CAREFUL_LSODA;
            counts[4] = istate;
            counts[6] = c.failed_in;
            report[0] = t_ok;
            report[3] = c.failed_t;
            end[0] = t_ok;
            memcpy(end + 1, y_ok, sizeof(double) * n);
            break;
        }
        istate = 2;
        t_old = t_ok;
        t_ok = t;
        memcpy(y_ok, y, sizeof(double) * n);
        njev = iwork[12];
        double t_new = t;
        end[0] = t;
        memcpy(end + 1, y, sizeof(double) * n);
        status = -2;   /* none yet */
        int have_interpolant = 0;
        double g_new = fall_margin(&c, y);
        if (g_old >= 0.0 && 0.0 >= g_new) {   /* |roll| rose through the limit (the event's direction) */
            interpolant_of_step(&d, rwork, iwork, t);
            have_interpolant = 1;
            root_problem r = {&c, &d, scratch, 0, 0.0};
            double eps = 2.220446049250313e-16;
            double t_fall = brentq_margin(&r, t_old, t_new, 4 * eps, 4 * eps, 100, &status);
            if (status != CAREFUL_FELL) {
                report[3] = r.nan_t;
                break;
            }
            t_new = t_fall;
            end[0] = t_fall;
            interpolate(&d, t_fall, end + 1);
        }
        g_old = g_new;
        int upto = nxt;
        while (upto < m && times[upto] <= t_new)
            upto++;
        if (upto > nxt) {
            if (!have_interpolant)
                interpolant_of_step(&d, rwork, iwork, t);
            for (; nxt < upto; nxt++)
                interpolate(&d, times[nxt], samples + (size_t)nxt * n);
        }
        if (status == -2 && t - t_bound >= 0)
            status = CAREFUL_COMPLETED;
        if (status != -2)
            break;
        used = c.nfev + njev * jac_evaluations;
        if (head + count == capacity) {   /* the marks of the window: drop the ones before head, or grow */
            if (head > 0) {
                memmove(marks, marks + head, sizeof(progress_mark) * count);
                head = 0;
            } else {
                progress_mark *more = realloc(marks, sizeof(progress_mark) * capacity * 2);
                if (!more) {
                    status = CAREFUL_NO_MEMORY;
                    break;
                }
                marks = more;
                capacity *= 2;
            }
        }
        marks[head + count].used = used;
        marks[head + count].t = t_new;
        count++;
        while (count > 1 && marks[head + 1].used <= used - stall_window) {
            head++;
            count--;
        }
        double simulated = t_new - t_start;
        if ((double)(spent + used) > allowance + per_second * (simulated > 0.0 ? simulated : 0.0))
            status = CAREFUL_BUDGET;
        else if (marks[head].used <= used - stall_window && t_new - marks[head].t < stall_progress)
            status = CAREFUL_STALL;
        if (status != -2) {
            report[0] = t_new;
            report[1] = fabs(t - t_old);
            report[2] = marks[head].t;
            counts[5] = marks[head].used;
            break;
        }
    }
    current = saved;
    counts[0] = c.nfev;
    counts[1] = njev;
    counts[2] = c.nfev + njev * jac_evaluations;
    counts[3] = nxt;
done:
    free(rwork); free(J); free(y); free(y_ok); free(yh); free(scratch); free(iwork); free(marks);
    return status;
}
