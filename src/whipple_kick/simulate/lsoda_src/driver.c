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

/* Built with -fvisibility=hidden (LSODA's own symbols stay inside); these two are the library's interface. */
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
} context;

/* LSODA's f has no user pointer: the context of the running call (one per thread; ctypes releases the GIL). */
static __thread context *current;

static void f_thunk(int *neq, double *t, double *y, double *ydot)
{
    context *c = current;
    if (fabs(y[c->i1]) > c->lim1 || fabs(y[c->i2]) > c->lim2) {
        c->stop = 1;
        *neq = -1;
        return;
    }
    if (c->rhs(*t, y, c->p, ydot, NULL)) {
        c->stop = 2;
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
        c->stop = 2;
        *neq = -1;
        return;
    }
    for (int j = 0; j < n; j++)   /* odeint with col_deriv=False: pd[i + j nrowpd] = J[i][j] */
        for (int i = 0; i < n; i++)
            pd[i + j * *nrowpd] = c->J[i * n + j];
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
    for (long i = 0; i < (long)m * n; i++)
        if (!isfinite(y[i]))
            return 1;
    return 0;
}

/* Integrate the chunks [grid[cuts[k]], grid[cuts[k+1]]] one after another from x, the fast path of
 * whipple_kick.simulate.lsoda.integrate. Stops before the first chunk that the careful path must redo: LSODA
 * failing or a limit passed inside it, a non-finite sample, a sample with |x[i1]| >= lim1 or |x[i2]| >= lim2, or
 * spent + its evaluations over allowance + per_second max(0, its end - t_start).
 *
 * out: rows cuts[0]..cuts[last done + 1] of the grid's states (row cuts[0] = x); x is left the state at the end of
 * the last chunk done; counts[0..2] (nfev, njev, evaluations) are added to. Returns the number of chunks done,
 * or -1 when memory ran out. */
WK_EXPORT int wk_lsoda_fast_chunks(void *rhs, void *jac, const double *p, const double *scale, int n,
                         const double *grid, const int *cuts, int ncuts, double *x, double rtol, const double *atol,
                         int mxstep, int i1, double lim1, int i2, double lim2, int jac_evaluations,
                         double allowance, double per_second, double t_start, long long *counts, double *out)
{
    int maxm = 0;
    for (int k = 0; k + 1 < ncuts; k++)
        if (cuts[k + 1] - cuts[k] + 1 > maxm)
            maxm = cuts[k + 1] - cuts[k] + 1;
    /* odeint's work array sizes (compute_lrw_liw, jt = 1, mxordn 12, mxords 5) */
    int lrn = 20 + n * 13 + 3 * n, lrs = 20 + n * 6 + 3 * n + n * n + 2;
    int lrw = lrn > lrs ? lrn : lrs, liw = 20 + n;
    double *rwork = malloc(sizeof(double) * lrw), *J = malloc(sizeof(double) * n * n);
    double *y = malloc(sizeof(double) * (size_t)(maxm > 0 ? maxm : 1) * n);
    int *iwork = malloc(sizeof(int) * liw);
    if (!rwork || !J || !y || !iwork) {
        free(rwork); free(J); free(y); free(iwork);
        return -1;
    }
    context c = {(rhs_fn)rhs, (jac_fn)jac, p, scale, J, i1, i2, lim1, lim2, 0};
    context *saved = current;
    current = &c;
    int done = 0;
    for (int k = 0; k + 1 < ncuts; k++) {
        int m = cuts[k + 1] - cuts[k] + 1, nfe = 0, nje = 0;
        const double *times = grid + cuts[k];
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
        memcpy(out + (size_t)cuts[k] * n, y, sizeof(double) * m * n);
        memcpy(x, y + (size_t)(m - 1) * n, sizeof(double) * n);
        done++;
    }
    current = saved;
    free(rwork); free(J); free(y); free(iwork);
    return done;
}
