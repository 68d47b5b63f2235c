/* Mass-spring-damper to ground driven by a force: m x'' = -c x - d x' + lambda (fmus/README.md). */
#ifndef ICOSIM_MODEL_H
#define ICOSIM_MODEL_H

#define MODEL_GUID "{8c4e810f-3df3-4a00-8276-176fa3c9f001}"
enum { VR_M, VR_C, VR_D, VR_X0, VR_V0, VR_LAMBDA, VR_X, VR_V, VR_A, VR_XSET, VR_VSET, VR_FAIL, NREAL };
#define NINPUT 1
#define INPUT_VRS {VR_LAMBDA}
#define INPUT_FIELDS(X) X(VR_LAMBDA, u)

typedef struct {
    double m, c, d, x0, v0, u, x, v, fail; /* u: the force lambda */
} Model;

#include "unit.h"
#endif
