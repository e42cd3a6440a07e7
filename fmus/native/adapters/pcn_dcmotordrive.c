/* Native DCMotorDrive (fmus/slaves/parcosim_dcmotordrive.py) over pc_drive_step.
 *
 * The drive is set up, started and stepped by pcn_drive_setup.c (build_drive's and
 * motor.Drive's checks and messages); the current controller is python-control's design made at
 * the FMU's build for its parameters then and for the motor presets at its T (pcn_design_*),
 * or for other motor values design.c's (pc_current_design); the presets travel as data
 * (pcn_preset_*).
 * Current mode: steps h = T / n, the controller sampling on sub-step sample_phase of each
 * period (the kernel's counter, pc_drive.phase); voltage mode: any step.  internal_observer:
 * the controller reads the drive's own estimate (observer.c: motor.CurrentObserver on the
 * voltage of the step just taken and the speed input omega).  Model data (FMU state): the
 * drive (pcn_drive_data), then the internal observer's pc_observer (all zero without it).
 */
#include <math.h>
#include <string.h>

#include "electrics.h"
#include "model_config.h"
#include "observer.h"
#include "pcn_drive_setup.h"
#include "pcn_model.h"
#include "pcn_sampling.h"

#define ABSURD 1e6   /* fmus/slave/refusals.py */
#define MIN_STEP 1e-9
#define OBSERVER_WORDS ((long)(sizeof(pc_observer) / sizeof(double)))

static pcn_drive_data *drive(const pcn_instance *in) { return (pcn_drive_data *)in->data; }
static pc_observer *observer(const pcn_instance *in) { return (pc_observer *)(in->data + PCN_DRIVE_WORDS); }
static int current_mode(const pcn_instance *in) { return strcmp(in->string[PCN_SLOT_mode], "current") == 0; }

static const pcn_motor_presets PRESETS = {PCN_PRESET_NAMES_COUNT, pcn_preset_names, pcn_preset_motor};

/* The drive's parameters as the variables hold them. */
static pcn_drive_parameters parameters(const pcn_instance *in)
{
    const double *r = in->real;
    const int *n = in->integer;
    char *const *s = in->string;
    return (pcn_drive_parameters){
        .suffix = "", .preset = s[PCN_SLOT_preset],
        .motor = {r[PCN_SLOT_R], r[PCN_SLOT_L], r[PCN_SLOT_kt], r[PCN_SLOT_ke], r[PCN_SLOT_b], r[PCN_SLOT_mu],
                  r[PCN_SLOT_v_max], r[PCN_SLOT_omega_eps], r[PCN_SLOT_mu_s], r[PCN_SLOT_omega_s], r[PCN_SLOT_sigma0],
                  r[PCN_SLOT_sigma1], r[PCN_SLOT_J_design]},
        .design = {r[PCN_SLOT_R_design], r[PCN_SLOT_L_design], r[PCN_SLOT_kt_design], r[PCN_SLOT_ke_design],
                   r[PCN_SLOT_b_design]},
        .friction = s[PCN_SLOT_friction], .pwm_counts = n[PCN_SLOT_pwm_counts],
        .current_offset = r[PCN_SLOT_current_offset], .current_noise = r[PCN_SLOT_current_noise],
        .noise_seed = n[PCN_SLOT_noise_seed], .noise_instance = n[PCN_SLOT_noise_instance], .mode = s[PCN_SLOT_mode],
        .method = s[PCN_SLOT_method], .torque_output = s[PCN_SLOT_torque_output], .T = r[PCN_SLOT_T],
        .sample_phase = n[PCN_SLOT_sample_phase]};
}

/* The slave's set-up up to the drive's start: its own first checks, then build_drive. */
static int build(const pcn_instance *in, pcn_drive_data *d, pcn_text *why)
{
    const double *r = in->real;
    const char *names[3] = {"T", "omega0", "i0"};
    const double values[3] = {r[PCN_SLOT_T], r[PCN_SLOT_omega0], r[PCN_SLOT_i0]};
    for (int k = 0; k < 3; ++k)
        if (isfinite(values[k]) && fabs(values[k]) > ABSURD)
            return pcn_addf(why, "parameter %s = %r is absurd: |%s| must be <= %G (SI units)", names[k], values[k],
                            names[k], ABSURD), 1;
    if (0.0 < values[0] && values[0] < MIN_STEP)
        return pcn_addf(why, "parameter T = %r s must be >= %G s", values[0], MIN_STEP), 1;
    pcn_drive_parameters p = parameters(in);
    pcn_drive_design design = {PCN_DESIGN_KEYS_WORDS / PCN_DESIGN_KEY, pcn_design_keys, pcn_design_coefficients,
                               pcn_design_error[0], pcn_current_poles};
    return pcn_drive_build(&p, &PRESETS, &design, d, why);
}

/* DCMotorDrive._internal_observer: checked, then reset to (i0, omega0); zero without it. */
static int internal_observer(const pcn_instance *in, const pcn_drive_data *d, pc_observer *o, pcn_text *why)
{
    const char *kind = in->string[PCN_SLOT_observer_kind];
    int is_static = strcmp(kind, "static") == 0;
    if (!is_static && strcmp(kind, "dynamic") != 0)
        return pcn_addf(why, "parameter observer_kind = '%s' must be one of 'static', 'dynamic'", kind), 1;
    memset(o, 0, sizeof *o);
    if (!in->boolean[PCN_SLOT_internal_observer]) return 0;
    if (!current_mode(in))
        return pcn_addf(why, "parameter internal_observer = True needs mode = 'current' (mode = '%s': no current "
                        "controller reads an estimate)", in->string[PCN_SLOT_mode]), 1;
    *o = (pc_observer){.is_static = is_static, .ke = d->drive.ke, .h = NAN, .i_hat = in->real[PCN_SLOT_i0],
                       .omega_prev = in->real[PCN_SLOT_omega0], .has_prev = 1.0};
    return 0;
}

static int setup(pcn_instance *in, pcn_text *why)
{
    double *r = in->real;
    pcn_drive_data d;
    pc_observer o;
    if (build(in, &d, why) || pcn_drive_start(&d, r[PCN_SLOT_omega0], r[PCN_SLOT_i0], why) ||
        internal_observer(in, &d, &o, why))
        return 1;
    *drive(in) = d;
    *observer(in) = o;
    r[PCN_SLOT_tau] = pcn_drive_torque(&d, r[PCN_SLOT_omega0]);
    r[PCN_SLOT_v] = d.drive.v;
    r[PCN_SLOT_i] = d.drive.i;
    return 0;
}

static const char *accepted_steps(const pcn_instance *in)
{
    return pcn_drive_accepted_steps(current_mode(in));
}

/* CurrentLoopSteps.check_step_size: in current mode h divides T, with the drive's counter. */
static int check_step(pcn_instance *in, double t, double h, pcn_text *why)
{
    if (!current_mode(in)) return 0;
    const pc_drive *k = &drive(in)->drive;
    pcn_sampling counted = {k->phase, k->substeps};   /* the drive counts its steps itself */
    return pcn_sampling_check(&counted, in, in->real[PCN_SLOT_T], in->integer[PCN_SLOT_sample_phase], t, h, why);
}

/* motor.CurrentObserver.estimate of the voltage v applied over the step just taken. */
static int estimate(pcn_instance *in, double v, double omega, double t, double h, double *i_hat, pcn_text *why)
{
    pc_observer *o = observer(in);
    pc_refusal refusal;
    int code = pc_observer_estimate(o, v, omega, h, i_hat, &refusal);
    if (code == PC_OBSERVER_UNPREPARED_STEP) {
        const pcn_drive_data *d = drive(in);
        double ag[2];
        pc_electrical_step_coefficients(d->R, d->L, h, o->is_static != 0.0 ? PC_ELECTRICS_QUASI_STATIC
                                                                           : PC_ELECTRICS_EXACT, ag);
        o->a = ag[0];
        o->g = ag[1];
        o->h = h;
        code = pc_observer_estimate(o, v, omega, h, i_hat, &refusal);
    }
    if (code == PC_OK) return 0;
    if (code == PC_OBSERVER_NONFINITE_INPUT) {   /* motor.kernel.OBSERVER_REASONS */
        pcn_quantify(why, code, "nonfinite_input", refusal.index ? "omega" : "v", refusal.value, "", NAN);
        return pcn_addf(why, "%s must be a finite number, got %r", refusal.index ? "omega" : "v", refusal.value), 1;
    }
    pcn_quantify(why, code, "diverged", "i_hat", refusal.value, "A", NAN);
    return pcn_addf(pcn_timed(why), "the estimate i_hat = %r A at t = %G s is not finite (inputs v = %r V, omega = "
                    "%r rad/s)", refusal.value, t, v, omega), 1;
}

static int step(pcn_instance *in, double t, double h, pcn_text *why)
{
    double *r = in->real, i_hat = r[PCN_SLOT_i_hat], out[3];
    if (in->boolean[PCN_SLOT_internal_observer] && estimate(in, r[PCN_SLOT_v], r[PCN_SLOT_omega], t, h, &i_hat, why))
        return 1;
    if (pcn_drive_step(drive(in), r[PCN_SLOT_i_ref], r[PCN_SLOT_v_ref], r[PCN_SLOT_omega], i_hat, h, out, why))
        return 1;
    r[PCN_SLOT_tau] = out[0];
    r[PCN_SLOT_v] = out[1];
    r[PCN_SLOT_i] = out[2];
    return 0;
}

/* Restored data: all zero (taken before set-up), or the drive built from this instance's
 * parameters with its run state, and the observer's configuration words and coefficients. */
static int check_data(const pcn_instance *in, const double *data, pcn_text *why)
{
    int zero = 1;
    for (long k = 0; k < PCN_DRIVE_WORDS + OBSERVER_WORDS; ++k) zero &= data[k] == 0.0;
    if (zero) return 0;
    pcn_drive_data built;
    pc_observer fresh;
    pcn_text ignored;
    pcn_clear(&ignored);
    if (build(in, &built, &ignored) || internal_observer(in, &built, &fresh, &ignored))
        return pcn_addf(why, "the drive's model data is set but this instance's parameters are refused"), 1;
    if (pcn_drive_check_data(&built, (const pcn_drive_data *)data, why)) return 1;
    const pc_observer *o = (const pc_observer *)(data + PCN_DRIVE_WORDS);
    if (!in->boolean[PCN_SLOT_internal_observer]) {
        for (long k = 0; k < OBSERVER_WORDS; ++k)
            if (data[PCN_DRIVE_WORDS + k] != 0.0)
                return pcn_addf(why, "the internal observer's words are set without internal_observer"), 1;
        return 0;
    }
    if (o->is_static != fresh.is_static || o->ke != fresh.ke || o->has_prev != 1.0)
        return pcn_addf(why, "the internal observer's configuration words (kind, ke) differ from this instance's"), 1;
    if (!isfinite(o->i_hat) || !isfinite(o->omega_prev))
        return pcn_addf(why, "the internal observer's state (%r, %r) is not finite", o->i_hat, o->omega_prev), 1;
    if (isnan(o->h)) return 0;
    double ag[2];
    if (!(o->h > 0.0 && isfinite(o->h)))
        return pcn_addf(why, "the internal observer's step length %r is not a finite positive number", o->h), 1;
    pc_electrical_step_coefficients(built.R, built.L, o->h, o->is_static != 0.0 ? PC_ELECTRICS_QUASI_STATIC
                                                                                : PC_ELECTRICS_EXACT, ag);
    if (o->a != ag[0] || o->g != ag[1])
        return pcn_addf(why, "the internal observer's coefficients are not those of its step length %r", o->h), 1;
    return 0;
}

const pcn_model pcn_this_model = {
    .identifier = PCN_IDENTIFIER,
    .accepted_steps = "",
    .accepted_steps_of = accepted_steps,
    .data_words = PCN_DRIVE_WORDS + OBSERVER_WORDS,
    .scratch_words = 0,
    .setup = setup,
    .check_step = check_step,
    .step = step,
    .check_data = check_data,
};
