/* The one classical RK4 of parcosim's kernels (the 5R, the actuated 5R, the wheeled pendulum):
 * `substeps` steps of h = dt / substeps of y' = f(y), inputs held.  scipy's rk.py keeps one
 * rk_step the same way.  `work` is caller-owned scratch of 5 n doubles. */
#ifndef PC_RK4_H
#define PC_RK4_H

typedef void (*pc_derivative_fn)(const void *model, const double *y, double *dydt);

static inline void pc_rk4(pc_derivative_fn f, const void *model, double *y, int n, double dt, int substeps,
                          double *work)
{
    double *k1 = work, *k2 = work + n, *k3 = work + 2 * n, *k4 = work + 3 * n, *tmp = work + 4 * n;
    const double h = dt / substeps;
    for (int s = 0; s < substeps; ++s) {
        f(model, y, k1);
        for (int i = 0; i < n; ++i) tmp[i] = y[i] + 0.5 * h * k1[i];
        f(model, tmp, k2);
        for (int i = 0; i < n; ++i) tmp[i] = y[i] + 0.5 * h * k2[i];
        f(model, tmp, k3);
        for (int i = 0; i < n; ++i) tmp[i] = y[i] + h * k3[i];
        f(model, tmp, k4);
        for (int i = 0; i < n; ++i) y[i] += (h / 6.0) * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
    }
}

#endif
