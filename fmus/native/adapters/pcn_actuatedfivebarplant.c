/* Native ActuatedFiveBarPlant (fmus/slaves/parcosim_actuatedfivebarplant.py) over pc_actuated_step.
 *
 * The set-up is the slave's: its own checks (T, L1, L2), the plant's (pcn_plant_setup.c:
 * build_plant) and each drive's (pcn_drive_setup.c: build_drive with the suffix "1" or "2",
 * the current controllers: designed at the build as data, or by design.c), then plant.actuated.ActuatedPlant's
 * motor rows and LuGre models (the drive's with sigma2 = 0: b stays in the ODE).  A step is
 * ActuatedPlant.step's one C call (RK4, the C kernel, no projection): the plant's step-size
 * rule, the armature poles' RK4 stability, the drives' coefficients for h, pc_actuated_step;
 * its refusals in ActuatedPlant's words.  With `project`, the twin's composition of the same
 * kernels (ActuatedPlant.advance: sample, integrate, project, judge).
 * Current mode: steps h = T / n, the controllers sampling on sub-step sample_phase (the
 * drives' counters); voltage mode: any step.  Model data (FMU state): the plant's
 * configuration, z = (q, dq, i1, i2), the motor rows, the two drives (pcn_drive_data).
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "actuated.h"
#include "model_config.h"
#include "pcn_drive_setup.h"
#include "pcn_model.h"
#include "pcn_plant_setup.h"
#include "pcn_sampling.h"

#define ABSURD 1e6   /* fmus/slave/refusals.py */
#define TINY 1e-12
#define PRESET_VALUE (-1.0)
#define MIN_STEP 1e-9
#define RK4_REAL_STABILITY 2.785293563405282   /* plant/simulator.py */
#define FIRST 6                                /* x: i_ref, i_hat, v_ref of each drive, then the outputs */
#define N_X (FIRST + 11 + 6)
#define PROJECTIONS 3                          /* PlantSimulator.project's Newton iterations */

typedef struct {
    pcn_plant_config config;
    double z[PCN_PLANT_STATES + 2];
    pc_fivebar_motor motors[2];
    pcn_drive_data drive[2];
} actuated;

#define DATA_WORDS ((long)(sizeof(actuated) / sizeof(double)))
#define SCRATCH_WORDS PC_FIVEBAR_SCRATCH(PCN_PLANT_STATES + 2)

static const pcn_motor_presets PRESETS = {PCN_PRESET_NAMES_COUNT, pcn_preset_names, pcn_preset_motor};

static actuated *data_of(const pcn_instance *in) { return (actuated *)in->data; }
static int current_mode(const pcn_instance *in) { return strcmp(in->string[PCN_SLOT_mode], "current") == 0; }

/* Drive n's (0, 1) parameters as the variables with its suffix hold them. */
static pcn_drive_parameters parameters(const pcn_instance *in, int n)
{
    const double *r = in->real;
    const int *k = in->integer;
    char *const *s = in->string;
    if (n == 0)
        return (pcn_drive_parameters){
            .suffix = "1", .preset = s[PCN_SLOT_preset1],
            .motor = {r[PCN_SLOT_R1], r[PCN_SLOT_L1], r[PCN_SLOT_kt1], r[PCN_SLOT_ke1], r[PCN_SLOT_b1],
                      r[PCN_SLOT_mu1], r[PCN_SLOT_v_max1], r[PCN_SLOT_omega_eps1], r[PCN_SLOT_mu_s1],
                      r[PCN_SLOT_omega_s1], r[PCN_SLOT_sigma01], r[PCN_SLOT_sigma11], r[PCN_SLOT_J_design1]},
            .design = {r[PCN_SLOT_R_design1], r[PCN_SLOT_L_design1], r[PCN_SLOT_kt_design1], r[PCN_SLOT_ke_design1],
                       r[PCN_SLOT_b_design1]},
            .friction = s[PCN_SLOT_friction1], .pwm_counts = k[PCN_SLOT_pwm_counts1],
            .current_offset = r[PCN_SLOT_current_offset1], .current_noise = r[PCN_SLOT_current_noise1],
            .noise_seed = k[PCN_SLOT_noise_seed1], .noise_instance = k[PCN_SLOT_noise_instance1],
            .mode = s[PCN_SLOT_mode], .method = "exact", .torque_output = "end", .T = r[PCN_SLOT_T],
            .sample_phase = k[PCN_SLOT_sample_phase]};
    return (pcn_drive_parameters){
        .suffix = "2", .preset = s[PCN_SLOT_preset2],
        .motor = {r[PCN_SLOT_R2], r[PCN_SLOT_L2], r[PCN_SLOT_kt2], r[PCN_SLOT_ke2], r[PCN_SLOT_b2], r[PCN_SLOT_mu2],
                  r[PCN_SLOT_v_max2], r[PCN_SLOT_omega_eps2], r[PCN_SLOT_mu_s2], r[PCN_SLOT_omega_s2],
                  r[PCN_SLOT_sigma02], r[PCN_SLOT_sigma12], r[PCN_SLOT_J_design2]},
        .design = {r[PCN_SLOT_R_design2], r[PCN_SLOT_L_design2], r[PCN_SLOT_kt_design2], r[PCN_SLOT_ke_design2],
                   r[PCN_SLOT_b_design2]},
        .friction = s[PCN_SLOT_friction2], .pwm_counts = k[PCN_SLOT_pwm_counts2],
        .current_offset = r[PCN_SLOT_current_offset2], .current_noise = r[PCN_SLOT_current_noise2],
        .noise_seed = k[PCN_SLOT_noise_seed2], .noise_instance = k[PCN_SLOT_noise_instance2], .mode = s[PCN_SLOT_mode],
        .method = "exact", .torque_output = "end", .T = r[PCN_SLOT_T], .sample_phase = k[PCN_SLOT_sample_phase]};
}

/* ActuatedFiveBarPlant.setup up to the ActuatedPlant: the configuration, z at rest, the drives
 * as built (not started: current, voltage and controller at 0), the motor rows. */
static int build(const pcn_instance *in, actuated *a, pcn_text *why)
{
    const double *r = in->real, T = r[PCN_SLOT_T];
    if (isfinite(T) && fabs(T) > ABSURD)
        return pcn_addf(why, "parameter T = %r is absurd: |T| must be <= %G (SI units)", T, ABSURD), 1;
    if (0.0 < T && T < MIN_STEP) return pcn_addf(why, "parameter T = %r s must be >= %G s", T, MIN_STEP), 1;
    const double L[2] = {r[PCN_SLOT_L1], r[PCN_SLOT_L2]};
    for (int n = 0; n < 2; ++n)
        if (L[n] != PRESET_VALUE && 0.0 <= L[n] && L[n] < TINY)
            return pcn_addf(why, "parameter L%d = %r H must be > 0: the drives inside the plant integrate the "
                            "armature current (use a separate DCMotorDrive with method 'quasi_static' for L = 0)",
                            n + 1, L[n]), 1;
    memset(a, 0, sizeof *a);
    if (pcn_plant_setup(in, &a->config, a->z, why)) return 1;
    const pcn_drive_design designs[2] = {
        {PCN_DESIGN1_KEYS_WORDS / PCN_DESIGN_KEY, pcn_design1_keys, pcn_design1_coefficients, pcn_design1_error[0],
         pcn_current_poles},
        {PCN_DESIGN2_KEYS_WORDS / PCN_DESIGN_KEY, pcn_design2_keys, pcn_design2_coefficients, pcn_design2_error[0],
         pcn_current_poles}};
    for (int n = 0; n < 2; ++n) {
        pcn_drive_parameters p = parameters(in, n);
        if (pcn_drive_build(&p, &PRESETS, &designs[n], &a->drive[n], why)) return 1;
    }
    for (int n = 0; n < 2; ++n) {   /* ActuatedPlant._motors: a LuGre drive's mu is its bristles' */
        const pcn_drive_data *d = &a->drive[n];
        a->motors[n] = (pc_fivebar_motor){.joint = n, .R = d->R, .L = d->L, .kt = d->drive.kt, .ke = d->drive.ke,
                                          .b = d->drive.b, .mu = d->has_lugre != 0.0 ? 0.0 : d->drive.mu,
                                          .omega_eps = d->drive.omega_eps};
    }
    return 0;
}

/* ActuatedPlant.lugre_models[n]: drive n's LuGre parameters with sigma2 = 0. */
static pc_lugre bristle_model(const pcn_drive_data *d)
{
    pc_lugre f = d->lugre;
    f.sigma2 = 0.0;
    f.z = NAN;
    return f;
}

/* The world speed of joint n (plant.fivebar.world_rates). */
static double joint_speed(const double *z, int n) { return n == 0 ? z[10] : -z[12]; }

/* The outputs: the plant's, then each drive's shaft torque (ActuatedPlant.shaft_torques), v, i. */
static void publish(pcn_instance *in, const pc_fivebar_report *report)
{
    const actuated *a = data_of(in);
    pcn_plant_publish(in, report);
    const int tau[2] = {PCN_SLOT_tau1, PCN_SLOT_tau2}, v[2] = {PCN_SLOT_v1, PCN_SLOT_v2},
              i[2] = {PCN_SLOT_i1, PCN_SLOT_i2};
    for (int n = 0; n < 2; ++n) {
        const pcn_drive_data *d = &a->drive[n];
        const pc_fivebar_motor *m = &a->motors[n];
        const double omega = joint_speed(a->z, n);
        double torque = pc_drive_shaft_torque(m->kt, m->b, m->mu, m->omega_eps, d->drive.i, omega);
        if (d->has_lugre != 0.0) {
            const pc_lugre f = bristle_model(d);
            torque -= pc_lugre_force(&f, d->lugre.z, omega);
        }
        in->real[tau[n]] = torque;
        in->real[v[n]] = d->drive.v;
        in->real[i[n]] = d->drive.i;
    }
}

static int setup(pcn_instance *in, pcn_text *why)
{
    actuated a;
    if (build(in, &a, why)) return 1;
    *data_of(in) = a;
    pc_fivebar_report report;
    pc_fivebar_report_of(&a.config.params, &a.config.settings, a.z, &report);
    publish(in, &report);
    return 0;
}

static const char *accepted_steps(const pcn_instance *in)
{
    return pcn_drive_accepted_steps(current_mode(in));
}

/* CurrentLoopSteps.check_step_size: in current mode h divides T, with each drive's counter. */
static int check_step(pcn_instance *in, double t, double h, pcn_text *why)
{
    if (!current_mode(in)) return 0;
    for (int n = 0; n < 2; ++n) {
        const pc_drive *k = &data_of(in)->drive[n].drive;
        pcn_sampling counted = {k->phase, k->substeps};
        if (pcn_sampling_check(&counted, in, in->real[PCN_SLOT_T], in->integer[PCN_SLOT_sample_phase], t, h, why))
            return 1;
    }
    return 0;
}

/* ActuatedPlant._check_rk4_stability: each armature pole -R/L within RK4's interval. */
static int check_rk4_stability(const actuated *a, double dt, pcn_text *why)
{
    const double h = dt / a->config.settings.substeps;
    for (int n = 0; n < 2; ++n) {
        const double R = a->drive[n].R, L = a->drive[n].L, x = R * h / L;
        if (!(x > RK4_REAL_STABILITY)) continue;
        char xs[32], stability[32], tau[32], substeps[64];
        snprintf(xs, sizeof xs, "%.4g", x);
        snprintf(stability, sizeof stability, "%.4g", RK4_REAL_STABILITY);
        snprintf(tau, sizeof tau, "%.3g", L / R);
        snprintf(substeps, sizeof substeps, "%.0f", ceil(dt * R / (L * 2.0)));
        return pcn_addf(why, "drive on joint %d: RK4 steps of %G s are unstable for its armature circuit: R h / L = "
                        "%s > %s (L/R = %s s); use substeps >= %s or dopri5", n + 1, h, xs, stability, tau,
                        substeps), 1;
    }
    return 0;
}

/* ActuatedPlant._check_inputs: the first input that is not finite, named with its joint. */
static int check_inputs(const double *x, pcn_text *why)
{
    static const char *const names[3] = {"i_ref", "i_hat", "v_ref"};
    for (int k = 0; k < 3; ++k)
        for (int n = 0; n < 2; ++n)
            if (!isfinite(x[3 * n + k]))
                return pcn_addf(why, "input %s%d = %r is not finite", names[k], n + 1, x[3 * n + k]), 1;
    return 0;
}

/* ActuatedPlant._currents_refusal: the step's armature currents (trial's last two) not all finite. */
static int currents_refusal(const double *trial, double t, const char *held, pcn_text *why)
{
    const double *i = trial + PCN_PLANT_STATES;
    const int bad = isfinite(i[0]) ? 1 : 0;
    pcn_addf(pcn_timed(why), "armature currents [%r, %r] after the step from t = %G s (%s) are not finite", i[0], i[1],
             t, held);
    pcn_quantify(why, PC_FIVEBAR_NONFINITE_STATE, "nonfinite_state", bad ? "i2" : "i1", i[bad], "", t);
    return 1;
}

/* ActuatedPlant._refuse_kernel_step: the refusal of a pc_actuated_step that returned `status`. */
static void refusal_text(const actuated *a, int status, const pc_refusal *r, const double *x, const double *trial,
                         double t, double h, pcn_text *why)
{
    if (status == PC_FIVEBAR_NONFINITE_INPUT && check_inputs(x, why)) return;
    double voltages[2];
    for (int n = 0; n < 2; ++n) {   /* the voltages the drives would have sampled */
        pc_drive_sample sample;
        pc_drive_peek_voltage(&a->drive[n].drive, &a->drive[n].controller, x[3 * n], x[3 * n + 2], x[3 * n + 1], h,
                              &sample, NULL);
        voltages[n] = sample.v;
    }
    pcn_text held;
    pcn_clear(&held);
    pcn_addf(&held, "v1 = %r V, v2 = %r V held", voltages[0], voltages[1]);
    if (status == PC_FIVEBAR_NONFINITE_INPUT) {
        pcn_addf(pcn_timed(why), "integration failed in the step from t = %G s (%s): the held input %d = %r is not "
                 "finite", t, held.text, r->index, r->value);
        char input[32];
        snprintf(input, sizeof input, "input %d", r->index);
        pcn_quantify(why, status, "nonfinite_input", input, r->value, "N m", t);
    } else if (status == PC_FIVEBAR_NONFINITE_STATE && r->index >= PCN_PLANT_STATES) {
        currents_refusal(trial, t, held.text, why);
    } else {
        pcn_plant_refusal(&a->config, status, r, trial, t, h, held.text, why);
    }
}

/* ActuatedPlant.step with `project` (not one C call): the inputs checked, each drive's voltage
 * sampled, the bristles advanced with the joint speeds held, the whole state integrated
 * (pc_fivebar_advance), the currents checked, the plant's part projected and judged as
 * PlantSimulator.accept does; kept only if accepted. */
static int projected_step(pcn_instance *in, actuated *a, const double *x, double t, double h, pcn_text *why)
{
    if (check_inputs(x, why)) return 1;
    pc_drive_sample samples[2];
    double voltages[2], external[2] = {0.0, 0.0}, bristle[2][3];
    for (int n = 0; n < 2; ++n) {   /* the inputs are finite and the drives prepared: a sample is never refused */
        pcn_drive_data *d = &a->drive[n];
        pc_drive_peek_voltage(&d->drive, &d->controller, x[3 * n], x[3 * n + 2], x[3 * n + 1], h, &samples[n], NULL);
        voltages[n] = samples[n].v;
        if (d->has_lugre == 0.0) continue;
        const pc_lugre f = bristle_model(d);   /* ActuatedPlant.held_friction */
        pc_lugre_advance(&f, d->lugre.z, joint_speed(a->z, n), h, bristle[n]);
        external[n] -= bristle[n][2];
    }
    pcn_text held;
    pcn_clear(&held);
    pcn_addf(&held, "v1 = %r V, v2 = %r V held", voltages[0], voltages[1]);
    double *trial = in->scratch;
    const int states = PCN_PLANT_STATES + 2;
    memcpy(trial, a->z, sizeof a->z);
    const pc_fivebar_held model = {&a->config.params, a->motors, voltages, external[0], -external[1],
                                   a->config.settings.lambda, 2};
    pc_fivebar_advance(&model, trial, h, (int)a->config.settings.substeps, in->scratch + states);
    if (!(isfinite(trial[PCN_PLANT_STATES]) && isfinite(trial[PCN_PLANT_STATES + 1])))
        return currents_refusal(trial, t, held.text, why);
    int finite = 1;
    for (int k = 0; k < PCN_PLANT_STATES; ++k) finite &= isfinite(trial[k]);
    if (finite) pc_fivebar_project(&a->config.params, trial, PROJECTIONS);
    pc_fivebar_report report;
    pc_refusal refusal;
    const int status = pcn_plant_judge(&a->config, trial, &report, &refusal);
    if (status != PC_OK) {
        pcn_plant_refusal(&a->config, status, &refusal, trial, t, h, held.text, why);
        return 1;
    }
    memcpy(a->z, trial, sizeof a->z);
    for (int n = 0; n < 2; ++n) {
        pcn_drive_data *d = &a->drive[n];
        pc_drive_commit(&d->drive, &d->controller, &samples[n], a->z[PCN_PLANT_STATES + n]);
        if (d->has_lugre != 0.0) d->lugre.z = bristle[n][0];
    }
    publish(in, &report);
    return 0;
}

static int step(pcn_instance *in, double t, double h, pcn_text *why)
{
    actuated *a = data_of(in);
    if (pcn_plant_check_step(&a->config, t, h, why) || check_rk4_stability(a, h, why)) return 1;
    const double *r = in->real;
    double x[N_X] = {r[PCN_SLOT_i_ref1], r[PCN_SLOT_i_hat1], r[PCN_SLOT_v_ref1],
                     r[PCN_SLOT_i_ref2], r[PCN_SLOT_i_hat2], r[PCN_SLOT_v_ref2]};
    for (int n = 0; n < 2; ++n) {
        pcn_drive_data *d = &a->drive[n];
        if (d->drive.h != h) pcn_drive_prepare(d, h);
        a->z[PCN_PLANT_STATES + n] = d->drive.i;
    }
    if (in->boolean[PCN_SLOT_project]) return projected_step(in, a, x, t, h, why);
    pc_lugre friction[2];
    pc_actuated_context context;
    const pc_fivebar_context plant = {&a->config.params, &a->config.settings, a->motors, a->z, NULL, NULL,
                                      in->scratch, 2, FIRST};
    context.plant = &plant;
    for (int n = 0; n < 2; ++n) {
        pcn_drive_data *d = &a->drive[n];
        context.drive[n] = &d->drive;
        context.controller[n] = &d->controller;
        friction[n] = bristle_model(d);
        context.friction[n] = d->has_lugre != 0.0 ? &friction[n] : NULL;
        context.bristles[n] = d->has_lugre != 0.0 ? &d->lugre : NULL;
    }
    pc_refusal refusal;
    const int status = pc_actuated_step(&context, x, h, &refusal);
    if (status != PC_OK) {
        refusal_text(a, status, &refusal, x, in->scratch, t, h, why);
        return 1;
    }
    const int slots[11] = {PCN_SLOT_q1, PCN_SLOT_q2, PCN_SLOT_dq1, PCN_SLOT_dq2, PCN_SLOT_x, PCN_SLOT_y,
                           PCN_SLOT_dx, PCN_SLOT_dy, PCN_SLOT_q1_enc, PCN_SLOT_q2_enc, PCN_SLOT_residual};
    for (int k = 0; k < 11; ++k) in->real[slots[k]] = x[FIRST + k];
    const int tau[2] = {PCN_SLOT_tau1, PCN_SLOT_tau2}, v[2] = {PCN_SLOT_v1, PCN_SLOT_v2},
              i[2] = {PCN_SLOT_i1, PCN_SLOT_i2};
    for (int n = 0; n < 2; ++n) {
        in->real[tau[n]] = x[FIRST + 11 + n];
        in->real[v[n]] = x[FIRST + 13 + n];
        in->real[i[n]] = x[FIRST + 15 + n];
    }
    return 0;
}

/* Restored data: all zero (taken before set-up), or the plant's configuration and finite
 * state, the motor rows and each drive as this instance's parameters make them. */
static int check_data(const pcn_instance *in, const double *data, pcn_text *why)
{
    int zero = 1;
    for (long k = 0; k < DATA_WORDS; ++k) zero &= data[k] == 0.0;
    if (zero) return 0;
    actuated built;
    pcn_text ignored;
    pcn_clear(&ignored);
    if (build(in, &built, &ignored))
        return pcn_addf(why, "the plant's model data is set but this instance's parameters are refused"), 1;
    if (pcn_plant_check_data(in, data, PCN_PLANT_STATES + 2, why)) return 1;
    const actuated *a = (const actuated *)data;
    if (memcmp(a->motors, built.motors, sizeof built.motors) != 0)
        return pcn_addf(why, "the drives' motor rows differ from this instance's parameters"), 1;
    for (int n = 0; n < 2; ++n)
        if (pcn_drive_check_data(&built.drive[n], &a->drive[n], why)) return 1;
    return 0;
}

const pcn_model pcn_this_model = {
    .identifier = PCN_IDENTIFIER,
    .accepted_steps = "",
    .accepted_steps_of = accepted_steps,
    .data_words = DATA_WORDS,
    .scratch_words = SCRATCH_WORDS,
    .setup = setup,
    .check_step = check_step,
    .step = step,
    .check_data = check_data,
};
