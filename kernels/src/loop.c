#include "loop.h"

static int first_of(const int *end, int m)
{
    return m == 0 ? 0 : end[m - 1];
}

static int step_member(const pc_loop_plan *p, int m, double *values, double t, double dt, pc_refusal *r)
{
    double *x = p->x[m];
    for (int e = first_of(p->in_end, m); e < p->in_end[m]; ++e) x[p->in_x[e]] = values[p->in_slot[e]];
    int status = p->io[m](p->context[m], x, t, dt, r);
    if (status != PC_OK) return status;
    for (int e = first_of(p->out_end, m); e < p->out_end[m]; ++e) values[p->out_slot[e]] = x[p->out_x[e]];
    return PC_OK;
}

/* The next step's row asked into the cache for writing while the members step: rows are
 * written once each, in order, and a row's store otherwise waits for its lines to come in. */
static void prefetch_row(const double *row, int n)
{
#if defined(__GNUC__)
    for (int c = 0; c < n; c += 8) __builtin_prefetch(row + c, 1, 3);
    __builtin_prefetch(row + n - 1, 1, 3);   /* the last line when n is not a multiple of 8 */
#else
    (void)row;
    (void)n;
#endif
}

void pc_loop_run(const pc_loop_plan *p, double *values, double *record, int64_t k0, int64_t k1, double t0, double h,
                 pc_loop_stop *stop)
{
    int single = 1;                              /* every group one sub-step: its members in one run */
    for (int g = 0; g < p->n_groups; ++g) single = single && p->group_substeps[g] == 1;
    const int members = first_of(p->group_end, p->n_groups);
    for (int64_t k = k0; k < k1; ++k) {
        const double t = t0 + (double)k * h;     /* from the step count, never summed */
        for (int m = 0; single && m < members; ++m) {
            pc_refusal r = {PC_OK, 0, 0.0};
            if (step_member(p, m, values, t, h, &r) != PC_OK) {
                stop->step = k;
                stop->member = m;
                stop->substep = 0;
                stop->time = t;
                stop->refusal = r;
                return;
            }
        }
        for (int g = 0; !single && g < p->n_groups; ++g) {
            const int substeps = p->group_substeps[g];
            const double dt = h / substeps;
            for (int j = 0; j < substeps; ++j) {
                const double start = substeps > 1 ? t + j * dt : t;
                for (int m = first_of(p->group_end, g); m < p->group_end[g]; ++m) {
                    pc_refusal r = {PC_OK, 0, 0.0};
                    if (step_member(p, m, values, start, dt, &r) != PC_OK) {
                        stop->step = k;
                        stop->member = m;
                        stop->substep = j;
                        stop->time = t;
                        stop->refusal = r;
                        return;
                    }
                }
            }
        }
        if (p->n_record > 0) {                   /* record may be NULL without columns */
            double *row = record + (size_t)(k + 1) * p->n_record;
            for (int c = 0; c < p->n_record; ++c) row[c] = values[p->record_slot[c]];
            if (k + 1 < k1) prefetch_row(row + p->n_record, p->n_record);
        }
    }
    stop->step = k1;
    stop->member = -1;
    stop->substep = 0;
    stop->time = t0 + (double)k1 * h;
}
