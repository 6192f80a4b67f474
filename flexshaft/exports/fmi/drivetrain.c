/* The drivetrain's linear state space behind the FMI functions (written by flexshaft, not generated).

   A co-simulation step is exact for inputs held over the step (zero-order hold), for any step the
   importer chooses: [[Ad, Bd], [0, I]] = exp([[A, B], [0, 0]] h), by scaling and squaring with the
   degree-13 Pade approximant (Higham 2005, the method of scipy.linalg.expm and MATLAB's expm),
   computed again only when the step changes. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "drivetrain.h"

#define NA (FS_NX + FS_NU)

void fs_defaults(FsModel *m)
{
    memset(m, 0, sizeof *m);
    m->initial_speed = 0.0;
    m->damping_scale = 1.0;
    m->damping_variant = 1;
    m->dirty = 1;
}

int fs_setup(FsModel *m)
{
    int i, j;
    const double *D;
    if (m->damping_variant < 1 || m->damping_variant > FS_NVARIANTS) return -1;
    if (!(m->damping_scale >= 0.0 && m->damping_scale <= 1e6)) return -1;
    if (!isfinite(m->initial_speed)) return -1;
    D = fs_damping + (size_t)(m->damping_variant - 1) * FS_NM * FS_NM;
    memset(m->A, 0, sizeof m->A);
    for (i = 0; i < FS_NM; i++) {
        m->A[i * FS_NX + FS_NM + i] = 1.0;
        m->A[(FS_NM + i) * FS_NX + i] = -fs_omega2[i];
        for (j = 0; j < FS_NM; j++)
            m->A[(FS_NM + i) * FS_NX + FS_NM + j] = -m->damping_scale * D[i * FS_NM + j];
    }
    for (i = 0; i < FS_NX; i++) m->x[i] = m->initial_speed * fs_spin[i];
    m->h = 0.0;
    m->dirty = 0;
    return 0;
}

/* Output i: its row of C under the chosen damping (the dampers' share differs between variants). */
static double output(const FsModel *m, int i)
{
    const double *C = fs_C + ((size_t)(m->damping_variant - 1) * FS_NY + i) * FS_NX;
    double s = 0.0;
    int j;
    for (j = 0; j < FS_NX; j++) s += C[j] * m->x[j];
    for (j = 0; j < FS_NU; j++) s += fs_D[i * FS_NU + j] * m->u[j];
    return s;
}

static double derivative(const FsModel *m, int i)
{
    double s = 0.0;
    int j;
    for (j = 0; j < FS_NX; j++) s += m->A[i * FS_NX + j] * m->x[j];
    if (i >= FS_NM)
        for (j = 0; j < FS_NU; j++) s += fs_Bq[(i - FS_NM) * FS_NU + j] * m->u[j];
    return s;
}

void fs_derivatives(const FsModel *m, double *dx)
{
    int i;
    for (i = 0; i < FS_NX; i++) dx[i] = derivative(m, i);
}

int fs_get(const FsModel *m, unsigned r, double *value)
{
    if (r == 0) *value = m->time; /* the independent variable, as FMI 3 numbers it */
    else if (r >= FS_VR_INPUT && r < FS_VR_INPUT + FS_NU) *value = m->u[r - FS_VR_INPUT];
    else if (r >= FS_VR_OUTPUT && r < FS_VR_OUTPUT + FS_NY) *value = output(m, (int)(r - FS_VR_OUTPUT));
    else if (r >= FS_VR_STATE && r < FS_VR_STATE + FS_NX) *value = m->x[r - FS_VR_STATE];
    else if (r >= FS_VR_DERIVATIVE && r < FS_VR_DERIVATIVE + FS_NX)
        *value = derivative(m, (int)(r - FS_VR_DERIVATIVE));
    else if (r == FS_VR_SPEED) *value = m->initial_speed;
    else if (r == FS_VR_SCALE) *value = m->damping_scale;
    else return -1;
    return 0;
}

int fs_set(FsModel *m, unsigned r, double value, int running)
{
    if (r >= FS_VR_INPUT && r < FS_VR_INPUT + FS_NU) {
        m->u[r - FS_VR_INPUT] = value;
        return 0;
    }
    if (r != FS_VR_SPEED && r != FS_VR_SCALE) return -1;
    if (running) return -2;
    if (r == FS_VR_SPEED) m->initial_speed = value;
    else m->damping_scale = value;
    m->dirty = 1;
    return 0;
}

int fs_set_variant(FsModel *m, long long value, int running)
{
    if (running) return -2;
    if (value < 1 || value > FS_NVARIANTS) return -1;
    m->damping_variant = (int)value;
    m->dirty = 1;
    return 0;
}

/* c = a b, all n x n row-major */
static void matmul(int n, const double *a, const double *b, double *c)
{
    int i, j, k;
    memset(c, 0, sizeof(double) * (size_t)n * n);
    for (i = 0; i < n; i++)
        for (k = 0; k < n; k++) {
            double aik = a[i * n + k];
            if (aik == 0.0) continue;
            for (j = 0; j < n; j++) c[i * n + j] += aik * b[k * n + j];
        }
}

/* Solve q r = p for r (n x n each, row-major) by LU with partial pivoting; r overwrites p, q is
   destroyed. -1 if q is singular. */
static int solve(int n, double *q, double *p)
{
    int i, j, k;
    for (k = 0; k < n; k++) {
        int piv = k;
        double big = fabs(q[k * n + k]);
        for (i = k + 1; i < n; i++)
            if (fabs(q[i * n + k]) > big) big = fabs(q[i * n + k]), piv = i;
        if (big == 0.0) return -1;
        if (piv != k)
            for (j = 0; j < n; j++) {
                double t = q[k * n + j];
                q[k * n + j] = q[piv * n + j], q[piv * n + j] = t;
                t = p[k * n + j];
                p[k * n + j] = p[piv * n + j], p[piv * n + j] = t;
            }
        for (i = k + 1; i < n; i++) {
            double f = q[i * n + k] / q[k * n + k];
            if (f == 0.0) continue;
            for (j = k; j < n; j++) q[i * n + j] -= f * q[k * n + j];
            for (j = 0; j < n; j++) p[i * n + j] -= f * p[k * n + j];
        }
    }
    for (k = n - 1; k >= 0; k--)
        for (j = 0; j < n; j++) {
            double s = p[k * n + j];
            for (i = k + 1; i < n; i++) s -= q[k * n + i] * p[i * n + j];
            p[k * n + j] = s / q[k * n + k];
        }
    return 0;
}

/* a <- exp(a), n x n row-major; w: 6 n^2 doubles of work. -1 if the Pade denominator is singular. */
static int expm(int n, double *a, double *w)
{
    static const double b[14] = {64764752532480000.0, 32382376266240000.0, 7771770303897600.0,
                                 1187353796428800.0,  129060195264000.0,   10559470521600.0,
                                 670442572800.0,      33522128640.0,       1323241920.0,
                                 40840800.0,          960960.0,            16380.0,
                                 182.0,               1.0};
    const size_t nn = (size_t)n * n;
    double *a2 = w, *a4 = w + nn, *a6 = w + 2 * nn, *t = w + 3 * nn, *u = w + 4 * nn, *v = w + 5 * nn;
    double norm = 0.0;
    int i, j, s = 0;
    for (j = 0; j < n; j++) {
        double c = 0.0;
        for (i = 0; i < n; i++) c += fabs(a[i * n + j]);
        if (c > norm) norm = c;
    }
    if (norm > 5.371920351148152) { /* theta_13: Pade 13 is accurate to double precision below it */
        s = (int)ceil(log2(norm / 5.371920351148152));
        for (i = 0; i < (int)nn; i++) a[i] = ldexp(a[i], -s);
    }
    matmul(n, a, a, a2);
    matmul(n, a2, a2, a4);
    matmul(n, a4, a2, a6);
    for (i = 0; i < (int)nn; i++) t[i] = b[13] * a6[i] + b[11] * a4[i] + b[9] * a2[i];
    matmul(n, a6, t, u);
    for (i = 0; i < (int)nn; i++) u[i] += b[7] * a6[i] + b[5] * a4[i] + b[3] * a2[i];
    for (i = 0; i < n; i++) u[i * n + i] += b[1];
    matmul(n, a, u, t); /* t = U */
    for (i = 0; i < (int)nn; i++) u[i] = b[12] * a6[i] + b[10] * a4[i] + b[8] * a2[i];
    matmul(n, a6, u, v);
    for (i = 0; i < (int)nn; i++) v[i] += b[6] * a6[i] + b[4] * a4[i] + b[2] * a2[i];
    for (i = 0; i < n; i++) v[i * n + i] += b[0];
    for (i = 0; i < (int)nn; i++) { /* a = V + U (right-hand side), u = V - U */
        a[i] = v[i] + t[i];
        u[i] = v[i] - t[i];
    }
    if (solve(n, u, a)) return -1;
    for (; s > 0; s--) {
        matmul(n, a, a, t);
        memcpy(a, t, sizeof(double) * nn);
    }
    return 0;
}

static int discretise(FsModel *m, double h)
{
    int i, j, status;
    double *e = (double *)calloc((size_t)7 * NA * NA, sizeof(double));
    if (!e) return -2;
    for (i = 0; i < FS_NX; i++) {
        for (j = 0; j < FS_NX; j++) e[i * NA + j] = m->A[i * FS_NX + j] * h;
        if (i >= FS_NM)
            for (j = 0; j < FS_NU; j++) e[i * NA + FS_NX + j] = fs_Bq[(i - FS_NM) * FS_NU + j] * h;
    }
    status = expm(NA, e, e + (size_t)NA * NA);
    if (status == 0) {
        for (i = 0; i < FS_NX; i++) {
            for (j = 0; j < FS_NX; j++) m->Ad[i * FS_NX + j] = e[i * NA + j];
            for (j = 0; j < FS_NU; j++) m->Bd[i * FS_NU + j] = e[i * NA + FS_NX + j];
        }
        /* A state nothing drives back (a zero column of A: a free line's rigid-body angle) maps onto
           itself exactly, as in flexshaft's own discretisation: round-off there would turn its pure
           accumulation into a near-defective pair. */
        for (j = 0; j < FS_NX; j++) {
            int zero = 1;
            for (i = 0; i < FS_NX && zero; i++) zero = m->A[i * FS_NX + j] == 0.0;
            if (!zero) continue;
            for (i = 0; i < FS_NX; i++) m->Ad[i * FS_NX + j] = (i == j) ? 1.0 : 0.0;
        }
        m->h = h;
    }
    free(e);
    return status ? -1 : 0;
}

int fs_step(FsModel *m, double h)
{
    double next[FS_NX];
    int i, j;
    if (!(h > 0.0) || !isfinite(h)) return -1;
    if (h != m->h) {
        int status = discretise(m, h);
        if (status) return status;
    }
    for (i = 0; i < FS_NX; i++) {
        double s = 0.0;
        for (j = 0; j < FS_NX; j++) s += m->Ad[i * FS_NX + j] * m->x[j];
        for (j = 0; j < FS_NU; j++) s += m->Bd[i * FS_NU + j] * m->u[j];
        if (!isfinite(s)) return -1;
        next[i] = s;
    }
    memcpy(m->x, next, sizeof next);
    return 0; /* the caller sets the time: the importer's communication point plus h */
}
