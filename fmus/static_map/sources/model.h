/* A static nonlinear map: y = a u + b + c sin(u) + q u^3, z = b, w = y, no state (fmus/README.md). */
#ifndef ICOSIM_MODEL_H
#define ICOSIM_MODEL_H

#define MODEL_GUID "{3f6b2a1e-7c0d-4e59-9a84-5d1c2b7e9f31}"
enum { VR_A, VR_B, VR_C, VR_Q, VR_U, VR_Y, VR_Z, VR_W, VR_FAIL, NREAL };
#define NINPUT 1
#define INPUT_VRS {VR_U}
#define INPUT_FIELDS(X) X(VR_U, u)

typedef struct {
    double a, b, c, q, u, fail;
} Model;

#define MODEL_DIRECTIONAL /* the partial derivatives of y, w, z by u: model_directional */
#include "unit.h"
#endif
