/* Link 2 driven kinematically: the joint point's acceleration a is prescribed, so
 * (J + m l^2/4) phi'' = (l/2) e2 x F_ext - (m l/2) e2 x a and a_S = a + (l/2)(phi'' n2 - phi'^2 e2), with
 * F_ext = (-d v_x, -m g - d v_y); integrated over a step by classical Runge-Kutta with nsteps steps, the
 * acceleration a polynomial given by its derivatives (link.h, link2.h).  The joint force is F = m a_S - F_ext. */
#include "link2.h"

static void rhs(const Model *m, const double *z, double ux, double uy, double *f) {
    double c = cos(z[2]), s = sin(z[2]), h = m->l / 2, w = z[5];
    double Fx = -m->d * z[3], Fy = -m->m * m->g - m->d * z[4];
    double alpha = h * ((c * Fy - s * Fx) - m->m * (c * uy - s * ux)) / (m->J + m->m * h * h);
    f[0] = z[3]; f[1] = z[4]; f[2] = w;
    f[3] = ux + h * (-alpha * s - w * w * c);
    f[4] = uy + h * (alpha * c - w * w * s);
    f[5] = alpha;
}

static double link2_output(const Model *m, unsigned vr, const double *f) {
    const double *z = m->z;
    switch (vr) {
    case VR_AX: return m->ux;
    case VR_AY: return m->uy;
    case VR_FX: return m->m * f[3] + m->d * z[3];
    case VR_FY: return m->m * f[4] + m->m * m->g + m->d * z[4];
    default: return 0.0;
    }
}
