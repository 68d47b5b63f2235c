/* Link 1 of the double pendulum (docs/pendulum.md), pinned to the ground, driven by the joint force
 * (lambda_x, lambda_y) at its tip; outputs the joint point's position, velocity and acceleration. */
#ifndef ICOSIM_MODEL_H
#define ICOSIM_MODEL_H

#define MODEL_GUID "{8c4e810f-3df3-4a00-8276-176fa3c9f011}"
#define MAX_ORDER 12
enum {
    VR_M, VR_L, VR_J, VR_G, VR_D, VR_PHI0, VR_OMEGA0, VR_LX, VR_LY,
    VR_PX, VR_PY, VR_VX, VR_VY, VR_AX, VR_AY, VR_FAIL, VR_NSTEPS, NREAL
};
#define NINPUT 2
#define INPUT_VRS {VR_LX, VR_LY}
#define FAIL_TIME_VR VR_FAIL

typedef struct {
    double m, l, J, g, d, phi0, omega0, lx, ly, fail, nsteps;
    double phi, w;
} Model;

void model_defaults(Model *m);
void model_initialize(Model *m);
double model_get(const Model *m, unsigned vr);
int model_set(Model *m, unsigned vr, double value);
void model_step(Model *m, const double *der, int max_order, double h);
#endif
