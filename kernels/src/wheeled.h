/* The two-wheeled inverted pendulum of seed 000 (docs/pendulum.md; plant/wheeled.py binds it).
 *
 * Equations (Lagrange-d'Alembert, seed 000's numbers in brackets), nu = (theta, psi, phi),
 * s = sin psi, c = cos psi:
 *
 *   M(psi) nu'' + C(psi, nu') + G(psi) = F                                   [(17)]
 *   M11 = (2m + M_b) R^2 + 2 J_w,  M12 = M_b R L c,  M22 = M_b L^2 + J_psi   [(18)]
 *   M33 = m W^2/2 + M_b L^2 s^2 + J_phi + W^2/(2 R^2) J_w                    [(18), m not M_b: typo]
 *   C1  = -M_b R L s psi'^2  - k M_b L R s phi'^2                            [(18) + nonholonomic]
 *   C2  = -M_b L^2 s c phi'^2                                                [(18), phi' not psi': typo]
 *   C3  = 2 M_b L^2 s c psi' phi' + k M_b L R s theta' phi'                  [(18) + nonholonomic]
 *   G2  = -M_b g L s                                                         [(18)]
 *   F   = (tau_l + tau_r, -(tau_l + tau_r) + tau_d, W/(2R) (tau_r - tau_l))  [(20)]
 *   x' = R theta' cos phi,  y' = R theta' sin phi                            [(2)]
 *
 * k = 1 for the exact model, 0 for the seed's (constraints substituted into the Lagrangian
 * before differentiating, (13)-(16)).  M_b is the body mass (the seed's M).  tau_d is a
 * disturbance torque on the body about the axle.
 */
#ifndef PC_WHEELED_H
#define PC_WHEELED_H

#include "pc_common.h"

/* Seed 000's mechanical parameters (SI); read-only after set-up. */
typedef struct {
    double g;            /* gravity [m/s2] */
    double m;            /* one wheel's mass [kg] */
    double R;            /* wheel radius [m] */
    double J_w;          /* wheel spin inertia [kg m2] */
    double M;            /* body mass M_b [kg] */
    double W;            /* body width (track) [m] */
    double D;            /* body depth [m] */
    double H;            /* body height [m] */
    double L;            /* axle to body centre of mass [m] */
    double J_psi;        /* body pitch inertia [kg m2] */
    double J_phi;        /* body yaw inertia [kg m2] */
    double nonholonomic; /* k above: 1 exact model, 0 the seed's */
    double yaw;          /* 0 locks the yaw (phi' = phi'' = 0) */
} pc_wheeled_params;

/* What a step advances and FMU state saves. */
typedef struct {
    double theta;   /* mean wheel angle from the vertical [rad] */
    double psi;     /* pitch, 0 upright, + toward the heading [rad] */
    double phi;     /* yaw, CCW from +x [rad] */
    double x, y;    /* axle midpoint [m] */
    double dtheta, dpsi, dphi;   /* rates [rad/s] */
} pc_wheeled_state;

#define PC_WHEELED_N_STATE 8
#define PC_WHEELED_N_OUTPUTS 14
#define PC_WHEELED_MAX_SUBSTEPS 10000

/* The compiled loop's settings of one pendulum (the adapter's, not the simulator's). */
typedef struct {
    double substeps;        /* RK4 steps per communication step, integer in [1, PC_WHEELED_MAX_SUBSTEPS] */
    double count;           /* encoder count [rad] (2 pi / counts per turn), > 0 */
    double push_torque;     /* a push on the body [N m] ... */
    double push_start;      /* ... over the steps starting in [start, start + duration) [s] */
    double push_duration;
    double limit;           /* largest |input| taken */
} pc_wheeled_settings;

/* pc_wheeled_io's context: the pendulum's buffers. */
typedef struct {
    const pc_wheeled_params *params;
    pc_wheeled_state *state;
    const pc_wheeled_settings *settings;
} pc_wheeled_context;

/* Refusal codes; `index` and `value` name the quantity (see each). */
enum {
    PC_WHEELED_FALLEN_PITCH = 1, /* |psi| reached 90 degrees: index 0, value psi [rad] */
    PC_WHEELED_FALLEN_FLOOR = 2, /* a body corner reached the floor: index 0, value psi [rad] */
    PC_WHEELED_NONFINITE = 3,    /* index: the state entry, value: it */
    PC_WHEELED_BAD_INPUT = 4,    /* index: 0 tau_l, 1 tau_r, 2 tau_d; value: not finite */
    PC_WHEELED_BAD_STEP = 5,     /* index 0: dt, not finite and > 0 */
    PC_WHEELED_INPUT_LIMIT = 6,  /* index as PC_WHEELED_BAD_INPUT; value: beyond the settings' limit */
    PC_WHEELED_BAD_SETTING = 7,  /* index 0: substeps not an integer in [1, PC_WHEELED_MAX_SUBSTEPS]; 1: count <= 0 */
};

extern const int pc_wheeled_max_substeps;
extern const pc_field pc_wheeled_params_fields[];
extern const pc_field pc_wheeled_state_fields[];
extern const pc_field pc_wheeled_settings_fields[];

/* dydt = f(y) for held torques: wheel torques tau_l, tau_r (motor on wheel, reaction on the
 * body) and a body torque tau_d [N m]. */
void pc_wheeled_derivative(const pc_wheeled_params *p, const double *y, double tau_l, double tau_r,
                           double tau_d, double *dydt);

/* Height above the floor of the body's lowest corner [m]. */
double pc_wheeled_lowest_body_point(const pc_wheeled_params *p, double psi);

/* PC_OK, or why `s` is no longer a standing robot (PC_WHEELED_NONFINITE, _FALLEN_PITCH, _FALLEN_FLOOR). */
int pc_wheeled_condition(const pc_wheeled_params *p, const pc_wheeled_state *s, pc_refusal *r);

/* Advance `s` over dt by `substeps` RK4 steps with the torques held.  `taken` (may be NULL)
 * receives `substeps`, or the 1-based substep whose end state failed pc_wheeled_condition;
 * on any refusal `s` is unchanged. */
int pc_wheeled_step(const pc_wheeled_params *p, pc_wheeled_state *s, double tau_l, double tau_r, double tau_d,
                    double dt, int substeps, int *taken, pc_refusal *r);

/* T + U [J] of seed 000 (8), (11), (12), the floor at z = 0. */
double pc_wheeled_energy(const pc_wheeled_params *p, const pc_wheeled_state *s);

/* out[0..13] = theta, psi, phi, dtheta, dpsi, dphi, x, y, omega_l, omega_r, enc_l, enc_r, gyro,
 * energy: the encoders read theta_l,r - psi (10) rounded to a multiple of `count` [rad]. */
void pc_wheeled_sensors(const pc_wheeled_params *p, const pc_wheeled_state *s, double count, double *out);

/* One communication step from t over h: torques x[0..2] (tau_l, tau_r, tau_d), the push added
 * over the steps starting in its window, then pc_wheeled_step and the sensors into x[3..16]. */
int pc_wheeled_step_io(const pc_wheeled_params *p, pc_wheeled_state *s, const pc_wheeled_settings *settings,
                       double *x, double t, double h, pc_refusal *r);

/* pc_io_fn of the compiled loop: pc_wheeled_step_io on a pc_wheeled_context. */
int pc_wheeled_io(void *context, double *x, double t, double h, pc_refusal *r);

#endif
