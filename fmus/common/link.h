/* The pendulum links' shared rigid-body code (pendulum_link1, pendulum_link2, pendulum_link2_kinematic;
 * docs/pendulum.md), included by their model.c: the parameters every link has and their defaults, model_get and
 * model_set of the variables read and written as they are (these and the unit's MODEL_FIELDS), and the step of
 * classical Runge-Kutta with nsteps steps, the two joint inputs (ux, uy) the polynomials given by their derivatives. */
#ifndef ICOSIM_LINK_H
#define ICOSIM_LINK_H
#include <math.h>
#include <string.h>
#include "model.h"
#include "poly.h"

#define LINK_FIELDS(X) \
    X(VR_M, m) X(VR_L, l) X(VR_J, J) X(VR_G, g) X(VR_D, d) X(VR_PHI0, phi0) X(VR_OMEGA0, omega0) \
    X(VR_FAIL, fail) X(VR_NSTEPS, nsteps)
#define LINK_MAX_STATES 6

static double link_output(const Model *m, unsigned vr); /* the unit's outputs, else 0 */

/* the state's derivative f at the state z under the joint inputs (ux, uy) */
typedef void link_rhs(const Model *m, const double *z, double ux, double uy, double *f);

static void link_defaults(Model *m) {
    m->m = 1.0; m->l = 1.0; m->J = 1.0 / 12.0; m->g = 9.81; m->d = 2.0;
    m->phi0 = 0.0; m->omega0 = 0.0; m->ux = m->uy = 0.0; m->fail = -1.0; m->nsteps = 100;
}

double model_get(const Model *m, unsigned vr) {
    switch (vr) {
    LINK_FIELDS(UNIT_GET)
    MODEL_FIELDS(UNIT_GET)
    default: return link_output(m, vr);
    }
}

int model_set(Model *m, unsigned vr, double value) {
    switch (vr) {
    LINK_FIELDS(UNIT_SET)
    MODEL_FIELDS(UNIT_SET)
    default: return -1; /* outputs */
    }
}

/* the nz states z advanced over h; afterwards the inputs hold the polynomials' values at the step end */
static void link_step(Model *m, link_rhs *rhs, int nz, double *state, const double *der, int max_order, double h) {
    int n = m->nsteps >= 1 ? (int)m->nsteps : 1;
    double dt = h / n, z[LINK_MAX_STATES], k[4][LINK_MAX_STATES], tmp[LINK_MAX_STATES];
    memcpy(z, state, nz * sizeof *z);
    for (int i = 0; i < n; i++) {
        double t = i * dt, ux[3], uy[3];
        for (int q = 0; q < 3; q++) {
            ux[q] = poly_input(der, 0, max_order, t + q * dt / 2);
            uy[q] = poly_input(der, 1, max_order, t + q * dt / 2);
        }
        rhs(m, z, ux[0], uy[0], k[0]);
        for (int j = 0; j < nz; j++) tmp[j] = z[j] + dt / 2 * k[0][j];
        rhs(m, tmp, ux[1], uy[1], k[1]);
        for (int j = 0; j < nz; j++) tmp[j] = z[j] + dt / 2 * k[1][j];
        rhs(m, tmp, ux[1], uy[1], k[2]);
        for (int j = 0; j < nz; j++) tmp[j] = z[j] + dt * k[2][j];
        rhs(m, tmp, ux[2], uy[2], k[3]);
        for (int j = 0; j < nz; j++) z[j] += dt / 6 * (k[0][j] + 2 * k[1][j] + 2 * k[2][j] + k[3][j]);
    }
    memcpy(state, z, nz * sizeof *z);
    m->ux = poly_input(der, 0, max_order, h);
    m->uy = poly_input(der, 1, max_order, h);
}
#endif
