/* exp(A) of a small dense matrix (row major, n <= EXPM_MAX) by scaling and squaring of the Taylor series;
 * accurate to a few units of rounding for the augmented matrices of the test units (fmus/README.md). */
#ifndef ICOSIM_EXPM_H
#define ICOSIM_EXPM_H
#include <math.h>
#include <string.h>

#define EXPM_MAX 24

static void expm_mul(int n, const double *a, const double *b, double *out) {
    double t[EXPM_MAX * EXPM_MAX];
    for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++) {
            double s = 0;
            for (int k = 0; k < n; k++) s += a[i * n + k] * b[k * n + j];
            t[i * n + j] = s;
        }
    memcpy(out, t, sizeof(double) * n * n);
}

static void expm(int n, const double *a, double *e) {
    double m[EXPM_MAX * EXPM_MAX], term[EXPM_MAX * EXPM_MAX];
    double norm = 0;
    for (int i = 0; i < n; i++) {
        double row = 0;
        for (int j = 0; j < n; j++) row += fabs(a[i * n + j]);
        if (row > norm) norm = row;
    }
    int s = norm > 0.125 ? (int)ceil(log2(norm / 0.125)) : 0;
    double scale = ldexp(1.0, -s);
    for (int i = 0; i < n * n; i++) m[i] = a[i] * scale;
    for (int i = 0; i < n * n; i++) e[i] = term[i] = (i % (n + 1) == 0) ? 1.0 : 0.0;
    for (int q = 1; q <= 30; q++) {
        expm_mul(n, term, m, term);
        double tn = 0;
        for (int i = 0; i < n * n; i++) {
            term[i] /= q;
            e[i] += term[i];
            tn = fmax(tn, fabs(term[i]));
        }
        if (tn < 1e-20) break;
    }
    for (int k = 0; k < s; k++) expm_mul(n, e, e, e);
}
#endif
