/* Native ClosedLoop (fmus/slaves/parcosim_closedloop.py): a scene's whole loop, the compiled
 * mode's plan (kernels/src/loop.c) laid out from build data (pcn_loop.h, loop_table.c made by
 * fmus/native/loopimage.py and loopbuild.py).  Every component's buffers were initialised by
 * its slave at build time, with the scene's parameters: a parameter set away from its build
 * value is refused by name at initialisation (docs/native.md). */
#include <math.h>
#include <string.h>

#include "loop_contexts.h"
#include "model_config.h"
#include "pcn_loop.h"
#include "pcn_model.h"

/* The scratch arena after the contexts: the plan, then its context and x pointer arrays. */
typedef struct {
    pc_loop_plan plan;
    int built;
} loop_head;

#define HEAD_WORDS ((long)((sizeof(loop_head) + sizeof(double) - 1) / sizeof(double)))

/* The plan's context and x pointer arrays take a word each. */
_Static_assert(sizeof(void *) <= sizeof(double), "a pointer fits a word of the scratch arena");

static loop_head *head(const pcn_instance *in) { return (loop_head *)(in->scratch + PCN_LOOP_SCRATCH_WORDS); }

/* The contexts filled in, their pointers into this instance's arenas; the plan over them.
 * Depends on the arenas' addresses only. */
static pc_loop_plan *plan_of(pcn_instance *in)
{
    loop_head *h = head(in);
    if (h->built) return &h->plan;
    unsigned char *scratch = (unsigned char *)in->scratch;
    pcn_loop_fill((pcn_loop_contexts *)in->scratch, in->data);
    void **contexts = (void **)(in->scratch + PCN_LOOP_SCRATCH_WORDS + HEAD_WORDS);
    double **x = (double **)(in->scratch + PCN_LOOP_SCRATCH_WORDS + HEAD_WORDS + PCN_LOOP_MEMBERS);
    for (int m = 0; m < pcn_loop.n_members; ++m) {
        contexts[m] = scratch + pcn_loop.members[m].context;
        x[m] = in->data + pcn_loop.members[m].x;
    }
    h->plan = (pc_loop_plan){pcn_loop.n_groups, pcn_loop.group_substeps, pcn_loop.group_end, pcn_loop.io, contexts,
                             x, pcn_loop.in_end, pcn_loop.in_x, pcn_loop.in_slot, pcn_loop.out_end, pcn_loop.out_x,
                             pcn_loop.out_slot, 0, NULL};
    h->built = 1;
    return &h->plan;
}

static void publish(pcn_instance *in)
{
    const double *values = in->data + pcn_loop.values;
    for (int k = 0; k < pcn_loop.n_outputs; ++k)
        in->real[pcn_loop.output_variable[k]] = values[pcn_loop.output_value[k]];
}

/* A parameter away from the value the loop was built with. */
static int refuse_unbuilt(const pcn_instance *in, pcn_text *why)
{
    for (int k = 0; k < pcn_n_variables; ++k) {
        const pcn_variable *v = &pcn_variables[k];
        if (v->causality != PCN_PARAMETER) continue;
        const char *name = v->name;
        int same = 1;
        pcn_text value, built;
        pcn_clear(&value);
        pcn_clear(&built);
        if (v->type == PCN_REAL) {
            double x = in->real[v->slot];
            same = x == v->start || (isnan(x) && isnan(v->start));
            pcn_addf(&value, "%r", x);
            pcn_addf(&built, "%r", v->start);
        } else if (v->type == PCN_INTEGER) {
            same = in->integer[v->slot] == (int)v->start;
            pcn_addf(&value, "%d", in->integer[v->slot]);
            pcn_addf(&built, "%d", (int)v->start);
        } else if (v->type == PCN_BOOLEAN) {
            same = in->boolean[v->slot] == (v->start != 0.0);
            pcn_addf(&value, "%B", in->boolean[v->slot]);
            pcn_addf(&built, "%B", v->start != 0.0);
        } else {
            same = strcmp(in->string[v->slot], v->start_string) == 0;
            pcn_addf(&value, "'%s'", in->string[v->slot]);
            pcn_addf(&built, "'%s'", v->start_string);
        }
        if (!same)
            return pcn_addf(why, "parameter %s = %s: this native FMU carries its scene's loop built with %s = %s only "
                            "(export the scene with that value, or use the pythonfmu FMU)", name, value.text, name,
                            built.text), 1;
    }
    return 0;
}

static int setup(pcn_instance *in, pcn_text *why)
{
    if (refuse_unbuilt(in, why)) return 1;
    memcpy(in->data, pcn_loop.data, sizeof(double) * (size_t)pcn_loop.data_words);
    plan_of(in);
    publish(in);
    return 0;
}

/* math.isclose */
static int isclose(double a, double b, double rel, double abs_tol)
{
    return a == b || fabs(a - b) <= fmax(rel * fmax(fabs(a), fabs(b)), abs_tol);
}

/* The twin's call budget: the steps h of one doStep, refused beyond the most its slave takes in a call. */
static int check_step(pcn_instance *in, double t, double h, pcn_text *why)
{
    (void)in;
    const double n = nearbyint(h / pcn_loop.step);
    if (n > (double)pcn_loop.most_steps)
        return pcn_addf(pcn_timed(why), "step size h = %r s at t = %r s needs %G of its steps h = %r s, more than the "
                        "%d one call takes; take steps of at most %G s (%d of its steps)", h, t, n, pcn_loop.step,
                        (int)pcn_loop.most_steps, (double)pcn_loop.most_steps * pcn_loop.step,
                        (int)pcn_loop.most_steps), 1;
    return 0;
}

/* fmus/systemfmu/cores.py's _steps_in, then the loop's steps. */
static int step(pcn_instance *in, double t, double h, pcn_text *why)
{
    const double H = pcn_loop.step;
    double *steps = in->data + pcn_loop.steps;    /* the loop's clock: step k starts at k H, never a sum */
    const double now = *steps * H;
    const double n = isfinite(h) && h > 0.0 ? nearbyint(h / H) : 0.0;
    if (n < 1.0 || !isclose(h, n * H, 1e-9, 0.0))
        return pcn_addf(pcn_timed(why), "step size %r s at t = %G s: this FMU steps its system at its communication "
                        "step; the step size must be a whole multiple of h = %r s", h, t, H), 1;
    if (!isclose(t, now, 0.0, 1e-6 * H))
        return pcn_addf(pcn_timed(why), "communication point t = %r s does not follow the last one (%r s)", t,
                        now), 1;
    pc_loop_stop stop;
    const int64_t k = (int64_t)*steps;
    pc_loop_run(plan_of(in), in->data + pcn_loop.values, NULL, k, k + (int64_t)n, 0.0, H, &stop);
    *steps = (double)stop.step;
    publish(in);
    if (stop.member < 0) return 0;
    const pcn_member *m = &pcn_loop.members[stop.member];
    return pcn_addf(pcn_timed(why), "component %s (%s): its kernel %s declined the step from t = %r s (sub-step %d; "
                    "refusal code %d, quantity %d = %r); the pythonfmu ClosedLoop takes such a step in Python, this "
                    "native FMU has no Python", m->name, m->model, m->kernel, stop.time, stop.substep,
                    stop.refusal.code, stop.refusal.index, stop.refusal.value), 1;
}

/* Saved data is this build's: all zero (a state taken before set-up), or every word the loop
 * never changes (sizes, designs, tables) as built. */
static int check_data(const pcn_instance *in, const double *data, pcn_text *why)
{
    (void)in;
    int unbuilt = 1;
    for (long k = 0; k < pcn_loop.data_words && unbuilt; ++k) unbuilt = data[k] == 0.0 && !signbit(data[k]);
    if (unbuilt) return 0;
    for (int r = 0; r < pcn_loop.n_fixed; ++r) {
        const long first = pcn_loop.fixed[2 * r], words = pcn_loop.fixed[2 * r + 1];
        for (long k = first; k < first + words; ++k)
            if (memcmp(&data[k], &pcn_loop.data[k], sizeof(double)) != 0)
                return pcn_addf(why, "word %d of the loop's data differs from the build's: it is configuration (a "
                                "kernel's sizes, design or table), which the loop never changes", (int)k), 1;
    }
    return 0;
}

const pcn_model pcn_this_model = {
    .identifier = PCN_IDENTIFIER,
    .accepted_steps = PCN_LOOP_ACCEPTS,
    .data_words = PCN_LOOP_DATA_WORDS,
    .scratch_words = PCN_LOOP_SCRATCH_WORDS + HEAD_WORDS + 2 * PCN_LOOP_MEMBERS,
    .setup = setup,
    .check_step = check_step,
    .step = step,
    .check_data = check_data,
};
