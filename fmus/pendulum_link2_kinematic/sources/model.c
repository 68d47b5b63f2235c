/* Link 2 driven kinematically: the joint point's acceleration a is prescribed, so
 * (J + m l^2/4) phi'' = (l/2) e2 x F_ext - (m l/2) e2 x a and a_S = a + (l/2)(phi'' n2 - phi'^2 e2), with
 * F_ext = (-d v_x, -m g - d v_y); integrated over a step by classical Runge-Kutta with nsteps steps, the
 * acceleration a polynomial given by its derivatives.  The joint force is F = m a_S - F_ext. */
#include <math.h>
#include <string.h>
#include "model.h"
#include "poly.h"

void model_defaults(Model *m) {
    m->m = 1.0; m->l = 1.0; m->J = 1.0 / 12.0; m->g = 9.81; m->d = 2.0;
    m->x0 = 0.0; m->y0 = 0.0; m->phi0 = 0.0; m->vx0 = m->vy0 = m->omega0 = 0.0;
    m->ax = m->ay = 0.0; m->fail = -1.0; m->nsteps = 100;
    memset(m->z, 0, sizeof m->z);
}

void model_initialize(Model *m) {
    double z[6] = {m->x0, m->y0, m->phi0, m->vx0, m->vy0, m->omega0};
    memcpy(m->z, z, sizeof z);
}

static void rhs(const Model *m, const double *z, double ux, double uy, double *f) {
    double c = cos(z[2]), s = sin(z[2]), h = m->l / 2, w = z[5];
    double Fx = -m->d * z[3], Fy = -m->m * m->g - m->d * z[4];
    double alpha = h * ((c * Fy - s * Fx) - m->m * (c * uy - s * ux)) / (m->J + m->m * h * h);
    f[0] = z[3]; f[1] = z[4]; f[2] = w;
    f[3] = ux + h * (-alpha * s - w * w * c);
    f[4] = uy + h * (alpha * c - w * w * s);
    f[5] = alpha;
}

double model_get(const Model *m, unsigned vr) {
    const double *z = m->z;
    double c = cos(z[2]), s = sin(z[2]), h = m->l / 2, w = z[5], f[6];
    rhs(m, z, m->ax, m->ay, f);
    switch (vr) {
    case VR_M: return m->m;
    case VR_L: return m->l;
    case VR_J: return m->J;
    case VR_G: return m->g;
    case VR_D: return m->d;
    case VR_X0: return m->x0;
    case VR_Y0: return m->y0;
    case VR_PHI0: return m->phi0;
    case VR_VX0: return m->vx0;
    case VR_VY0: return m->vy0;
    case VR_OMEGA0: return m->omega0;
    case VR_AXIN: case VR_AX: return m->ax;
    case VR_AYIN: case VR_AY: return m->ay;
    case VR_PX: return z[0] - h * c;
    case VR_PY: return z[1] - h * s;
    case VR_VX: return z[3] + h * w * s;
    case VR_VY: return z[4] - h * w * c;
    case VR_FX: return m->m * f[3] + m->d * z[3];
    case VR_FY: return m->m * f[4] + m->m * m->g + m->d * z[4];
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
    case VR_X0: m->x0 = value; return 0;
    case VR_Y0: m->y0 = value; return 0;
    case VR_PHI0: m->phi0 = value; return 0;
    case VR_VX0: m->vx0 = value; return 0;
    case VR_VY0: m->vy0 = value; return 0;
    case VR_OMEGA0: m->omega0 = value; return 0;
    case VR_AXIN: m->ax = value; return 0;
    case VR_AYIN: m->ay = value; return 0;
    case VR_FAIL: m->fail = value; return 0;
    case VR_NSTEPS: m->nsteps = value; return 0;
    default: return -1;
    }
}

void model_step(Model *m, const double *der, int max_order, double h) {
    int n = m->nsteps >= 1 ? (int)m->nsteps : 1;
    double dt = h / n, z[6], k[4][6], tmp[6];
    memcpy(z, m->z, sizeof z);
    for (int i = 0; i < n; i++) {
        double t = i * dt, ux[3], uy[3];
        for (int q = 0; q < 3; q++) {
            ux[q] = poly_input(der, 0, max_order, t + q * dt / 2);
            uy[q] = poly_input(der, 1, max_order, t + q * dt / 2);
        }
        rhs(m, z, ux[0], uy[0], k[0]);
        for (int j = 0; j < 6; j++) tmp[j] = z[j] + dt / 2 * k[0][j];
        rhs(m, tmp, ux[1], uy[1], k[1]);
        for (int j = 0; j < 6; j++) tmp[j] = z[j] + dt / 2 * k[1][j];
        rhs(m, tmp, ux[1], uy[1], k[2]);
        for (int j = 0; j < 6; j++) tmp[j] = z[j] + dt * k[2][j];
        rhs(m, tmp, ux[2], uy[2], k[3]);
        for (int j = 0; j < 6; j++) z[j] += dt / 6 * (k[0][j] + 2 * k[1][j] + 2 * k[2][j] + k[3][j]);
    }
    memcpy(m->z, z, sizeof z);
    m->ax = poly_input(der, 0, max_order, h);
    m->ay = poly_input(der, 1, max_order, h);
}
