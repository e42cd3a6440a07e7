/* One DC motor drive in a native FMU (docs/native.md): its set-up as fmus.slave.declarations.build_drive,
 * motor.Drive and Drive.start make it, with their checks in their order and their messages;
 * its step (drive.c) with the step coefficients of a new step length (electrics.c) and the
 * kernel's refusals in motor.kernel.DRIVE_REASONS' words; the check of restored model data.
 *
 * Shared by the adapters of the models that hold drives: DCMotorDrive (its variables' names
 * as they are) and ActuatedFiveBarPlant (each drive's variables followed by "1" or "2": the
 * `suffix` every message appends to a variable's name, as build_drive(slave, suffix) does).
 *
 * The current controller's design (app. C): python-control's, made when the FMU is built for
 * its parameters then and for each motor preset at its T (pcn_drive_design: the twin's
 * coefficients bit for bit), and for any other design values (R, L, kt, ke, b, J_rotor of the
 * design's motor, T) kernels/src/design.c's pc_current_design at set-up.  The motor presets
 * travel as data too (pcn_motor_presets).
 */
#ifndef PCN_DRIVE_SETUP_H
#define PCN_DRIVE_SETUP_H

#include "drive.h"
#include "pcn_text.h"

/* The motor's fields in fmus.slave.declarations.MOTOR_PARAMETERS' order (their FMU variables R ... sigma1,
 * J_design: J_design sets MotorParams' J_rotor). */
enum {
    PCN_MOTOR_R, PCN_MOTOR_L, PCN_MOTOR_KT, PCN_MOTOR_KE, PCN_MOTOR_B, PCN_MOTOR_MU, PCN_MOTOR_V_MAX,
    PCN_MOTOR_OMEGA_EPS, PCN_MOTOR_MU_S, PCN_MOTOR_OMEGA_S, PCN_MOTOR_SIGMA0, PCN_MOTOR_SIGMA1, PCN_MOTOR_J_ROTOR,
    PCN_MOTOR_FIELDS
};
/* fmus.slave.declarations.DESIGN_PARAMETERS: R_design, L_design, kt_design, ke_design, b_design. */
#define PCN_DESIGN_FIELDS 5
/* What a design depends on (motor.current_controller.design_key, the poles fixed):
 * R, L, kt, ke, b, J_rotor of the design's motor, then T. */
#define PCN_DESIGN_KEY 7

/* The motor presets (motor.presets.MOTOR_PRESETS), sorted by name. */
typedef struct {
    int count;
    const char *const *names;
    const double *values;   /* count rows of PCN_MOTOR_FIELDS, in the names' order */
} pcn_motor_presets;

/* The current controllers designed at the FMU's build: the first for its parameters then,
 * the others for the motor presets at its T (fmus.native.models.drive_design); the poles any
 * other design places (motor.current_controller.THESIS_POLES). */
typedef struct {
    int count;
    const double *keys;           /* count rows of the PCN_DESIGN_KEY values each was designed for */
    const double *coefficients;   /* count rows of alpha, beta, gamma, delta (C.5) */
    const char *error;            /* "" or the message the first's design failed with (motor.drive._design's) */
    const double *poles;          /* the three requested closed-loop poles */
} pcn_drive_design;

/* A drive's parameters, as its FMU variables hold them. */
typedef struct {
    const char *suffix;                   /* appended to every variable's name in messages */
    const char *preset;
    double motor[PCN_MOTOR_FIELDS];       /* -1: the preset's */
    double design[PCN_DESIGN_FIELDS];     /* -1: the drive's */
    const char *friction;
    int pwm_counts;
    double current_offset, current_noise;
    int noise_seed, noise_instance;
    const char *mode, *method, *torque_output;   /* variables without suffix (one for all drives) */
    double T;
    int sample_phase;
} pcn_drive_parameters;

/* A drive's model data: what its steps need beside the kernel's structs (configuration), then
 * the kernel's structs (the LuGre one unused with the tanh friction). */
typedef struct {
    double R, L;       /* the motor's, for the coefficients of a new step length */
    double method;     /* PC_ELECTRICS_* */
    double has_lugre;  /* 1: friction 'lugre' */
    pc_drive drive;
    pc_controller controller;
    pc_lugre lugre;
} pcn_drive_data;

#define PCN_DRIVE_WORDS ((long)(sizeof(pcn_drive_data) / sizeof(double)))

/* build_drive(slave, suffix, mode=, method=, T=, torque_output=, sample_phase=): the checks in
 * their order, then the drive as motor.Drive.__init__ leaves it (not started).  Refused: the
 * message in `why`, nonzero, `out` unchanged. */
int pcn_drive_build(const pcn_drive_parameters *p, const pcn_motor_presets *presets, const pcn_drive_design *design,
                    pcn_drive_data *out, pcn_text *why);

/* Drive.start(omega0, i0): electrical steady state, v0 = R i0 + ke omega0 saturated, the
 * controller restarted holding it, the bristles at their steady deflection. */
int pcn_drive_start(pcn_drive_data *d, double omega0, double i0, pcn_text *why);

/* Drive.torque(omega): the shaft torque of the present current. */
double pcn_drive_torque(const pcn_drive_data *d, double omega);

/* Drive.prepare_step: the coefficients of a new step length h (checked by the FMU's step rule;
 * ActuatedFiveBarPlant prepares its drives before pc_actuated_step). */
void pcn_drive_prepare(pcn_drive_data *d, double h);

/* The steps a drive accepts, in CurrentLoopSteps' words: sampled in current mode, any h in voltage mode. */
const char *pcn_drive_accepted_steps(int current_mode);

/* Drive.step: one step with the inputs held; out = {tau, v, i}.  Refused: DRIVE_REASONS'
 * message (with euler's divergence explained) in `why`, nonzero, nothing changed. */
int pcn_drive_step(pcn_drive_data *d, double i_ref, double v_ref, double omega, double i_hat, double h,
                   double out[3], pcn_text *why);

/* Whether restored model data fits the drive `built` for the same parameters: equal
 * configuration words, the coefficients of its step length, a whole sub-step counter, finite
 * run words; all zero (a state taken before set-up) fits. */
int pcn_drive_check_data(const pcn_drive_data *built, const pcn_drive_data *data, pcn_text *why);

#endif
