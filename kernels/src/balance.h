/* The wheeled pendulum's balance controller sample (controller/balance.py: design, docstring).
 *
 * At each sample at time t: correct the observer's estimate with the measurements
 *   y = ((enc_l + enc_r)/2, gyro, (R/W)(enc_r - enc_l))        (mean encoder, pitch rate, yaw)
 *   x_hat <- x_hat + Lo (y - C x_hat),
 * command u = sat(-K (x_hat - x_ref(t)), +-v_battery), x_ref from the route's smooth steps
 * (7.27), and predict x_hat <- Ad x_hat + Bd u with the voltages applied.  The design (LQR,
 * Kalman, python-control) stays in Python and fills pc_balance_params.
 *
 * Sizes and kept-state indices are words of a buffer a restored FMU state may carry: the
 * sample checks each against its array's declared size and refuses, never reads or writes
 * outside (PC_BALANCE_BAD_BUFFER).
 */
#ifndef PC_BALANCE_H
#define PC_BALANCE_H

#include "pc_common.h"

#define PC_BALANCE_N_MAX 6    /* states: theta, psi, phi, theta', psi', phi' */
#define PC_BALANCE_NY_MAX 3   /* measurements: mean encoder, gyro, yaw */
#define PC_BALANCE_N_INPUTS 3 /* enc_l, enc_r, gyro */
#define PC_BALANCE_N_OUTPUTS 12

/* The design and the route; read-only after set-up.  Matrices row-major at their largest
 * size, the kept block in the top-left corner. */
typedef struct {
    double n;          /* kept states, integer in [0, PC_BALANCE_N_MAX] */
    double ny;         /* measurements, integer in [0, PC_BALANCE_NY_MAX] */
    double yaw;        /* 1: the yaw is controlled and measured */
    double r_over_w;   /* R/W: the yaw from the encoders */
    double radius;     /* wheel radius R [m]: theta_d = distance s / R */
    double v_max;      /* v_battery [V] */
    double gain;       /* K_t/R_m [N m/V]: an ideal drive's torque per volt */
    double distance;   /* the route: distance [m] over `drive`, then `turn` [rad] over `turning` */
    double turn;
    double drive[2];   /* (start, end) [s] */
    double turning[2];
    double smooth[8];  /* coefficients of s(tau) (7.27), ascending */
    double slope[7];   /* coefficients of s'(tau), ascending */
    double states[PC_BALANCE_N_MAX];   /* kept state indices, integers in [0, 6) (-1 unused) */
    double K[2][PC_BALANCE_N_MAX];     /* LQR gain */
    double Lo[PC_BALANCE_N_MAX][PC_BALANCE_NY_MAX];   /* observer gain */
    double C[PC_BALANCE_NY_MAX][PC_BALANCE_N_MAX];    /* measurement matrix */
    double Ad[PC_BALANCE_N_MAX][PC_BALANCE_N_MAX];    /* zero-order-hold discretisation */
    double Bd[PC_BALANCE_N_MAX][2];
} pc_balance_params;

/* What a run changes (FMU state's run-state words). */
typedef struct {
    double started;                    /* 1 once x_hat holds an estimate */
    double x_hat[PC_BALANCE_N_MAX];    /* the estimate for the next sample (kept states) */
    double u[2];                       /* the last saturated voltages (v_l, v_r) [V] */
} pc_balance_state;

/* The controller's one buffer: configuration, then run state. */
typedef struct {
    pc_balance_params params;
    pc_balance_state state;
} pc_balance;

/* pc_balance_io's context: the buffer and the largest |input| taken. */
typedef struct {
    pc_balance *balance;
    double limit;
} pc_balance_context;

enum {
    PC_BALANCE_BAD_INPUT = 1,   /* index: 0 enc_l, 1 enc_r, 2 gyro; value: not finite */
    PC_BALANCE_INPUT_LIMIT = 2, /* index as above; value: beyond the limit */
    PC_BALANCE_BAD_BUFFER = 3,  /* index: the word of pc_balance (in doubles); value: a size or index out of range */
};

extern const pc_field pc_balance_fields[];
extern const pc_field pc_balance_params_fields[];
extern const pc_field pc_balance_state_fields[];

/* One sample at time t: inputs x[0..2] (enc_l, enc_r, gyro), outputs into x[3..14] (v_l, v_r,
 * tau_l, tau_r, x_d, y_d, then the estimate of the six states, 0 for those not kept).
 * Refused (nothing changed): an input not finite or beyond `limit`, a size or index word
 * out of range. */
int pc_balance_sample(pc_balance *b, double *x, double t, double limit, pc_refusal *r);

/* pc_io_fn of the compiled loop: pc_balance_sample on a pc_balance_context. */
int pc_balance_io(void *context, double *x, double t, double h, pc_refusal *r);

#endif
