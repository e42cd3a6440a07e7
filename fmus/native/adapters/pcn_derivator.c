/* Native Derivator (fmus/slaves/parcosim_derivator.py) over the kernel pc_derivator_step.
 *
 * The Bessel filters are designed with scipy at the FMU's build, for its parameters then
 * (fc_vel, fc_acc, T): the design travels as the kernel's buffer, not started
 * (pcn_design_buffer).  Other values of those three are refused by name at initialisation
 * (docs/native.md); every check the pythonfmu slave makes before its design comes first, with
 * its words.  Steps h = T / n sample on sub-step sample_phase of each period and hold the
 * outputs in between (pcn_sampling.h).  Model data (FMU state): the kernel's buffer, then the
 * sub-step counter; scratch: its n m doubles.
 */
#include <math.h>
#include <string.h>

#include "derivator.h"
#include "model_config.h"
#include "pcn_model.h"
#include "pcn_sampling.h"

#define ABSURD 1e6      /* fmus/slave/refusals.py */
#define MIN_FC_T 1e-6   /* the slave's lowest fc T */
#define CHANNELS 2

static pcn_sampling *counter(pcn_instance *in) { return (pcn_sampling *)(in->data + PCN_DESIGN_BUFFER_WORDS); }

static pc_derivator_context context(pcn_instance *in)
{
    pc_derivator_context c = {(pc_derivator *)in->data, in->scratch, PCN_DESIGN_BUFFER_WORDS,
                              PCN_DERIVATOR_STATES * CHANNELS, ABSURD};
    return c;
}

/* A kernel's refusal in controller.derivators._REASONS' words and fields: an angle of `q` not
 * finite or beyond `limit`, or a word of the damaged buffer (its sizes). */
static void kernel_refusal(const pc_refusal *r, const double q[CHANNELS], double limit, pcn_text *why)
{
    static const char *const ANGLES[CHANNELS] = {"q1", "q2"};
    static const char *const LAYOUT[5] = {"states", "channels", "length", "scratch length", "velocity sections"};
    if (r->code == PC_DERIVATOR_BAD_INPUT) {
        pcn_quantify(why, r->code, "bad_input", ANGLES[r->index], r->value, "rad", NAN);
        pcn_addf(why, "angles q = [%r, %r] rad must be finite with |q| <= ", q[0], q[1]);
        if (isinf(limit)) pcn_addf(why, "inf");
        else pcn_addf(why, "%G", limit);
        return;
    }
    pcn_quantify(why, r->code, "bad_layout", LAYOUT[r->index], r->value, "", NAN);
    pcn_addf(why, "the derivator's buffer of %d words is damaged: %s = %r does not fit it",
             (int)PCN_DESIGN_BUFFER_WORDS, LAYOUT[r->index], r->value);
}

/* The slave's parameter checks (require_finite, refuse_absurd, > 0, T, Nyquist, fc T). */
static int check_parameters(const double *r, pcn_text *why)
{
    const char *names[] = {"fc_vel", "fc_acc", "T", "q1_0", "q2_0"};
    const double values[] = {r[PCN_SLOT_fc_vel], r[PCN_SLOT_fc_acc], r[PCN_SLOT_T], r[PCN_SLOT_q1_0],
                             r[PCN_SLOT_q2_0]};
    for (int k = 0; k < 5; ++k)
        if (!isfinite(values[k])) return pcn_addf(why, "%s = %r is not finite", names[k], values[k]), 1;
    for (int k = 0; k < 5; ++k)
        if (fabs(values[k]) > ABSURD)
            return pcn_addf(why, "parameter %s = %r is absurd: |%s| must be <= %G (SI units)", names[k], values[k],
                            names[k], ABSURD), 1;
    for (int k = 0; k < 3; ++k)
        if (values[k] <= 0.0) return pcn_addf(why, "parameter %s = %r must be > 0", names[k], values[k]), 1;
    double T = values[2], nyquist = 0.5 / T, lowest = MIN_FC_T / T;
    if (T < 1e-9) return pcn_addf(why, "parameter T = %r s is below the shortest step %G s", T, 1e-9), 1;
    for (int k = 0; k < 2; ++k) {
        if (values[k] >= nyquist)
            return pcn_addf(why, "parameter %s = %r Hz must be below 1/(2T) = %G Hz", names[k], values[k], nyquist), 1;
        if (values[k] < lowest)
            return pcn_addf(why, "parameter %s = %r Hz is below %G/T = %G Hz: the filter discretised at T = %r s "
                            "would be singular", names[k], values[k], MIN_FC_T, lowest, T), 1;
    }
    return 0;
}

static int setup(pcn_instance *in, pcn_text *why)
{
    const double *r = in->real;
    if (check_parameters(r, why)) return 1;
    if (r[PCN_SLOT_fc_vel] != PCN_DESIGN_FC_VEL || r[PCN_SLOT_fc_acc] != PCN_DESIGN_FC_ACC ||
        r[PCN_SLOT_T] != PCN_DESIGN_T)
        return pcn_addf(why, "parameters fc_vel = %r Hz, fc_acc = %r Hz, T = %r s: this native FMU carries the "
                        "filter design for fc_vel = %r Hz, fc_acc = %r Hz, T = %r s only (the Bessel design needs "
                        "scipy: build the native FMU with these values as its start values, or use the pythonfmu "
                        "FMU)", r[PCN_SLOT_fc_vel], r[PCN_SLOT_fc_acc], r[PCN_SLOT_T], PCN_DESIGN_FC_VEL,
                        PCN_DESIGN_FC_ACC, PCN_DESIGN_T), 1;
    memcpy(in->data, pcn_design_buffer, sizeof(double) * PCN_DESIGN_BUFFER_WORDS);
    *counter(in) = (pcn_sampling){0.0, 0.0};
    if (in->boolean[PCN_SLOT_start_from_input]) return 0;
    pc_derivator_context c = context(in);
    const double q0[CHANNELS] = {r[PCN_SLOT_q1_0], r[PCN_SLOT_q2_0]};
    pc_refusal refusal;
    if (pc_derivator_reset(&c, q0, &refusal) == PC_OK) return 0;
    return kernel_refusal(&refusal, q0, INFINITY, why), 1;
}

static int check_step(pcn_instance *in, double t, double h, pcn_text *why)
{
    return pcn_sampling_check(counter(in), in, in->real[PCN_SLOT_T], in->integer[PCN_SLOT_sample_phase], t, h, why);
}

/* The model's step at a sample (the slave's sample). */
static int sample(pcn_instance *in, double t, pcn_text *why)
{
    double *r = in->real;
    const double q[CHANNELS] = {r[PCN_SLOT_q1], r[PCN_SLOT_q2]};
    const char *names[CHANNELS] = {"q1", "q2"};
    for (int k = 0; k < CHANNELS; ++k) {
        if (!isfinite(q[k]))
            return pcn_addf(pcn_timed(why), "input %s = %r at t = %G s is not finite", names[k], q[k], t), 1;
        if (fabs(q[k]) > ABSURD)
            return pcn_addf(pcn_timed(why), "input %s = %r rad at t = %G s is absurd: |%s| must be <= %G rad", names[k],
                            q[k], t, names[k], ABSURD), 1;
    }
    pc_derivator_context c = context(in);
    double out[2 * CHANNELS];
    pc_refusal refusal;
    int code = pc_derivator_step(&c, q, ABSURD, out, &refusal);
    if (code == PC_DERIVATOR_NONFINITE_OUTPUT)
        return pcn_addf(pcn_timed(why), "the estimates (dq1, dq2, ddq1, ddq2) = (%r, %r, %r, %r) at t = %G s are not "
                        "finite (inputs q1 = %r, q2 = %r rad)", out[0], out[1], out[2], out[3], t, q[0], q[1]), 1;
    if (code != PC_OK) return kernel_refusal(&refusal, q, ABSURD, why), 1;
    r[PCN_SLOT_dq1] = out[0];
    r[PCN_SLOT_dq2] = out[1];
    r[PCN_SLOT_ddq1] = out[2];
    r[PCN_SLOT_ddq2] = out[3];
    return 0;
}

/* Sample on sub-step sample_phase, hold the estimates on the others. */
static int step(pcn_instance *in, double t, double h, pcn_text *why)
{
    (void)h;
    pcn_sampling *s = counter(in);
    if (PCN_SAMPLES(s, in, t) && sample(in, t, why)) return 1;
    s->substep = pc_sampling_next(s->substep, s->substeps);
    return 0;
}

/* A restored buffer may change only the run words (started, the state): the sizes, 1/T and
 * the sections are the design (configuration), or all zero in a state taken before
 * the model was built. */
static int check_data(const pcn_instance *in, const double *data, pcn_text *why)
{
    (void)in;
    const long state = PCN_DESIGN_BUFFER_WORDS - (PCN_DERIVATOR_STATES + 1) * CHANNELS;
    int unbuilt = 1;
    for (long k = 0; k < PCN_DESIGN_BUFFER_WORDS; ++k) unbuilt &= data[k] == 0.0;
    if (unbuilt) return pcn_sampling_check_data((const pcn_sampling *)(data + PCN_DESIGN_BUFFER_WORDS), why);
    for (long k = 0; k < state; ++k) {
        if (k == 2) continue;   /* started */
        if (memcmp(&data[k], &pcn_design_buffer[k], sizeof(double)) != 0)
            return pcn_addf(why, "word %d of the derivator's buffer differs from the design: it is configuration",
                            (int)k), 1;
    }
    if (data[2] != 0.0 && data[2] != 1.0) return pcn_addf(why, "the derivator's started word is %r", data[2]), 1;
    return pcn_sampling_check_data((const pcn_sampling *)(data + PCN_DESIGN_BUFFER_WORDS), why);
}

const pcn_model pcn_this_model = {
    .identifier = PCN_IDENTIFIER,
    .accepted_steps = PCN_SAMPLING_ACCEPTS,
    .data_words = PCN_DESIGN_BUFFER_WORDS + PCN_SAMPLING_WORDS,
    .scratch_words = PCN_DERIVATOR_STATES * CHANNELS,
    .setup = setup,
    .check_step = check_step,
    .step = step,
    .check_data = check_data,
};
