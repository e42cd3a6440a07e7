/* The 5R parallel robot (thesis 003 ch. 4-5, architecture 7.8-7.11) and the actuated 5R (its
 * drives' armature circuits inside the ODE): the chapter 4-5 algorithm specialised to two
 * planar RR chains, with scalars.
 *
 * State z = [q (7), dq (7), i_1 .. i_n] with q = [x, y, z, theta11, theta12, theta21, theta22]
 * (7.12) and the armature currents of n motors.  Chain 2 lives in a frame mirrored by
 * E_2 = diag(-1, 1, -1) (7.4); the world convention of the interface (angles counter-clockwise
 * from +x) is q1 = theta11, q2 = pi - theta21 (plant/fivebar.py: world_angles, world_rates).
 *
 * Counter-masses (seed 001 (55)-(64)) are absorbed into each chain's link mass, centre of mass
 * and inertia by the Python set-up (plant.fast5r.composite_link): the kernel does not see them.
 */
#ifndef PC_FIVEBAR_H
#define PC_FIVEBAR_H

#include "pc_common.h"

/* One RR chain in its own base frame N_k (Table 2). */
typedef struct {
    double l1, l2;     /* link lengths [m] */
    double lg1, lg2;   /* centre of mass of each link from its proximal joint [m] */
    double m1, m2;     /* link masses [kg] */
    double Jz1, Jz2;   /* link inertias about z at the centre of mass [kg m^2] */
    double J_rotor;    /* rotor inertia on the actuated joint (4.139-4.140) [kg m^2] */
} pc_fivebar_chain;

/* The mechanism: read-only after set-up. */
typedef struct {
    double l0;                 /* half the base distance: chain 1 at (+l0, 0), chain 2 at (-l0, 0) [m] */
    double m0;                 /* end-effector (platform) point mass [kg] */
    double gravity[2];         /* (g_x, g_y) in the world frame [m/s^2] */
    pc_fivebar_chain chain[2];
} pc_fivebar_params;

/* One motor row of the actuated 5R (motor.MotorParams; mu = 0 for a LuGre drive, whose bristle
 * torque is held from outside). */
typedef struct {
    double joint;      /* the world joint it drives: 0 (q1) or 1 (q2) */
    double R, L;       /* armature resistance [ohm] and inductance [H] */
    double kt, ke;     /* torque [N m/A] and back-emf [V s/rad] constants */
    double b;          /* viscous friction [N m s/rad] */
    double mu;         /* Coulomb friction [N m] */
    double omega_eps;  /* speed of the tanh smoothing [rad/s] */
} pc_fivebar_motor;

/* How a step integrates and what it accepts (plant.simulator.PlantSimulator's settings). */
typedef struct {
    double lambda;          /* Baumgarte lambda of (5.66) [1/s] */
    double substeps;        /* RK4 steps per step */
    double count;           /* one encoder count [rad] */
    double residual_stop;   /* largest loop-closure residual accepted [m] (RESIDUAL_STOP) */
    double singular_stop;   /* smallest singularity measure accepted (SINGULAR_STOP) */
    double offset[2];       /* the encoders' zero errors [rad] */
} pc_fivebar_settings;

/* The state's layout; `current` has one entry per motor. */
typedef struct {
    double q[7];
    double dq[7];
    double current[];
} pc_fivebar_state;

/* Chain terms (scratch, one chain, world-aligned: E_k applied to the tip rows). */
typedef struct {
    double tip[2];      /* E_k tip, tip (4.4) in the chain frame */
    double J[4];        /* E_k J_v, row-major 2x2 (4.13) */
    double a_bias[2];   /* E_k times the velocity-quadratic tip acceleration (4.57-4.58) */
    double M[4];        /* joint-space inertia with the rotor (4.85, 4.139-4.140), row-major */
    double v[2];        /* Coriolis and centripetal efforts (4.86) */
    double g[2];        /* gravity efforts (4.87) */
} pc_fivebar_terms;

/* What a step reports about the new state (what PlantSimulator checks and publishes). */
typedef struct {
    double finite;        /* 1 if every state entry is finite, else 0 */
    double residual;      /* norm of the position residual (5.18) [m] */
    double measures[3];   /* sin theta12, sin theta22, sin(phi12 - phi22) */
    /* the FiveBarPlant outputs, world convention (fmus.slave.declarations.PLANT_OUTPUTS order) */
    double q1, q2, dq1, dq2, x, y, dx, dy, q1_enc, q2_enc;
} pc_fivebar_report;

/* The inverse dynamics terms of (5.67-5.77): M_M ddq# + v_M + g_M = Z^T u* (5.74). */
typedef struct {
    double M[4];   /* M_M (5.75), row-major */
    double v[2];   /* v_M (5.76) */
    double g[2];   /* g_M (5.77) */
    double Z[4];   /* Z = U^T C (5.72), row-major */
    double c[7];   /* chain accelerations at ddq# = 0 (5.69) */
} pc_fivebar_inverse;

/* What a step holds constant: the derivative's model for pc_rk4. */
typedef struct {
    const pc_fivebar_params *params;
    const pc_fivebar_motor *motors;
    const double *voltages;   /* one per motor [V] */
    double u1, u2;            /* efforts on theta11, theta21 besides the motors' [N m] */
    double lambda;            /* Baumgarte lambda [1/s] */
    int n_motors;
} pc_fivebar_held;

/* The compiled loop's buffers (pc_io_fn context). */
typedef struct {
    const pc_fivebar_params *params;
    const pc_fivebar_settings *settings;
    const pc_fivebar_motor *motors;   /* n_motors rows */
    double *state;                    /* z (14 + n_motors) */
    const double *voltages;           /* held over the step, one per motor (actuated_io) */
    const double *held;               /* (u1, u2) on theta11, theta21 (actuated_io), or NULL: none */
    double *scratch;                  /* PC_FIVEBAR_SCRATCH(14 + n_motors) doubles */
    int n_motors;
    int first;                        /* index in x of the first output (actuated_io) */
} pc_fivebar_context;

/* Refusal codes; a refused step changes nothing. */
enum {
    PC_FIVEBAR_NONFINITE_INPUT = 1,   /* index: 0 u1, 1 u2, 2 + n voltage n; 0/1 tau1/tau2 in plant_io */
    PC_FIVEBAR_NONFINITE_STATE = 2,   /* index: the first non-finite entry of z (currents checked first) */
    PC_FIVEBAR_DIVERGED = 3,          /* value: the residual */
    PC_FIVEBAR_SINGULAR = 4           /* index: the measure (report.measures), value: it */
};

/* Scratch of a step of n states: the trial state (n), RK4's work (5 n) and the trigonometry
 * of the last trial state (PC_FIVEBAR_TRIG_WORDS, fivebar.c: read by the next step when it
 * starts from that state, checked against it; allocate it zeroed). */
#define PC_FIVEBAR_TRIG_WORDS 17
#define PC_FIVEBAR_SCRATCH(n) (6 * (n) + PC_FIVEBAR_TRIG_WORDS)

extern const pc_field pc_fivebar_params_fields[];
extern const pc_field pc_fivebar_chain_fields[];
extern const pc_field pc_fivebar_motor_fields[];
extern const pc_field pc_fivebar_settings_fields[];
extern const pc_field pc_fivebar_state_fields[];
extern const pc_field pc_fivebar_terms_fields[];
extern const pc_field pc_fivebar_report_fields[];
extern const pc_field pc_fivebar_inverse_fields[];

int pc_fivebar_context_size(void);
/* PC_FIVEBAR_SCRATCH(n), for callers that cannot read the macro. */
int pc_fivebar_scratch_words(int n);

void pc_fivebar_chain_terms(const pc_fivebar_params *p, int k, double a, double b, double da, double db,
                            pc_fivebar_terms *t);
void pc_fivebar_derivative(const pc_fivebar_params *p, const double *y, double u1, double u2, double lambda,
                           double *dydt);
void pc_fivebar_actuated_derivative(const void *held, const double *z, double *dzdt);
void pc_fivebar_advance(const pc_fivebar_held *held, double *z, double dt, int substeps, double *work);
void pc_fivebar_residual(const pc_fivebar_params *p, const double *y, double *out);
void pc_fivebar_report_of(const pc_fivebar_params *p, const pc_fivebar_settings *s, const double *y,
                          pc_fivebar_report *out);
int pc_fivebar_step(const pc_fivebar_params *p, const pc_fivebar_settings *s, const pc_fivebar_motor *motors,
                    int n_motors, const double *z, const double *voltages, double u1, double u2, double dt,
                    double *scratch, pc_fivebar_report *report, pc_refusal *refusal);
void pc_fivebar_project(const pc_fivebar_params *p, double *y, int iterations);
void pc_fivebar_inverse_terms(const pc_fivebar_params *p, const double *q, const double *dq,
                              pc_fivebar_inverse *out);
void pc_fivebar_terms_of(const void *model, const double *q, const double *dq, double *terms);
int pc_fivebar_plant_io(void *context, double *x, double t, double h, pc_refusal *refusal);
int pc_fivebar_actuated_io(void *context, double *x, double t, double h, pc_refusal *refusal);

#endif
