/* The current observer's step (observer.h). */
#include "observer.h"

const pc_field pc_observer_fields[] = {
    PC_FIELD(pc_observer, is_static), PC_FIELD(pc_observer, ke), PC_FIELD(pc_observer, h),
    PC_FIELD(pc_observer, a), PC_FIELD(pc_observer, g), PC_FIELD(pc_observer, i_hat),
    PC_FIELD(pc_observer, omega_prev), PC_FIELD(pc_observer, has_prev), {0, 0, 0}};

int pc_observer_estimate(pc_observer *o, double v, double omega, double h, double *i_hat, pc_refusal *r)
{
    if (!isfinite(v)) return pc_refuse(r, PC_OBSERVER_NONFINITE_INPUT, 0, v);
    if (!isfinite(omega)) return pc_refuse(r, PC_OBSERVER_NONFINITE_INPUT, 1, omega);
    if (h != o->h) return pc_refuse(r, PC_OBSERVER_UNPREPARED_STEP, 0, h);
    /* the dynamic kind holds the speed of the step's start, as the drive does */
    double omega_held = (o->is_static != 0.0 || o->has_prev == 0.0) ? omega : o->omega_prev;
    double estimate = o->a * o->i_hat + o->g * (v - o->ke * omega_held);   /* 7.20 or 4.162 over h */
    *i_hat = estimate;
    if (!isfinite(estimate)) return pc_refuse(r, PC_OBSERVER_DIVERGED, 0, estimate);
    o->i_hat = estimate;
    o->omega_prev = omega;
    o->has_prev = 1.0;
    return PC_OK;
}

int pc_observer_io(void *context, double *x, double t, double h, pc_refusal *r)
{
    (void)t;
    const pc_observer_context *k = (const pc_observer_context *)context;
    double i_hat;
    int code = pc_observer_estimate(k->observer, x[0], x[1], h, &i_hat, r);
    if (code == PC_OK) x[2] = i_hat;
    return code;
}

/* The Python layer's call: x = [v, omega, h | i_hat], i_hat written also on PC_OBSERVER_DIVERGED. */
int pc_observer_estimate_x(void *context, double *x, pc_refusal *r)
{
    const pc_observer_context *k = (const pc_observer_context *)context;
    return pc_observer_estimate(k->observer, x[0], x[1], x[2], &x[3], r);
}
