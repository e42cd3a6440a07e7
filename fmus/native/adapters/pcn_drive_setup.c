/* One DC motor drive in a native FMU (pcn_drive_setup.h): set-up, step, restored data. */
#include "pcn_drive_setup.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "design.h"
#include "electrics.h"
#include "pc_sampling.h"
#include "pcn_sampling.h"

#define ABSURD 1e6          /* fmus/slave/refusals.py */
#define TINY 1e-12
#define PRESET_VALUE (-1.0)
#define MAX_COUNT 2147483648.0        /* motor._checks.count's default limit, 2^31 */
#define MAX_SEED 9007199254740992.0   /* motor.drive.MAX_SEED, 2^53 */

/* The motor fields' FMU variables (MOTOR_PARAMETERS) and the design's (DESIGN_PARAMETERS). */
static const char *const MOTOR_VARIABLES[PCN_MOTOR_FIELDS] = {
    "R", "L", "kt", "ke", "b", "mu", "v_max", "omega_eps", "mu_s", "omega_s", "sigma0", "sigma1", "J_design"};
static const char *const DESIGN_VARIABLES[PCN_DESIGN_FIELDS] = {"R_design", "L_design", "kt_design", "ke_design",
                                                                "b_design"};
static const char *const DESIGN_FIELDS[PCN_DESIGN_FIELDS] = {"R", "L", "kt", "ke", "b"};
/* motor.presets.POSITIVE_FIELDS (the others must be >= 0). */
static const int POSITIVE[PCN_MOTOR_FIELDS] = {1, 0, 1, 1, 0, 0, 1, 1, 0, 1, 1, 0, 1};
/* MotorParams' own field order (MotorParams.validate checks them in it). */
static const int DATACLASS_ORDER[PCN_MOTOR_FIELDS] = {
    PCN_MOTOR_R, PCN_MOTOR_L, PCN_MOTOR_KT, PCN_MOTOR_KE, PCN_MOTOR_B, PCN_MOTOR_MU, PCN_MOTOR_J_ROTOR,
    PCN_MOTOR_V_MAX, PCN_MOTOR_OMEGA_EPS, PCN_MOTOR_MU_S, PCN_MOTOR_OMEGA_S, PCN_MOTOR_SIGMA0, PCN_MOTOR_SIGMA1};
static const char *const METHODS[3] = {"exact", "euler", "quasi_static"};   /* PC_ELECTRICS_* */

static int absurd(const char *name, const char *suffix, double v, pcn_text *why)
{
    if (!(isfinite(v) && fabs(v) > ABSURD)) return 0;
    pcn_addf(why, "parameter %s%s = %r is absurd: |%s%s| must be <= %G (SI units)", name, suffix, v, name, suffix,
             ABSURD);
    return 1;
}

/* motor._checks.choice: the index of `value` among the n options, or -1 (why written). */
static int choice(const char *name, const char *suffix, const char *value, const char *const *options, int n,
                  pcn_text *why)
{
    for (int k = 0; k < n; ++k)
        if (strcmp(value, options[k]) == 0) return k;
    pcn_addf(why, "%s%s must be one of ", name, suffix);
    for (int k = 0; k < n; ++k) pcn_addf(why, k ? ", '%s'" : "'%s'", options[k]);
    pcn_addf(why, "; got '%s'", value);
    return -1;
}

/* motor._checks.count of an Integer variable. */
static int count(const char *name, const char *suffix, int value, double limit, pcn_text *why)
{
    if (value >= 0 && value < limit) return 0;
    char bound[32];
    snprintf(bound, sizeof bound, "%.0f", limit);
    pcn_addf(why, "%s%s must be a whole number in [0, %s), got %d", name, suffix, bound, value);
    return 1;
}

/* motor._checks.finite, positive, non_negative: sign 1 (> 0), 0 (>= 0) or -1 (finite only). */
static int number(const char *prefix, const char *name, const char *suffix, double v, int sign, pcn_text *why)
{
    if (!isfinite(v)) return pcn_addf(why, "%s%s%s must be a finite number, got %r", prefix, name, suffix, v), 1;
    if (sign > 0 && v <= 0.0) return pcn_addf(why, "%s%s%s must be > 0, got %r", prefix, name, suffix, v), 1;
    if (sign == 0 && v < 0.0) return pcn_addf(why, "%s%s%s must be >= 0, got %r", prefix, name, suffix, v), 1;
    return 0;
}

/* fmus.refusals.motor_preset and with_overrides (positive: POSITIVE_FIELDS), then
 * MotorParams.validate: the drive's motor into m. */
static int motor(const pcn_drive_parameters *p, const pcn_motor_presets *presets, double *m, pcn_text *why)
{
    const char *s = p->suffix;
    int row = -1;
    for (int k = 0; k < presets->count; ++k)
        if (strcmp(p->preset, presets->names[k]) == 0) row = k;
    if (row < 0) {
        pcn_addf(why, "parameter preset%s = '%s': unknown motor preset '%s'; valid presets: ", s, p->preset, p->preset);
        for (int k = 0; k < presets->count; ++k) pcn_addf(why, k ? ", %s" : "%s", presets->names[k]);
        return 1;
    }
    for (int k = 0; k < PCN_MOTOR_FIELDS; ++k) {
        double v = p->motor[k];
        m[k] = presets->values[row * PCN_MOTOR_FIELDS + k];
        if (v == PRESET_VALUE) continue;
        const char *name = MOTOR_VARIABLES[k];
        if (v < 0.0)
            return pcn_addf(why, "parameter %s%s = %r is negative (use -1 for the preset's value)", name, s, v), 1;
        if (absurd(name, s, v, why)) return 1;
        if (POSITIVE[k] && isfinite(v) && 0.0 < v && v < TINY)
            return pcn_addf(why, "parameter %s%s = %r is absurdly small: it must be >= %G (SI units)", name, s, v,
                            TINY), 1;
        m[k] = v;
    }
    for (int j = 0; j < PCN_MOTOR_FIELDS; ++j) {
        int k = DATACLASS_ORDER[j];
        if (number("parameter ", MOTOR_VARIABLES[k], s, m[k], POSITIVE[k] ? 1 : 0, why)) return 1;
    }
    return 0;
}

/* The design's motor: m with the design parameters that are not -1 (build_drive). */
static int design_motor(const pcn_drive_parameters *p, const double *m, double *key, pcn_text *why)
{
    const int fields[PCN_DESIGN_FIELDS] = {PCN_MOTOR_R, PCN_MOTOR_L, PCN_MOTOR_KT, PCN_MOTOR_KE, PCN_MOTOR_B};
    for (int k = 0; k < PCN_DESIGN_FIELDS; ++k) {
        double v = p->design[k];
        key[k] = m[fields[k]];
        if (v == PRESET_VALUE) continue;
        if (absurd(DESIGN_VARIABLES[k], p->suffix, v, why)) return 1;
        if (!(isfinite(v) && v >= TINY))
            return pcn_addf(why, "parameter %s%s = %r must be > 0 (or -1: the value of %s)", DESIGN_VARIABLES[k],
                            p->suffix, v, DESIGN_FIELDS[k]), 1;
        key[k] = v;
    }
    key[5] = m[PCN_MOTOR_J_ROTOR];
    key[6] = p->T;
    return 0;
}

/* motor.friction.LuGre.__post_init__ of LuGre.of_motor (the checks MotorParams leaves open). */
static int lugre(const pcn_drive_parameters *p, const double *m, pc_lugre *f, pcn_text *why)
{
    const char *s = p->suffix;
    if (!(m[PCN_MOTOR_MU] > 0.0))
        return pcn_addf(why, "LuGre friction: Fc (mu%s) = %r must be > 0", s, m[PCN_MOTOR_MU]), 1;
    if (m[PCN_MOTOR_MU_S] < m[PCN_MOTOR_MU])
        return pcn_addf(why, "LuGre friction: the break-away torque Fs (mu_s%s) = %r must be >= the Coulomb torque "
                        "Fc (mu%s) = %r", s, m[PCN_MOTOR_MU_S], s, m[PCN_MOTOR_MU]), 1;
    *f = (pc_lugre){.Fc = m[PCN_MOTOR_MU], .Fs = m[PCN_MOTOR_MU_S], .omega_s = m[PCN_MOTOR_OMEGA_S],
                    .sigma0 = m[PCN_MOTOR_SIGMA0], .sigma1 = m[PCN_MOTOR_SIGMA1], .sigma2 = m[PCN_MOTOR_B], .z = 0.0};
    return 0;
}

/* The current controller of the design values `key` (motor.drive._design): the one python-control
 * made at the build for these values if it carries it (the twin's coefficients, bit for bit),
 * else pc_current_design's (design.c: the same poles, the exact ZOH model). */
static int controller(const double *key, const pcn_drive_design *design, const char *s, pc_controller *c,
                      pcn_text *why)
{
    static const char *const NAMES[PCN_DESIGN_KEY] = {"R", "L", "kt", "ke", "b", "J_rotor", "T"};
    for (int j = 0; j < design->count; ++j) {
        const double *built = design->keys + j * PCN_DESIGN_KEY;
        int equal = 0;
        for (int k = 0; k < PCN_DESIGN_KEY; ++k) equal += key[k] == built[k];
        if (equal < PCN_DESIGN_KEY) continue;
        if (j == 0 && design->error[0]) return pcn_addf(why, "%s", design->error), 1;
        const double *a = design->coefficients + 4 * j;
        *c = (pc_controller){.alpha = a[0], .beta = a[1], .gamma = a[2], .delta = a[3]};
        return 0;
    }
    double coefficients[4], detail;
    const int code = pc_current_design(key, key[PCN_DESIGN_KEY - 1], design->poles, coefficients, &detail);
    if (code == PC_OK) {
        *c = (pc_controller){.alpha = coefficients[0], .beta = coefficients[1], .gamma = coefficients[2],
                             .delta = coefficients[3]};
        return 0;
    }
    pcn_addf(why, "current controller design (app. C) failed for ");
    for (int k = 0; k < PCN_DESIGN_KEY; ++k) pcn_addf(why, k ? ", %s = %r" : "%s = %r", NAMES[k], key[k]);
    if (code == PC_DESIGN_NO_L) return pcn_addf(why, ": current controller design needs L > 0, got L=0.0"), 1;
    if (code == PC_DESIGN_ZERO_AT_ONE)
        return pcn_addf(why, ": with b = 0 the plant's zero is z = 1, the controller's integrator, and appendix C's "
                        "system is singular: the native FMU does not pick one of its many solutions as numpy's "
                        "solve does (set b%s or b_design%s > 0, or use the pythonfmu FMU)", s, s), 1;
    if (code == PC_DESIGN_NOT_ZOH)
        return pcn_addf(why, ": the ZOH model's numerator has the leading coefficient %r", detail), 1;
    return pcn_addf(why, ": a coefficient of K(z) is %r", detail), 1;
}

int pcn_drive_build(const pcn_drive_parameters *p, const pcn_motor_presets *presets, const pcn_drive_design *design,
                    pcn_drive_data *out, pcn_text *why)
{
    static const char *const FRICTIONS[2] = {"tanh", "lugre"}, *const MODES[2] = {"current", "voltage"},
                             *const TORQUES[2] = {"end", "mean"};
    const char *s = p->suffix;
    double m[PCN_MOTOR_FIELDS], key[PCN_DESIGN_KEY];
    if (motor(p, presets, m, why) || design_motor(p, m, key, why)) return 1;
    if (absurd("current_offset", s, p->current_offset, why) || absurd("current_noise", s, p->current_noise, why))
        return 1;
    pcn_drive_data d;
    memset(&d, 0, sizeof d);
    /* motor.Drive.__init__, its checks in their order */
    int friction = choice("friction", s, p->friction, FRICTIONS, 2, why);
    if (friction < 0 || (friction == 1 && lugre(p, m, &d.lugre, why))) return 1;
    if (count("pwm_counts", s, p->pwm_counts, MAX_COUNT, why) || count("noise_seed", s, p->noise_seed, MAX_SEED, why) ||
        count("noise_instance", s, p->noise_instance, MAX_SEED, why) ||
        count("sample_phase", "", p->sample_phase, MAX_COUNT, why) ||
        number("", "current_offset", s, p->current_offset, -1, why) ||
        number("", "current_noise", s, p->current_noise, 0, why))
        return 1;
    int torque = choice("torque_output", "", p->torque_output, TORQUES, 2, why);
    int mode = torque < 0 ? -1 : choice("mode", "", p->mode, MODES, 2, why);
    int method = mode < 0 ? -1 : choice("method", "", p->method, METHODS, 3, why);
    if (method < 0) return 1;
    if (method == PC_ELECTRICS_EULER && m[PCN_MOTOR_L] == 0.0)
        return pcn_addf(why, "method 'euler' needs L%s > 0, got L%s = %r; use 'quasi_static'", s, s, m[PCN_MOTOR_L]), 1;
    if (number("", "T", "", p->T, 1, why)) return 1;
    double v_max = m[PCN_MOTOR_V_MAX];
    if (mode == 0 && controller(key, design, s, &d.controller, why)) return 1;
    d.controller.v_max = v_max;   /* the voltage mode's: CurrentController.idle_buffer */
    d.R = m[PCN_MOTOR_R];
    d.L = m[PCN_MOTOR_L];
    d.method = method;
    d.has_lugre = friction;
    d.drive = (pc_drive){.current_mode = mode == 0, .mean_torque = torque == 1, .ke = m[PCN_MOTOR_KE],
                         .kt = m[PCN_MOTOR_KT], .b = m[PCN_MOTOR_B], .mu = m[PCN_MOTOR_MU],
                         .omega_eps = m[PCN_MOTOR_OMEGA_EPS], .v_max = v_max, .T = p->T,
                         .sample_phase = p->sample_phase, .h = NAN,
                         .pwm_quantum = p->pwm_counts ? v_max / p->pwm_counts : 0.0, .i_offset = p->current_offset,
                         .i_noise = p->current_noise, .noise_seed = p->noise_seed,
                         .noise_instance = p->noise_instance};
    *out = d;
    return 0;
}

int pcn_drive_start(pcn_drive_data *d, double omega0, double i0, pcn_text *why)
{
    if (number("", "omega0", "", omega0, -1, why) || number("", "i0", "", i0, -1, why)) return 1;
    double v_max = d->drive.v_max, v0 = d->R * i0 + d->drive.ke * omega0;
    v0 = fmin(fmax(v0, -v_max), v_max);
    d->drive.i = i0;
    d->drive.v = v0;
    d->drive.phase = d->drive.sample = 0.0;
    pc_controller *c = &d->controller;
    if (d->drive.current_mode != 0.0) {   /* CurrentController.reset; voltage mode's idle one stays 0 */
        c->u1 = c->u2 = fmin(fmax(v0, -c->v_max), c->v_max);
        c->e1 = c->e2 = 0.0;
    }
    d->lugre.z = d->has_lugre != 0.0 ? pc_lugre_steady_deflection(&d->lugre, omega0) : 0.0;
    return 0;
}

static pc_lugre *friction(pcn_drive_data *d) { return d->has_lugre != 0.0 ? &d->lugre : NULL; }

double pcn_drive_torque(const pcn_drive_data *d, double omega)
{
    return pc_drive_torque(&d->drive, d->has_lugre != 0.0 ? &d->lugre : NULL, omega);
}

/* Drive.prepare_step: the coefficients of a new step length h (checked by the FMU's step rule). */
void pcn_drive_prepare(pcn_drive_data *d, double h)
{
    double ag[2], w[2];
    pc_drive *k = &d->drive;
    k->substeps = k->current_mode != 0.0 ? pc_sampling_substeps(k->T, h) : 1.0;
    pc_electrical_step_coefficients(d->R, d->L, h, (int)d->method, ag);
    pc_mean_current_coefficients(d->R, d->L, h, (int)d->method, w);
    k->a = ag[0];
    k->g = ag[1];
    k->w_i = w[0];
    k->w_u = w[1];
    k->h = h;
}

/* Drive._diverged_why, then DRIVE_REASONS' text. */
static int refused(const pcn_drive_data *d, const pc_refusal *r, const double out[3], double h, pcn_text *why)
{
    static const char *const INPUTS[4] = {"omega", "i_ref", "v_ref", "i_hat"};   /* PC_DRIVE_OMEGA ... */
    static const char *const DIVERGED[2] = {"i", "tau"};                              /* motor.kernel.DRIVE_REASONS */
    if (r->code == PC_DRIVE_NONFINITE_INPUT) {
        pcn_quantify(why, r->code, "nonfinite_input", INPUTS[r->index], r->value, "", NAN);
        return pcn_addf(why, "%s must be a finite number, got %r", INPUTS[r->index], r->value), 1;
    }
    pcn_quantify(why, r->code, "diverged", DIVERGED[r->index], r->value, "", NAN);
    pcn_addf(why, "armature current i = %r A, shaft torque tau = %r N m after this step are not finite", out[2],
             out[0]);
    double a = d->drive.a;
    if (d->method == PC_ELECTRICS_EULER && a < -1.0) {
        char limit[32], factor[32];
        snprintf(limit, sizeof limit, "%.3g", 2.0 * d->L / d->R);
        snprintf(factor, sizeof factor, "%.3g", a);
        pcn_addf(why, ": method 'euler' diverges for h = %r s > 2 L/R = %s s (L = %r H, R = %r ohm; the current is "
                 "multiplied by 1 - hR/L = %s every step); use 'exact'", h, limit, d->L, d->R, factor);
    }
    return 1;
}

int pcn_drive_step(pcn_drive_data *d, double i_ref, double v_ref, double omega, double i_hat, double h,
                   double out[3], pcn_text *why)
{
    pc_refusal r;
    int code = pc_drive_step(&d->drive, &d->controller, friction(d), i_ref, v_ref, omega, i_hat, h, out, &r);
    if (code == PC_DRIVE_UNPREPARED_STEP) {
        pcn_drive_prepare(d, h);
        code = pc_drive_step(&d->drive, &d->controller, friction(d), i_ref, v_ref, omega, i_hat, h, out, &r);
    }
    return code == PC_OK ? 0 : refused(d, &r, out, h, why);
}

/* Whether a double is a whole number in [0, limit). */
static int whole(double x, double limit) { return x == floor(x) && x >= 0.0 && x < limit; }

int pcn_drive_check_data(const pcn_drive_data *built, const pcn_drive_data *data, pcn_text *why)
{
    const pc_drive *k = &data->drive;
    /* configuration: every word but the run state and the step's, as the set-up wrote it */
    pcn_drive_data config = *data;
    config.drive.h = built->drive.h;
    config.drive.a = config.drive.g = config.drive.w_i = config.drive.w_u = config.drive.substeps = 0.0;
    config.drive.i = config.drive.v = config.drive.phase = config.drive.sample = 0.0;
    config.controller.u1 = config.controller.u2 = config.controller.e1 = config.controller.e2 = 0.0;
    config.lugre.z = 0.0;
    if (memcmp(&config, built, sizeof config) != 0)
        return pcn_addf(why, "the drive's configuration words (motor, design, options) differ from this instance's"), 1;
    const double run[] = {k->i, k->v, data->controller.u1, data->controller.u2, data->controller.e1,
                          data->controller.e2, data->lugre.z};
    for (size_t j = 0; j < sizeof run / sizeof run[0]; ++j)
        if (!isfinite(run[j])) return pcn_addf(why, "the drive's state word %d is %r", (int)j, run[j]), 1;
    if (!whole(k->sample, MAX_SEED)) return pcn_addf(why, "the drive's sample count %r is not whole", k->sample), 1;
    if (isnan(k->h)) {
        if (k->a == 0.0 && k->g == 0.0 && k->w_i == 0.0 && k->w_u == 0.0 && k->substeps == 0.0 && k->phase == 0.0)
            return 0;
        return pcn_addf(why, "the drive's step words are set without a step length"), 1;
    }
    if (!(k->h > 0.0 && isfinite(k->h)))
        return pcn_addf(why, "the drive's step length %r is not a finite positive number", k->h), 1;
    pcn_drive_data prepared = *built;
    pcn_drive_prepare(&prepared, k->h);
    const pc_drive *p = &prepared.drive;
    if (p->substeps == 0.0)
        return pcn_addf(why, "the drive's step length %r does not divide its period T = %r", k->h, p->T), 1;
    if (k->a != p->a || k->g != p->g || k->w_i != p->w_i || k->w_u != p->w_u || k->substeps != p->substeps)
        return pcn_addf(why, "the drive's coefficients are not those of its step length %r", k->h), 1;
    if (!whole(k->phase, k->substeps))
        return pcn_addf(why, "the drive's sub-step %r is not a whole number in [0, %r)", k->phase, k->substeps), 1;
    return 0;
}

const char *pcn_drive_accepted_steps(int current_mode)
{
    if (current_mode) return "in current mode " PCN_SAMPLING_ACCEPTS;
    return "any step size h with 1e-09 s <= h and t + h <= 1e+09 s (voltage mode)";
}
