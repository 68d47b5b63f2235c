/* The embedded solvers of body_rk45 (fmus/README.md) for an autonomous system y' = f(y) of at most SOLVER_MAX
 * states (the unit's input is held over a communication step, so its right-hand side does not depend on time):
 *
 * dopri45 -- Dormand-Prince 5(4) with adaptive step-size control.  A step is accepted when its error estimate
 *   (the difference of the embedded 4th- and 5th-order solutions) satisfies max_i |e_i| / (atol + rtol max(|y_i|,
 *   |y_new_i|)) <= 1, and the next step is scaled by 0.9 err^(-1/5), between 0.2 and 5 times the last.  The
 *   solution advances with the 5th-order result (local extrapolation).  Steps are clipped so that the last one ends
 *   exactly at H; the step size to try next is handed back, so a caller that keeps it (in a saved FMU state)
 *   repeats a step bit for bit.
 * rk4 -- classical Runge-Kutta with n equal steps.
 */
#ifndef BODY_DOPRI45_H
#define BODY_DOPRI45_H
#include <math.h>
#include <string.h>

#define SOLVER_MAX 4
#define DOPRI_MAX_STEPS 1000000

typedef void solver_rhs(const void *ctx, const double *y, double *f);

/* The Dormand-Prince tableau: nodes c, coefficients a (lower triangle), 5th-order weights b (those of the last
 * stage, b7 = 0) and the error weights e = b - bhat (bhat: the embedded 4th-order weights). */
static const double dp_a[7][6] = {
    {0},
    {1.0 / 5},
    {3.0 / 40, 9.0 / 40},
    {44.0 / 45, -56.0 / 15, 32.0 / 9},
    {19372.0 / 6561, -25360.0 / 2187, 64448.0 / 6561, -212.0 / 729},
    {9017.0 / 3168, -355.0 / 33, 46732.0 / 5247, 49.0 / 176, -5103.0 / 18656},
    {35.0 / 384, 0, 500.0 / 1113, 125.0 / 192, -2187.0 / 6784, 11.0 / 84},
};
static const double dp_e[7] = {71.0 / 57600, 0, -71.0 / 16695, 71.0 / 1920, -17253.0 / 339200, 22.0 / 525, -1.0 / 40};

static double dp_scale(double y0, double y1, double rtol, double atol) {
    return atol + rtol * fmax(fabs(y0), fabs(y1));
}

/* A first step size (Hairer, Norsett & Wanner, Solving ODEs I, II.4): from the sizes of y, f(y) and of f's change
 * over a trial Euler step, at most 100 times the trial step and at most H. */
static double dp_first_step(solver_rhs *f, const void *ctx, int n, const double *y, const double *f0, double H,
                            double rtol, double atol) {
    double d0 = 0, d1 = 0, d2 = 0, y1[SOLVER_MAX], f1[SOLVER_MAX];
    for (int i = 0; i < n; i++) {
        double sc = dp_scale(y[i], y[i], rtol, atol);
        d0 = fmax(d0, fabs(y[i]) / sc);
        d1 = fmax(d1, fabs(f0[i]) / sc);
    }
    double h0 = (d0 < 1e-5 || d1 < 1e-5) ? 1e-6 : 0.01 * d0 / d1;
    h0 = fmin(h0, H);
    for (int i = 0; i < n; i++) y1[i] = y[i] + h0 * f0[i];
    f(ctx, y1, f1);
    for (int i = 0; i < n; i++) d2 = fmax(d2, fabs(f1[i] - f0[i]) / dp_scale(y[i], y[i], rtol, atol) / h0);
    double dmax = fmax(d1, d2);
    double h1 = dmax <= 1e-15 ? fmax(1e-6, h0 * 1e-3) : pow(0.01 / dmax, 1.0 / 5);
    return fmin(fmin(100 * h0, h1), H);
}

/* y advanced over [0, H]; *h: the step size to try first (0: choose one), afterwards the one to try next.
 * The number of accepted steps (rejected ones added to *rejected), or -1 when the step size underflowed or more
 * than DOPRI_MAX_STEPS steps were needed (y and *h then unchanged). */
static int dopri45(solver_rhs *f, const void *ctx, int n, double *y, double H, double rtol, double atol, double *h,
                   int *rejected) {
    double k[7][SOLVER_MAX], z[SOLVER_MAX], ynew[SOLVER_MAX], yt[SOLVER_MAX];
    memcpy(z, y, n * sizeof *z);
    f(ctx, z, k[0]);
    double hh = *h > 0 ? *h : dp_first_step(f, ctx, n, z, k[0], H, rtol, atol), s = 0, next = hh;
    int accepted = 0, tries = 0;
    while (s < H) {
        if (++tries > DOPRI_MAX_STEPS) return -1;
        int last = s + 1.01 * hh >= H; /* the remainder is taken whole rather than leaving a sliver */
        double step = last ? H - s : hh;
        if (!(step > 1e-14 * H)) return -1;
        for (int j = 1; j < 7; j++) {
            for (int i = 0; i < n; i++) {
                double sum = 0;
                for (int q = 0; q < j; q++) sum += dp_a[j][q] * k[q][i];
                yt[i] = z[i] + step * sum;
            }
            if (j == 6) memcpy(ynew, yt, n * sizeof *yt); /* the 6th stage's point is the 5th-order solution */
            f(ctx, yt, k[j]);
        }
        double err = 0;
        for (int i = 0; i < n; i++) {
            double e = 0;
            for (int q = 0; q < 7; q++) e += dp_e[q] * k[q][i];
            err = fmax(err, fabs(step * e) / dp_scale(z[i], ynew[i], rtol, atol));
        }
        double fac = err > 0 ? fmin(5.0, fmax(0.2, 0.9 * pow(err, -1.0 / 5))) : 5.0;
        if (err <= 1) {
            memcpy(z, ynew, n * sizeof *z);
            memcpy(k[0], k[6], n * sizeof *z); /* first same as last */
            s = last ? H : s + step;
            accepted++;
            /* a step shortened to end at H says little about the size to try next: keep the longer proposal */
            next = (last && step < hh && fac >= 1) ? hh : step * fac;
            hh = step * fac;
        } else {
            (*rejected)++;
            hh = step * fac;
        }
    }
    memcpy(y, z, n * sizeof *z);
    *h = next;
    return accepted;
}

/* y advanced over [0, H] by n equal steps of classical Runge-Kutta. */
static void rk4(solver_rhs *f, const void *ctx, int dim, double *y, double H, int n) {
    double dt = H / n, k1[SOLVER_MAX], k2[SOLVER_MAX], k3[SOLVER_MAX], k4[SOLVER_MAX], t[SOLVER_MAX];
    for (int s = 0; s < n; s++) {
        f(ctx, y, k1);
        for (int i = 0; i < dim; i++) t[i] = y[i] + dt / 2 * k1[i];
        f(ctx, t, k2);
        for (int i = 0; i < dim; i++) t[i] = y[i] + dt / 2 * k2[i];
        f(ctx, t, k3);
        for (int i = 0; i < dim; i++) t[i] = y[i] + dt * k3[i];
        f(ctx, t, k4);
        for (int i = 0; i < dim; i++) y[i] += dt / 6 * (k1[i] + 2 * k2[i] + 2 * k3[i] + k4[i]);
    }
}
#endif
