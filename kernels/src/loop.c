#include "loop.h"

static int first_of(const int *end, int m)
{
    return m == 0 ? 0 : end[m - 1];
}

/* Members [first, end) stepped once each, in order, from t over dt: each one's inputs copied
 * from their slots, its I/O step, its outputs copied to their slots.  The member that declined
 * (its refusal in *r), or -1. */
static int step_members(const pc_loop_plan *p, int first, int end, double *values, double t, double dt,
                        pc_refusal *r)
{
    const pc_io_fn *const io = p->io;
    void *const *const context = p->context;
    double *const *const xs = p->x;
    const int *const in_end = p->in_end, *const in_x = p->in_x, *const in_slot = p->in_slot;
    const int *const out_end = p->out_end, *const out_x = p->out_x, *const out_slot = p->out_slot;
    int in = first_of(in_end, first), out = first_of(out_end, first);
    for (int m = first; m < end; ++m) {
        double *const x = xs[m];
        for (const int last = in_end[m]; in < last; ++in) x[in_x[in]] = values[in_slot[in]];
        *r = (pc_refusal){PC_OK, 0, 0.0};
        if (io[m](context[m], x, t, dt, r) != PC_OK) return m;
        for (const int last = out_end[m]; out < last; ++out) values[out_slot[out]] = x[out_x[out]];
    }
    return -1;
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

static void stopped(pc_loop_stop *stop, int64_t k, int member, int substep, double t, const pc_refusal *r)
{
    stop->step = k;
    stop->member = member;
    stop->substep = substep;
    stop->time = t;
    stop->refusal = *r;
}

void pc_loop_run(const pc_loop_plan *p, double *values, double *record, int64_t k0, int64_t k1, double t0, double h,
                 pc_loop_stop *stop)
{
    int single = 1;                              /* every group one sub-step: its members in one run */
    for (int g = 0; g < p->n_groups; ++g) single = single && p->group_substeps[g] == 1;
    const int members = first_of(p->group_end, p->n_groups), n_record = p->n_record;
    const int *const record_slot = p->record_slot;
    pc_refusal r;
    for (int64_t k = k0; k < k1; ++k) {
        const double t = t0 + (double)k * h;     /* from the step count, never summed */
        if (single) {
            const int m = step_members(p, 0, members, values, t, h, &r);
            if (m >= 0) {
                stopped(stop, k, m, 0, t, &r);
                return;
            }
        } else {
            for (int g = 0; g < p->n_groups; ++g) {
                const int substeps = p->group_substeps[g];
                const double dt = h / substeps;
                for (int j = 0; j < substeps; ++j) {
                    const double start = substeps > 1 ? t + j * dt : t;
                    const int m = step_members(p, first_of(p->group_end, g), p->group_end[g], values, start, dt, &r);
                    if (m >= 0) {
                        stopped(stop, k, m, j, t, &r);
                        return;
                    }
                }
            }
        }
        if (n_record > 0) {                      /* record may be NULL without columns */
            double *row = record + (size_t)(k + 1) * n_record;
            for (int c = 0; c < n_record; ++c) row[c] = values[record_slot[c]];
            if (k + 1 < k1) prefetch_row(row + n_record, n_record);
        }
    }
    stop->step = k1;
    stop->member = -1;
    stop->substep = 0;
    stop->time = t0 + (double)k1 * h;
}
