/* Native Trajectory (fmus/slaves/parcosim_trajectory.py) over the kernel pc_trajectory_sample.
 *
 * controller/trajectories.py packs each kind's buffer; the build packs all four kinds with the
 * FMU's parameters then (cycles, side_time, frequency, x_hold, y_hold), so `kind` may be set
 * freely; a parameter that the chosen kind uses, set away from its build value, is refused by
 * name at initialisation (docs/native.md).  No model data: the buffer follows from `kind`.
 */
#include <math.h>
#include <string.h>

#include "model_config.h"
#include "pcn_model.h"
#include "trajectory.h"

#define ABSURD 1e6   /* fmus/slave/refusals.py */
#define TINY 1e-12
#define PRESET_CYCLES (-1)

typedef struct {
    const char *name;
    const double *buffer;
    long words;
    double start_x, start_y;
    int uses_cycles, uses_side_time, uses_frequency, uses_hold;
} kind;

static const kind KINDS[] = {
    {"thesis_circle", pcn_buffer_thesis_circle, PCN_BUFFER_THESIS_CIRCLE_WORDS, PCN_START_X_THESIS_CIRCLE,
     PCN_START_Y_THESIS_CIRCLE, 1, 0, 0, 0},
    {"circle", pcn_buffer_circle, PCN_BUFFER_CIRCLE_WORDS, PCN_START_X_CIRCLE, PCN_START_Y_CIRCLE, 1, 0, 1, 0},
    {"triangle", pcn_buffer_triangle, PCN_BUFFER_TRIANGLE_WORDS, PCN_START_X_TRIANGLE, PCN_START_Y_TRIANGLE, 1, 1,
     0, 0},
    {"hold", pcn_buffer_hold, PCN_BUFFER_HOLD_WORDS, PCN_START_X_HOLD, PCN_START_Y_HOLD, 0, 0, 0, 1},
};
#define N_KINDS (int)(sizeof KINDS / sizeof KINDS[0])

static const kind *chosen(const pcn_instance *in)
{
    for (int k = 0; k < N_KINDS; ++k)
        if (strcmp(in->string[PCN_SLOT_kind], KINDS[k].name) == 0) return &KINDS[k];
    return NULL;
}

/* The slave's checks: require_finite, refuse_absurd, refuse_tiny, then from_parameters'. */
static int check_parameters(const pcn_instance *in, pcn_text *why)
{
    const char *names[] = {"side_time", "x_hold", "y_hold", "frequency"};
    const double values[] = {in->real[PCN_SLOT_side_time], in->real[PCN_SLOT_x_hold], in->real[PCN_SLOT_y_hold],
                             in->real[PCN_SLOT_frequency]};
    for (int k = 0; k < 4; ++k)
        if (!isfinite(values[k])) return pcn_addf(why, "%s = %r is not finite", names[k], values[k]), 1;
    for (int k = 0; k < 4; ++k)
        if (fabs(values[k]) > ABSURD)
            return pcn_addf(why, "parameter %s = %r is absurd: |%s| must be <= %G (SI units)", names[k], values[k],
                            names[k], ABSURD), 1;
    if (values[0] > 0.0 && values[0] < TINY)
        return pcn_addf(why, "parameter side_time = %r is absurdly small: it must be >= %G (SI units)", values[0],
                        TINY), 1;
    const char *name = in->string[PCN_SLOT_kind];
    if (strcmp(name, "hold") == 0) return 0;
    int cycles = in->integer[PCN_SLOT_cycles];
    if (cycles != PRESET_CYCLES) {
        if (cycles < 1) return pcn_addf(why, "parameter cycles = %d must be >= 1 (or -1 for the default)", cycles), 1;
        if (strcmp(name, "triangle") == 0 && cycles > PC_TRAJECTORY_MAX_CYCLES)
            return pcn_addf(why, "parameter cycles = %d must be <= %d (rounds of the triangle)", cycles,
                            PC_TRAJECTORY_MAX_CYCLES), 1;
    }
    if (strcmp(name, "circle") == 0 && values[3] != 1.0 && !(values[3] > 0.0))
        return pcn_addf(why, "parameter frequency = %r Hz must be > 0", values[3]), 1;
    if (strcmp(name, "triangle") == 0 && !(values[0] > 0.0))
        return pcn_addf(why, "parameter side_time = %r s must be > 0", values[0]), 1;
    if (chosen(in) == NULL) {
        pcn_addf(why, "parameter kind: unknown trajectory kind '%s'; valid kinds: ", name);
        for (int k = 0; k < N_KINDS; ++k) pcn_addf(why, k ? ", %s" : "%s", KINDS[k].name);
        return 1;
    }
    return 0;
}

/* A parameter the kind uses away from the value its buffer was packed with. */
static int refuse_unbuilt(const pcn_instance *in, const kind *k, pcn_text *why)
{
    const char *what = NULL;
    double value = 0.0, built = 0.0;
    if (k->uses_cycles && in->integer[PCN_SLOT_cycles] != PCN_BUILT_CYCLES)
        return pcn_addf(why, "parameter cycles = %d: this native FMU carries the %s trajectory for cycles = %d only "
                        "(build the native FMU with that value as its start value, or use the pythonfmu FMU)",
                        in->integer[PCN_SLOT_cycles], k->name, PCN_BUILT_CYCLES), 1;
    if (k->uses_side_time && in->real[PCN_SLOT_side_time] != PCN_BUILT_SIDE_TIME)
        what = "side_time", value = in->real[PCN_SLOT_side_time], built = PCN_BUILT_SIDE_TIME;
    else if (k->uses_frequency && in->real[PCN_SLOT_frequency] != PCN_BUILT_FREQUENCY)
        what = "frequency", value = in->real[PCN_SLOT_frequency], built = PCN_BUILT_FREQUENCY;
    else if (k->uses_hold && in->real[PCN_SLOT_x_hold] != PCN_BUILT_X_HOLD)
        what = "x_hold", value = in->real[PCN_SLOT_x_hold], built = PCN_BUILT_X_HOLD;
    else if (k->uses_hold && in->real[PCN_SLOT_y_hold] != PCN_BUILT_Y_HOLD)
        what = "y_hold", value = in->real[PCN_SLOT_y_hold], built = PCN_BUILT_Y_HOLD;
    if (what == NULL) return 0;
    return pcn_addf(why, "parameter %s = %r: this native FMU carries the %s trajectory for %s = %r only (build the "
                    "native FMU with that value as its start value, or use the pythonfmu FMU)", what, value, k->name,
                    what, built), 1;
}

/* The reference at t into the outputs (GuardedSlave's _publish). */
static int publish(pcn_instance *in, const kind *k, double t, pcn_text *why)
{
    double out[6];
    pc_refusal r;
    int code = pc_trajectory_sample(k->buffer, k->words, t, out, &r);
    if (code == PC_TRAJECTORY_BAD_TIME) {   /* controller.trajectories._REASONS */
        pcn_quantify(why, code, "bad_time", "t", r.value, "s", t);
        return pcn_addf(why, "trajectory time must be >= 0 s, got %r", r.value), 1;
    }
    if (code != PC_OK) {
        pcn_quantify(why, code, "bad_layout", "", r.value, "", t);
        return pcn_addf(why, "the trajectory's buffer is damaged: word %d = %r does not fit it", r.index, r.value), 1;
    }
    const int slots[6] = {PCN_SLOT_x_d, PCN_SLOT_y_d, PCN_SLOT_dx_d, PCN_SLOT_dy_d, PCN_SLOT_ddx_d, PCN_SLOT_ddy_d};
    for (int j = 0; j < 6; ++j) in->real[slots[j]] = out[j];
    return 0;
}

static int setup(pcn_instance *in, pcn_text *why)
{
    if (check_parameters(in, why)) return 1;
    const kind *k = chosen(in);
    if (refuse_unbuilt(in, k, why)) return 1;
    in->real[PCN_SLOT_x_start] = k->start_x;
    in->real[PCN_SLOT_y_start] = k->start_y;
    return publish(in, k, in->start_time, why);
}

static int step(pcn_instance *in, double t, double h, pcn_text *why)
{
    const kind *k = chosen(in);
    if (k == NULL) return pcn_addf(why, "parameter kind '%s' is no trajectory", in->string[PCN_SLOT_kind]), 1;
    return publish(in, k, t + h, why);
}

const pcn_model pcn_this_model = {
    .identifier = PCN_IDENTIFIER,
    .accepted_steps = "any step size h with 1e-09 s <= h and t + h <= 1e+09 s",
    .data_words = 0,
    .scratch_words = 0,
    .setup = setup,
    .step = step,
};
