/* The open-loop current observer (thesis 003: 7.20 static, 4.162 integrated exactly: dynamic).
 * The bench has no current sensor; the current controller is closed on this estimate (7.2.4).
 * One caller-owned struct of doubles (motor.CurrentObserver owns it as a numpy buffer). */
#ifndef PC_OBSERVER_H
#define PC_OBSERVER_H

#include "pc_common.h"

/* Refusal codes: the drive's (drive.h) NONFINITE_INPUT 1, UNPREPARED_STEP 2, DIVERGED 3. */
#define PC_OBSERVER_NONFINITE_INPUT 1   /* index: 0 v, 1 omega */
#define PC_OBSERVER_UNPREPARED_STEP 2   /* h is not the step a, g are for */
#define PC_OBSERVER_DIVERGED 3          /* the estimate is not finite (returned, not kept) */

typedef struct {
    double is_static;   /* 1: static kind (7.20: omega now), 0: dynamic (omega of the previous call) */
    double ke;          /* back-emf constant [V s/rad] */
    double h;           /* the step length a, g are for [s] (NaN: none) */
    double a, g;        /* i(t+h) = a i + g (v - ke omega) (motor.electrics; static: a = 0, g = 1/R) */
    /* state */
    double i_hat;       /* the last estimate [A] */
    double omega_prev;  /* the speed of the previous call [rad/s] */
    double has_prev;    /* 1: there was a previous call */
} pc_observer;

typedef struct {
    pc_observer *observer;
} pc_observer_context;

extern const pc_field pc_observer_fields[];

/* The estimate at the end of a step of length h over which v was applied; omega is the speed now. */
int pc_observer_estimate(pc_observer *o, double v, double omega, double h, double *i_hat, pc_refusal *r);

/* CurrentObserver: x = [v, omega | i_hat]. */
int pc_observer_io(void *context, double *x, double t, double h, pc_refusal *r);

/* The Python layer's call: x = [v, omega, h | i_hat] (three pointers). */
int pc_observer_estimate_x(void *context, double *x, pc_refusal *r);

#endif
