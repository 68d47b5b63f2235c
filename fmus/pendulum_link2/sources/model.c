/* Link 2: m a_S = lambda - d v_S + m g (0, -1), J phi'' = -(l/2) e2 x lambda, integrated over a step by classical
 * Runge-Kutta with nsteps steps, the joint force a polynomial given by its derivatives (link.h, link2.h). */
#include "link2.h"

static void rhs(const Model *m, const double *z, double ux, double uy, double *f) {
    double c = cos(z[2]), s = sin(z[2]);
    f[0] = z[3]; f[1] = z[4]; f[2] = z[5];
    f[3] = (ux - m->d * z[3]) / m->m;
    f[4] = (uy - m->d * z[4]) / m->m - m->g;
    f[5] = -m->l / 2 * (c * uy - s * ux) / m->J;
}

static double link2_output(const Model *m, unsigned vr, const double *f) {
    const double *z = m->z;
    double c = cos(z[2]), s = sin(z[2]), h = m->l / 2, w = z[5];
    switch (vr) {
    case VR_AX: return f[3] - h * (-f[5] * s - w * w * c);
    case VR_AY: return f[4] - h * (f[5] * c - w * w * s);
    default: return 0.0;
    }
}
