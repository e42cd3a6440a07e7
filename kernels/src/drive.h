/* The DC drive (thesis 003: 4.162, B.2, appendix C, 7.2.10) with the bench's imperfections
 * (PWM quantum, current offset and noise) and the LuGre friction with stiction (Canudas de Wit,
 * Olsson, Astrom, Lischinsky, IEEE TAC 40(3), 1995; equations (1)-(4) of the paper).
 *
 * Three caller-owned structs of doubles (motor.Drive owns them as numpy buffers):
 *   pc_controller  K(z) of C.5: its coefficients, then its state (last outputs and errors);
 *   pc_drive       the motor's constants, the step's coefficients (set by prepare_step in
 *                  Python: a, g of i(t+h) = a i + g (v - ke omega) and the mean weights), the
 *                  imperfections, then the run state (current, voltage, sub-step, sample count);
 *   pc_lugre       the LuGre parameters, then the bristle deflection z.
 * Design-time work (pole placement, the step coefficients) stays in Python (motor/).
 *
 * A step returns PC_OK or a PC_DRIVE_* code and, on a refusal, has changed nothing. */
#ifndef PC_DRIVE_H
#define PC_DRIVE_H

#include <stdint.h>

#include "pc_common.h"

/* Refusal codes (shared with the observer). */
#define PC_DRIVE_NONFINITE_INPUT 1   /* an input is NaN or infinite; index: pc_drive_inputs */
#define PC_DRIVE_UNPREPARED_STEP 2   /* h is not the step the coefficients are for (Python prepares it) */
#define PC_DRIVE_DIVERGED 3          /* the current (index 0) or torque (index 1) after the step is not finite */

/* The drive's inputs as pc_refusal.index names them (the order its checks run). */
enum { PC_DRIVE_OMEGA = 0, PC_DRIVE_I_REF = 1, PC_DRIVE_V_REF = 2, PC_DRIVE_I_HAT = 3 };

/* K(z) = (alpha z^2 + beta z + gamma) / ((z - 1)(z - delta)) (C.5), saturated at +-v_max. */
typedef struct {
    double alpha, beta, gamma, delta;   /* C.5, placed by motor.current_controller (C.8-C.12) */
    double v_max;                       /* saturation [V] */
    /* state: the last two saturated outputs u [V] and errors e [A] */
    double u1, u2, e1, e2;
} pc_controller;

typedef struct {
    double current_mode;    /* 1: K(z) on i_ref, i_hat; 0: voltage mode (v_ref applied) */
    double mean_torque;     /* 1: tau over the step's mean current; 0: at the step's end */
    double ke, kt, b, mu, omega_eps, v_max;   /* B.2, 4.162 [V s/rad, N m/A, N m s/rad, N m, rad/s, V] */
    double T;               /* controller period [s] */
    double sample_phase;    /* the sub-step of each period that samples, 0 <= sample_phase < substeps */
    double h;               /* the step length the coefficients below are for [s] (NaN: none) */
    double a, g;            /* i(t+h) = a i + g (v - ke omega)  (4.162 over the step) */
    double w_i, w_u;        /* mean current over the step = w_i i + w_u (v - ke omega) */
    double substeps;        /* n = T / h, whole: the steps of a controller period */
    /* state */
    double i;               /* armature current [A] */
    double v;               /* voltage applied over the last step [V] */
    double phase;           /* the next step's sub-step in its period, 0 ... substeps - 1 (whole) */
    /* the bench's imperfections (0: ideal) */
    double pwm_quantum;     /* v_max / pwm_counts [V] */
    double i_offset;        /* offset of the current the loop reads [A] */
    double i_noise;         /* standard deviation of its noise [A] */
    double noise_seed, noise_instance;   /* whole numbers < 2^53 (pc_drive_gaussian) */
    /* state */
    double sample;          /* controller samples taken so far */
} pc_drive;

/* dz/dt = omega - sigma0 |omega| z / G(omega) (1), G = Fc + (Fs - Fc) exp(-(omega/omega_s)^2) (3),
 * F = sigma0 z + sigma1 dz/dt + sigma2 omega (4). */
typedef struct {
    double Fc, Fs;          /* Coulomb and break-away torques [N m] */
    double omega_s;         /* Stribeck speed [rad/s] */
    double sigma0;          /* bristle stiffness [N m/rad] */
    double sigma1, sigma2;  /* bristle damping, viscous coefficient [N m s/rad] */
    /* state */
    double z;               /* bristle deflection [rad] */
} pc_lugre;

/* A voltage sample not yet kept (pc_drive_peek_voltage, pc_drive_commit). */
typedef struct {
    double v;        /* the voltage applied over the step [V] */
    double e;        /* the controller's error at this sample [A] */
    double sampled;  /* 1: the controller sampled at this step */
    double phase;    /* the sub-step after the step */
} pc_drive_sample;

/* The drive's buffers for the compiled loop's pc_drive_io (lugre NULL: the tanh friction of B.2). */
typedef struct {
    pc_drive *drive;
    pc_controller *controller;
    pc_lugre *lugre;
} pc_drive_context;

extern const pc_field pc_controller_fields[];
extern const pc_field pc_drive_fields[];
extern const pc_field pc_lugre_fields[];

/* K(z) */
double pc_controller_update(pc_controller *c, double i_ref, double i_meas);

/* B.2 and 4.162 of pc_motor.h, exported for Python (motor.shaft_torque, motor.armature_current_rate). */
double pc_drive_shaft_torque(double kt, double b, double mu, double omega_eps, double i, double omega);
double pc_drive_armature_rate(double R, double L, double ke, double v, double i, double omega);

/* The stateless noise: SplitMix64 (Steele, Lea, Flood 2014) over (seed, instance, step). */
uint64_t pc_splitmix64(uint64_t x);
double pc_drive_uniform(uint64_t seed, uint64_t instance, uint64_t step);
double pc_drive_gaussian(uint64_t seed, uint64_t instance, uint64_t step);

/* LuGre (1)-(4); pc_lugre_advance solves (1) exactly over h with omega held: out = {z, F_end, F_mean}. */
double pc_lugre_stribeck(const pc_lugre *f, double omega);
double pc_lugre_bristle_rate(const pc_lugre *f, double z, double omega);
double pc_lugre_force(const pc_lugre *f, double z, double omega);
double pc_lugre_steady_deflection(const pc_lugre *f, double omega);
void pc_lugre_phi(double x, double phi[2]);
void pc_lugre_advance(const pc_lugre *f, double z0, double omega, double h, double out[3]);
void pc_lugre_push(const pc_lugre *f, int kind, double a, double b, double mass, double h, int n, double *rows);

/* The voltage of a step: peek (nothing changed), commit (kept with the end current i). */
int pc_drive_peek_voltage(const pc_drive *d, const pc_controller *c, double i_ref, double v_ref, double i_hat,
                          double h, pc_drive_sample *s, pc_refusal *r);
void pc_drive_commit(pc_drive *d, pc_controller *c, const pc_drive_sample *s, double i);
int pc_drive_sample_voltage(pc_drive *d, pc_controller *c, double i_ref, double v_ref, double i_hat, double h,
                            double *v, pc_refusal *r);

/* The shaft torque of the present current at speed omega (B.2, or kt i - F (4) with f). */
double pc_drive_torque(const pc_drive *d, const pc_lugre *f, double omega);

/* One step with inputs held: out = {tau, v, i}.  f: the LuGre friction (advanced with the step)
 * or NULL (B.2's tanh). */
int pc_drive_step(pc_drive *d, pc_controller *c, pc_lugre *f, double i_ref, double v_ref, double omega,
                  double i_hat, double h, double out[3], pc_refusal *r);

/* DCMotorDrive: x = [i_ref, v_ref, omega, i_hat | tau, v, i], the outputs written only on PC_OK. */
int pc_drive_io(void *context, double *x, double t, double h, pc_refusal *r);

/* The Python layer's calls (three pointers: ctypes' cost grows with the arguments):
 * x = [i_ref, v_ref, omega, i_hat, h | tau, v, i], the outputs also on PC_DRIVE_DIVERGED (the
 * refused values, for the message); pc_drive_sample_x puts pc_drive_sample_voltage's v in x[6]. */
int pc_drive_step_x(void *context, double *x, pc_refusal *r);
int pc_drive_sample_x(void *context, double *x, pc_refusal *r);

#endif
