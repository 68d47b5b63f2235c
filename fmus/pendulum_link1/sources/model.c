/* Link 1: JO1 phi'' = -m g l/2 cos(phi) - d l^2/4 phi' - l n1 . lambda  (JO1 = J + m l^2/4), integrated over a
 * step by classical Runge-Kutta with nsteps steps, the joint force a polynomial given by its derivatives (link.h). */
#include "link.h"

void model_defaults(Model *m) {
    link_defaults(m);
    m->phi0 = 0.7853981633974483;
    m->z[0] = m->phi0; m->z[1] = 0.0;
}

void model_initialize(Model *m) { m->z[0] = m->phi0; m->z[1] = m->omega0; }

static double accel(const Model *m, double phi, double w, double ux, double uy) {
    double c = cos(phi), s = sin(phi);
    double JO = m->J + m->m * m->l * m->l / 4;
    double torque = -m->m * m->g * m->l / 2 * c - m->d * m->l * m->l / 4 * w;
    return (torque - m->l * (c * uy - s * ux)) / JO;
}

static void rhs(const Model *m, const double *z, double ux, double uy, double *f) {
    f[0] = z[1];
    f[1] = accel(m, z[0], z[1], ux, uy);
}

static double link_output(const Model *m, unsigned vr) {
    double c = cos(m->z[0]), s = sin(m->z[0]), l = m->l, w = m->z[1];
    switch (vr) {
    case VR_PX: return l * c;
    case VR_PY: return l * s;
    case VR_VX: return -l * w * s;
    case VR_VY: return l * w * c;
    case VR_AX: return -l * accel(m, m->z[0], w, m->ux, m->uy) * s - l * w * w * c;
    case VR_AY: return l * accel(m, m->z[0], w, m->ux, m->uy) * c - l * w * w * s;
    default: return 0.0;
    }
}

void model_step(Model *m, const double *der, int max_order, double h) { link_step(m, rhs, 2, m->z, der, max_order, h); }
