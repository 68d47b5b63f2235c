/* A communication step of a unit as both interfaces take it (fmi2_cs.c, fmi3_cs.c; fmus/README.md). */
#ifndef ICOSIM_STEP_H
#define ICOSIM_STEP_H
#include "model.h"

static const unsigned input_vrs[NINPUT] = INPUT_VRS;

#define STEP_REFUSED "step refused: the communication point reached fail_time"

/* The step from t of size h: refused (1) when it starts at or after fail_time, an error (-1) when h is not
 * positive, else (0) taken with the inputs' present values as their 0th derivatives in der. */
static int unit_step(Model *m, double *der, double t, double h) {
    if (model_get(m, FAIL_TIME_VR) >= 0 && t >= model_get(m, FAIL_TIME_VR)) return 1;
    if (!(h > 0)) return -1;
    for (int k = 0; k < NINPUT; k++) der[k * (MAX_ORDER + 1)] = model_get(m, input_vrs[k]);
    model_step(m, der, MAX_ORDER, h);
    return 0;
}
#endif
