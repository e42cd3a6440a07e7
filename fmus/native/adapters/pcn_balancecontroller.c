/* Native BalanceController (fmus/slaves/parcosim_balancecontroller.py) over pc_balance_sample.
 *
 * The observer and LQR are designed with python-control at the build, for the FMU's T,
 * v_battery, electrics, friction, yaw and encoder_counts then; both routes are packed
 * (pcn_buffer_<route>), so `route` is free.  A design parameter away from its build value is
 * refused by name at initialisation, after the slave's own first checks (docs/native.md).
 * Steps h = T / n sample on sub-step sample_phase of each period and hold the outputs in
 * between (pcn_sampling.h).  Model data (FMU state): the kernel's pc_balance (configuration,
 * then run state), then the sub-step counter.
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "balance.h"
#include "model_config.h"
#include "pcn_model.h"
#include "pcn_sampling.h"

#define ABSURD 1e6   /* fmus/slave/refusals.py */
#define MIN_STEP 1e-9
#define WORDS ((long)(sizeof(pc_balance) / sizeof(double)))
#define CONFIGURATION ((long)(sizeof(pc_balance_params) / sizeof(double)))

static pcn_sampling *counter(pcn_instance *in) { return (pcn_sampling *)(in->data + WORDS); }

static const char *const ROUTES[] = {"hold", "forward_turn"};
static const double *const BUFFERS[] = {pcn_buffer_hold, pcn_buffer_forward_turn};

static int route(const pcn_instance *in)
{
    for (int k = 0; k < 2; ++k)
        if (strcmp(in->string[PCN_SLOT_route], ROUTES[k]) == 0) return k;
    return -1;
}

/* A design parameter away from the value the FMU's design was made for. */
static int refuse_unbuilt(const pcn_instance *in, pcn_text *why)
{
    const double *r = in->real;
    const char *tail = ": this native FMU carries the balance design for T = %r s, v_battery = %r V, electrics = "
                       "'%s', friction = %B, yaw = %B, encoder_counts = %d only (build the native FMU with these "
                       "values as its start values, or use the pythonfmu FMU)";
    if (r[PCN_SLOT_T] != PCN_BUILT_T) pcn_addf(why, "parameter T = %r s", r[PCN_SLOT_T]);
    else if (r[PCN_SLOT_v_battery] != PCN_BUILT_V_BATTERY)
        pcn_addf(why, "parameter v_battery = %r V", r[PCN_SLOT_v_battery]);
    else if (strcmp(in->string[PCN_SLOT_electrics], pcn_built_electrics[0]) != 0)
        pcn_addf(why, "parameter electrics = '%s'", in->string[PCN_SLOT_electrics]);
    else if (in->boolean[PCN_SLOT_friction] != PCN_BUILT_FRICTION)
        pcn_addf(why, "parameter friction = %B", in->boolean[PCN_SLOT_friction]);
    else if (in->boolean[PCN_SLOT_yaw] != PCN_BUILT_YAW) pcn_addf(why, "parameter yaw = %B", in->boolean[PCN_SLOT_yaw]);
    else if (in->integer[PCN_SLOT_encoder_counts] != PCN_BUILT_ENCODER_COUNTS)
        pcn_addf(why, "parameter encoder_counts = %d", in->integer[PCN_SLOT_encoder_counts]);
    else return 0;
    pcn_addf(why, tail, PCN_BUILT_T, PCN_BUILT_V_BATTERY, pcn_built_electrics[0], PCN_BUILT_FRICTION, PCN_BUILT_YAW,
             PCN_BUILT_ENCODER_COUNTS);
    return 1;
}

static int setup(pcn_instance *in, pcn_text *why)
{
    const char *names[2] = {"T", "v_battery"};
    const double values[2] = {in->real[PCN_SLOT_T], in->real[PCN_SLOT_v_battery]};
    for (int k = 0; k < 2; ++k)
        if (!isfinite(values[k])) return pcn_addf(why, "%s = %r is not finite", names[k], values[k]), 1;
    for (int k = 0; k < 2; ++k)
        if (fabs(values[k]) > ABSURD)
            return pcn_addf(why, "parameter %s = %r is absurd: |%s| must be <= %G (SI units)", names[k], values[k],
                            names[k], ABSURD), 1;
    if (!(values[0] >= MIN_STEP)) return pcn_addf(why, "parameter T = %r s must be >= %G s", values[0], MIN_STEP), 1;
    int k = route(in);
    if (k < 0)
        return pcn_addf(why, "parameter route = '%s'; valid: %s, %s", in->string[PCN_SLOT_route], ROUTES[0],
                        ROUTES[1]), 1;
    if (refuse_unbuilt(in, why)) return 1;
    memcpy(in->data, BUFFERS[k], sizeof(double) * WORDS);
    *counter(in) = (pcn_sampling){0.0, 0.0};
    return 0;
}

static int check_step(pcn_instance *in, double t, double h, pcn_text *why)
{
    return pcn_sampling_check(counter(in), in, in->real[PCN_SLOT_T], in->integer[PCN_SLOT_sample_phase], t, h, why);
}

/* controller.fastbalance.WORD_NAMES[index]: the field of pc_balance holding the word, with its
 * element for an array ("K[3]"). */
static void word_name(int index, char *out, size_t size)
{
    const pc_field *const parts[2] = {pc_balance_params_fields, pc_balance_state_fields};
    snprintf(out, size, "%d", index);
    for (int p = 0; p < 2; ++p)
        for (const pc_field *f = parts[p]; f->name; ++f) {
            const int first = pc_balance_fields[p].offset + f->offset;
            if (first <= index && index < first + f->count) {
                if (f->count == 1) snprintf(out, size, "%s", f->name);
                else snprintf(out, size, "%s[%d]", f->name, index - first);
            }
        }
}

/* The controller's sample at t (the slave's sample). */
static int sample(pcn_instance *in, double t, pcn_text *why)
{
    static const char *const inputs[3] = {"enc_l", "enc_r", "gyro"};
    double *r = in->real, x[15] = {r[PCN_SLOT_enc_l], r[PCN_SLOT_enc_r], r[PCN_SLOT_gyro]};
    for (int k = 0; k < 3; ++k)   /* refuse_absurd_inputs: NaN passes, the kernel names it */
        if (fabs(x[k]) > ABSURD)
            return pcn_addf(pcn_timed(why), "input %s = %r at t = %G s is absurd: |%s| must be <= %G", inputs[k], x[k],
                            t, inputs[k], ABSURD), 1;
    pc_refusal refusal;
    int code = pc_balance_sample((pc_balance *)in->data, x, t, INFINITY, &refusal);
    if (code == PC_BALANCE_BAD_INPUT) {   /* controller.balance.REASONS */
        pcn_quantify(why, code, "input_not_finite", inputs[refusal.index], refusal.value, "", t);
        return pcn_addf(pcn_timed(why), "input %s = %r at t = %G s is not finite", inputs[refusal.index], refusal.value,
                        t), 1;
    }
    if (code != PC_OK) {   /* PC_BALANCE_BAD_BUFFER */
        char word[64];
        word_name(refusal.index, word, sizeof word);
        pcn_quantify(why, code, "bad_buffer", word, refusal.value, "", t);
        return pcn_addf(pcn_timed(why), "the balance controller's buffer word %s = %r at t = %G s is not a size or "
                        "state index its arrays have", word, refusal.value, t), 1;
    }
    const int slots[12] = {PCN_SLOT_v_l, PCN_SLOT_v_r, PCN_SLOT_tau_l, PCN_SLOT_tau_r, PCN_SLOT_x_d, PCN_SLOT_y_d,
                           PCN_SLOT_theta_hat, PCN_SLOT_psi_hat, PCN_SLOT_phi_hat, PCN_SLOT_dtheta_hat,
                           PCN_SLOT_dpsi_hat, PCN_SLOT_dphi_hat};
    for (int k = 0; k < 12; ++k) r[slots[k]] = x[3 + k];
    return 0;
}

/* Sample on sub-step sample_phase, hold the outputs on the others. */
static int step(pcn_instance *in, double t, double h, pcn_text *why)
{
    (void)h;
    pcn_sampling *s = counter(in);
    if (PCN_SAMPLES(s, in, t) && sample(in, t, why)) return 1;
    s->substep = pc_sampling_next(s->substep, s->substeps);
    return 0;
}

/* Restored data: the configuration words are the instance's route's design (or all zero,
 * a state taken before set-up); started is 0 or 1. */
static int check_data(const pcn_instance *in, const double *data, pcn_text *why)
{
    if (pcn_sampling_check_data((const pcn_sampling *)(data + WORDS), why)) return 1;
    int zero = 1;
    for (long k = 0; k < WORDS; ++k) zero &= data[k] == 0.0;
    if (zero) return 0;
    int k = route(in);
    if (k < 0 || memcmp(data, BUFFERS[k], sizeof(double) * CONFIGURATION) != 0)
        return pcn_addf(why, "the balance controller's configuration words differ from this instance's design"), 1;
    double started = ((const pc_balance *)data)->state.started;
    if (started != 0.0 && started != 1.0) return pcn_addf(why, "the controller's started word is %r", started), 1;
    return 0;
}

const pcn_model pcn_this_model = {
    .identifier = PCN_IDENTIFIER,
    .accepted_steps = PCN_SAMPLING_ACCEPTS,
    .data_words = WORDS + PCN_SAMPLING_WORDS,
    .scratch_words = 0,
    .setup = setup,
    .check_step = check_step,
    .step = step,
    .check_data = check_data,
};
