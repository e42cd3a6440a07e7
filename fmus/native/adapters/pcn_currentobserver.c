/* Native CurrentObserver (fmus/slaves/parcosim_currentobserver.py) over pc_observer_estimate.
 *
 * The motor presets' R, L, ke travel as build data (pcn_preset_*); the parameters R, ke, L
 * override them (-1: the preset's value), checked as fmus.refusals.with_overrides and
 * motor.MotorParams do, with their messages.  A new step length's coefficients come from
 * pc_electrical_step_coefficients, as motor.CurrentObserver.prepare_step gets them.
 * Steps h = T / n advance the estimate on every sub-step and publish i_hat on sub-step
 * sample_phase of each period (pcn_sampling.h).  Model data (FMU state): the kernel's
 * pc_observer, then the sub-step counter.
 */
#include <math.h>
#include <string.h>

#include "electrics.h"
#include "model_config.h"
#include "observer.h"
#include "pcn_model.h"
#include "pcn_sampling.h"

#define ABSURD 1e6   /* fmus/slave/refusals.py */
#define TINY 1e-12
#define PRESET_VALUE (-1.0)
#define MIN_STEP 1e-9
#define OBSERVER_WORDS ((long)(sizeof(pc_observer) / sizeof(double)))

static pcn_sampling *counter(pcn_instance *in) { return (pcn_sampling *)(in->data + OBSERVER_WORDS); }

/* The motor's R, L, ke: the preset's, overridden; nonzero (why written) when refused. */
static int motor(const pcn_instance *in, double *R, double *L, double *ke, pcn_text *why)
{
    const char *name = in->string[PCN_SLOT_preset];
    int p = -1;
    for (int k = 0; k < PCN_PRESET_NAMES_COUNT; ++k)
        if (strcmp(name, pcn_preset_names[k]) == 0) p = k;
    if (p < 0) {
        pcn_addf(why, "parameter preset = '%s': unknown motor preset '%s'; valid presets: ", name, name);
        for (int k = 0; k < PCN_PRESET_NAMES_COUNT; ++k) pcn_addf(why, k ? ", %s" : "%s", pcn_preset_names[k]);
        return 1;
    }
    /* with_overrides: in the slave's order R, ke, L; positive: R, ke */
    const char *names[3] = {"R", "ke", "L"};
    const int slots[3] = {PCN_SLOT_R, PCN_SLOT_ke, PCN_SLOT_L};
    double value[3] = {pcn_preset_R[p], pcn_preset_ke[p], pcn_preset_L[p]};
    for (int k = 0; k < 3; ++k) {
        double v = in->real[slots[k]];
        if (v == PRESET_VALUE) continue;
        if (v < 0.0)
            return pcn_addf(why, "parameter %s = %r is negative (use -1 for the preset's value)", names[k], v), 1;
        if (isfinite(v) && fabs(v) > ABSURD)
            return pcn_addf(why, "parameter %s = %r is absurd: |%s| must be <= %G (SI units)", names[k], v, names[k],
                            ABSURD), 1;
        if (k < 2 && isfinite(v) && 0.0 < v && v < TINY)
            return pcn_addf(why, "parameter %s = %r is absurdly small: it must be >= %G (SI units)", names[k], v,
                            TINY), 1;
        value[k] = v;
    }
    /* MotorParams.validate, in its field order R, L, ke (the others are the preset's) */
    const int order[3] = {0, 2, 1};
    for (int j = 0; j < 3; ++j) {
        int k = order[j];
        if (!isfinite(value[k]))
            return pcn_addf(why, "parameter %s must be a finite number, got %r", names[k], value[k]), 1;
        if (k < 2 ? value[k] <= 0.0 : value[k] < 0.0)
            return pcn_addf(why, "parameter %s must be %s, got %r", names[k], k < 2 ? "> 0" : ">= 0", value[k]), 1;
    }
    *R = value[0];
    *ke = value[1];
    *L = value[2];
    return 0;
}

static int is_static(const pcn_instance *in) { return strcmp(in->string[PCN_SLOT_kind], "static") == 0; }

static int setup(pcn_instance *in, pcn_text *why)
{
    double R, L, ke, *r = in->real;
    if (motor(in, &R, &L, &ke, why)) return 1;
    double T = r[PCN_SLOT_T];
    if (!isfinite(T)) return pcn_addf(why, "T = %r is not finite", T), 1;
    const char *names[3] = {"i0", "omega0", "T"};
    const double values[3] = {r[PCN_SLOT_i0], r[PCN_SLOT_omega0], T};
    for (int k = 0; k < 3; ++k)
        if (isfinite(values[k]) && fabs(values[k]) > ABSURD)
            return pcn_addf(why, "parameter %s = %r is absurd: |%s| must be <= %G (SI units)", names[k], values[k],
                            names[k], ABSURD), 1;
    if (!(T > 0.0)) return pcn_addf(why, "parameter T = %r s must be > 0", T), 1;
    if (T < MIN_STEP) return pcn_addf(why, "parameter T = %r s must be >= %G s", T, MIN_STEP), 1;
    const char *kind = in->string[PCN_SLOT_kind];
    if (strcmp(kind, "static") != 0 && strcmp(kind, "dynamic") != 0)
        return pcn_addf(why, "kind must be one of 'static', 'dynamic'; got '%s'", kind), 1;
    for (int k = 0; k < 2; ++k)
        if (!isfinite(values[k])) return pcn_addf(why, "%s must be a finite number, got %r", names[k], values[k]), 1;
    pc_observer *o = (pc_observer *)in->data;
    *o = (pc_observer){.is_static = is_static(in), .ke = ke, .h = NAN, .a = 0.0, .g = 0.0,
                       .i_hat = values[0], .omega_prev = values[1], .has_prev = 1.0};
    *counter(in) = (pcn_sampling){0.0, 0.0};
    r[PCN_SLOT_i_hat] = o->i_hat;
    return 0;
}

static int check_step(pcn_instance *in, double t, double h, pcn_text *why)
{
    return pcn_sampling_check(counter(in), in, in->real[PCN_SLOT_T], in->integer[PCN_SLOT_sample_phase], t, h, why);
}

/* motor.CurrentObserver.prepare_step: the coefficients of a new step length. */
static void prepare(pcn_instance *in, double h)
{
    double R, L, ke, ag[2];
    pcn_text ignored;
    pcn_clear(&ignored);
    pc_observer *o = (pc_observer *)in->data;
    if (motor(in, &R, &L, &ke, &ignored)) return;   /* set up already: cannot happen */
    pc_electrical_step_coefficients(R, L, h, o->is_static != 0.0 ? PC_ELECTRICS_QUASI_STATIC : PC_ELECTRICS_EXACT,
                                    ag);
    o->a = ag[0];
    o->g = ag[1];
    o->h = h;
}

static int step(pcn_instance *in, double t, double h, pcn_text *why)
{
    double *r = in->real, v = r[PCN_SLOT_v], omega = r[PCN_SLOT_omega], i_hat;
    pc_observer *o = (pc_observer *)in->data;
    pc_refusal refusal;
    int code = pc_observer_estimate(o, v, omega, h, &i_hat, &refusal);
    if (code == PC_OBSERVER_UNPREPARED_STEP) {
        prepare(in, h);
        code = pc_observer_estimate(o, v, omega, h, &i_hat, &refusal);
    }
    if (code == PC_OK) {
        pcn_sampling *s = counter(in);
        if (PCN_SAMPLES(s, in, t)) r[PCN_SLOT_i_hat] = i_hat;
        s->substep = pc_sampling_next(s->substep, s->substeps);
        return 0;
    }
    if (code == PC_OBSERVER_NONFINITE_INPUT) {   /* motor.kernel.OBSERVER_REASONS */
        pcn_quantify(why, code, "nonfinite_input", refusal.index ? "omega" : "v", refusal.value, "", NAN);
        return pcn_addf(why, "%s must be a finite number, got %r", refusal.index ? "omega" : "v", refusal.value), 1;
    }
    pcn_quantify(why, code, "diverged", "i_hat", refusal.value, "A", NAN);
    return pcn_addf(pcn_timed(why), "the estimate i_hat = %r A at t = %G s is not finite (inputs v = %r V, omega = "
                    "%r rad/s)", refusal.value, t, v, omega), 1;
}

/* Restored data: is_static and ke are the parameters' (configuration); the coefficients, if
 * prepared, are those of their step length; all zero: a state taken before set-up. */
static int check_data(const pcn_instance *in, const double *data, pcn_text *why)
{
    const pc_observer *o = (const pc_observer *)data;
    double R, L, ke, ag[2];
    pcn_text ignored;
    pcn_clear(&ignored);
    if (pcn_sampling_check_data((const pcn_sampling *)(data + OBSERVER_WORDS), why)) return 1;
    int zero = 1;
    for (long k = 0; k < OBSERVER_WORDS; ++k) zero &= data[k] == 0.0;
    if (zero) return 0;
    if (motor(in, &R, &L, &ke, &ignored) || o->is_static != (double)is_static(in) || o->ke != ke)
        return pcn_addf(why, "the observer's configuration words (kind, ke) differ from this instance's"), 1;
    if (isnan(o->h)) return 0;
    if (!(o->h > 0.0)) return pcn_addf(why, "the observer's step length %r is not > 0", o->h), 1;
    pc_electrical_step_coefficients(R, L, o->h, o->is_static != 0.0 ? PC_ELECTRICS_QUASI_STATIC : PC_ELECTRICS_EXACT,
                                    ag);
    if (o->a != ag[0] || o->g != ag[1])
        return pcn_addf(why, "the observer's coefficients are not those of its step length %r", o->h), 1;
    return 0;
}

const pcn_model pcn_this_model = {
    .identifier = PCN_IDENTIFIER,
    .accepted_steps = PCN_SAMPLING_ACCEPTS,
    .data_words = OBSERVER_WORDS + PCN_SAMPLING_WORDS,
    .scratch_words = 0,
    .setup = setup,
    .check_step = check_step,
    .step = step,
    .check_data = check_data,
};
