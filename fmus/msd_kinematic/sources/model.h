/* Mass-spring-damper to ground with a prescribed acceleration: x'' = a_in; output the force
 * F = m a + c x + d x' the drive exerts on the mass (fmus/README.md). */
#ifndef ICOSIM_MODEL_H
#define ICOSIM_MODEL_H

#define MODEL_GUID "{8c4e810f-3df3-4a00-8276-176fa3c9f002}"
enum { VR_M, VR_C, VR_D, VR_X0, VR_V0, VR_AIN, VR_X, VR_V, VR_A, VR_F, VR_XSET, VR_VSET, VR_FAIL, NREAL };
#define NINPUT 1
#define INPUT_VRS {VR_AIN}
#define INPUT_FIELDS(X) X(VR_AIN, u)

typedef struct {
    double m, c, d, x0, v0, u, x, v, fail; /* u: the acceleration a_in */
} Model;

#include "unit.h"
#endif
