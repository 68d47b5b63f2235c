/* The value at time s after the step start of input k given by its derivatives there (fmi2_cs.c layout). */
#ifndef ICOSIM_POLY_H
#define ICOSIM_POLY_H

static double poly_input(const double *der, int k, int max_order, double s) {
    const double *d = der + k * (max_order + 1);
    double u = 0.0, p = 1.0;
    for (int j = 0; j <= max_order; j++) {
        u += d[j] * p;
        p *= s / (j + 1);
    }
    return u;
}
#endif
