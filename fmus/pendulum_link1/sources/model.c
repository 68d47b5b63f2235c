/* Link 1: JO1 phi'' = -m g l/2 cos(phi) - d l^2/4 phi' - l n1 . lambda  (JO1 = J + m l^2/4), integrated over a
 * step by classical Runge-Kutta with nsteps steps, the joint force a polynomial given by its derivatives. */
#include <math.h>
#include "model.h"
#include "poly.h"

void model_defaults(Model *m) {
    m->m = 1.0; m->l = 1.0; m->J = 1.0 / 12.0; m->g = 9.81; m->d = 2.0;
    m->phi0 = 0.7853981633974483; m->omega0 = 0.0; m->lx = 0.0; m->ly = 0.0; m->fail = -1.0; m->nsteps = 100;
    m->phi = m->phi0; m->w = 0.0;
}

void model_initialize(Model *m) { m->phi = m->phi0; m->w = m->omega0; }

static double accel(const Model *m, double phi, double w, double ux, double uy) {
    double c = cos(phi), s = sin(phi);
    double JO = m->J + m->m * m->l * m->l / 4;
    double torque = -m->m * m->g * m->l / 2 * c - m->d * m->l * m->l / 4 * w;
    return (torque - m->l * (c * uy - s * ux)) / JO;
}

double model_get(const Model *m, unsigned vr) {
    double c = cos(m->phi), s = sin(m->phi), l = m->l, w = m->w;
    switch (vr) {
    case VR_M: return m->m;
    case VR_L: return m->l;
    case VR_J: return m->J;
    case VR_G: return m->g;
    case VR_D: return m->d;
    case VR_PHI0: return m->phi0;
    case VR_OMEGA0: return m->omega0;
    case VR_LX: return m->lx;
    case VR_LY: return m->ly;
    case VR_PX: return l * c;
    case VR_PY: return l * s;
    case VR_VX: return -l * w * s;
    case VR_VY: return l * w * c;
    case VR_AX: return -l * accel(m, m->phi, w, m->lx, m->ly) * s - l * w * w * c;
    case VR_AY: return l * accel(m, m->phi, w, m->lx, m->ly) * c - l * w * w * s;
    case VR_FAIL: return m->fail;
    case VR_NSTEPS: return m->nsteps;
    default: return 0.0;
    }
}

int model_set(Model *m, unsigned vr, double value) {
    switch (vr) {
    case VR_M: m->m = value; return 0;
    case VR_L: m->l = value; return 0;
    case VR_J: m->J = value; return 0;
    case VR_G: m->g = value; return 0;
    case VR_D: m->d = value; return 0;
    case VR_PHI0: m->phi0 = value; return 0;
    case VR_OMEGA0: m->omega0 = value; return 0;
    case VR_LX: m->lx = value; return 0;
    case VR_LY: m->ly = value; return 0;
    case VR_FAIL: m->fail = value; return 0;
    case VR_NSTEPS: m->nsteps = value; return 0;
    default: return -1;
    }
}

void model_step(Model *m, const double *der, int max_order, double h) {
    int n = m->nsteps >= 1 ? (int)m->nsteps : 1;
    double dt = h / n, phi = m->phi, w = m->w;
    for (int i = 0; i < n; i++) {
        double t = i * dt, ux[3], uy[3];
        for (int q = 0; q < 3; q++) {
            ux[q] = poly_input(der, 0, max_order, t + q * dt / 2);
            uy[q] = poly_input(der, 1, max_order, t + q * dt / 2);
        }
        double k1p = w, k1w = accel(m, phi, w, ux[0], uy[0]);
        double k2p = w + dt / 2 * k1w, k2w = accel(m, phi + dt / 2 * k1p, w + dt / 2 * k1w, ux[1], uy[1]);
        double k3p = w + dt / 2 * k2w, k3w = accel(m, phi + dt / 2 * k2p, w + dt / 2 * k2w, ux[1], uy[1]);
        double k4p = w + dt * k3w, k4w = accel(m, phi + dt * k3p, w + dt * k3w, ux[2], uy[2]);
        phi += dt / 6 * (k1p + 2 * k2p + 2 * k3p + k4p);
        w += dt / 6 * (k1w + 2 * k2w + 2 * k3w + k4w);
    }
    m->phi = phi; m->w = w;
    m->lx = poly_input(der, 0, max_order, h);
    m->ly = poly_input(der, 1, max_order, h);
}
