/* The force-driven mass-spring-damper of fmus/msd exchanging its values in millimetres and kilonewtons
 * (fmus/README.md): m x'' = -c x - d x' + lambda with x in mm, lambda in kN, c in N/mm, d in N.s/mm. */
#ifndef ICOSIM_MODEL_H
#define ICOSIM_MODEL_H

#define MODEL_GUID "{585a5a4f-99cb-4e38-834a-a1f3ef9a2e5b}"
enum { VR_M, VR_C, VR_D, VR_X0, VR_V0, VR_LAMBDA, VR_X, VR_V, VR_A, VR_XSET, VR_VSET, VR_FAIL, NREAL };
#define NINPUT 1
#define INPUT_VRS {VR_LAMBDA}
/* the variables read and written as they are (x_set, v_set: setting them moves the mass) */
#define MODEL_FIELDS(X) \
    X(VR_M, m) X(VR_C, c) X(VR_D, d) X(VR_X0, x0) X(VR_V0, v0) X(VR_LAMBDA, u) X(VR_FAIL, fail) \
    X(VR_XSET, x) X(VR_VSET, v)

/* every value in the unit's own units: m kg, c N/mm, d N.s/mm, x0 and x mm, v0 and v mm/s, u (lambda) kN */
typedef struct {
    double m, c, d, x0, v0, u, x, v, fail;
} Model;

#include "unit.h"
#endif
