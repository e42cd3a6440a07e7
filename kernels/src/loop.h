/* The compiled mode's step loop (fmus/cosim/compiled.py): a system's components stepped in their
 * Gauss-Seidel order, each through its model's I/O function (pc_io_fn), the connections
 * copies between fixed slots of one value array.  The plan is data built once per run; no
 * code is generated. */
#ifndef PC_LOOP_H
#define PC_LOOP_H

#include <stdint.h>

#include "pc_common.h"

typedef struct {
    int n_groups;
    const int *group_substeps;   /* per group: sub-steps of the communication step */
    const int *group_end;        /* members of group g: [group_end[g-1], group_end[g]) */
    const pc_io_fn *io;          /* per member: its model's I/O step */
    void *const *context;        /* per member: its model's buffers */
    double *const *x;            /* per member: its inputs then outputs */
    const int *in_end;           /* inputs of member m: entries [in_end[m-1], in_end[m]) */
    const int *in_x;             /*   x[in_x[e]] = values[in_slot[e]] before the step */
    const int *in_slot;
    const int *out_end;          /* outputs of member m: entries [out_end[m-1], out_end[m]) */
    const int *out_x;            /*   values[out_slot[e]] = x[out_x[e]] after it */
    const int *out_slot;
    int n_record;                /* recorded slots, one row per communication step */
    const int *record_slot;
} pc_loop_plan;

/* Where a run stopped: the step reached, and when a member declined (status != PC_OK), which
 * member, which sub-step and the step's start time; `refusal` is the member's. */
typedef struct {
    int64_t step;
    int member;                  /* -1: every step of [k0, k1) done */
    int substep;
    double time;
    pc_refusal refusal;
} pc_loop_stop;

/* Steps k0 .. k1-1 of length h, step k from t0 + k h (the step count times h, never a sum, as
 * the in-process stepper; a group's sub-step j from there + j h / n); row k + 1 of `record`
 * (n_record columns) gets the recorded slots after step k.  `stop->time`: the start of the
 * step declined, or t0 + k1 h. */
void pc_loop_run(const pc_loop_plan *plan, double *values, double *record, int64_t k0, int64_t k1, double t0,
                 double h, pc_loop_stop *stop);

#endif
