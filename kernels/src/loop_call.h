/* One communication step of a pc_loop_plan called from Python with one argument: the in-process
 * stepper's kernel segments and its row writer (fmus/cosim/segments.py).  The caller sets `t`
 * (and `k`) in the record and calls pc_loop_call_step: a ctypes call of one pointer costs a
 * third of one of pc_loop_run's eight converted arguments. */
#ifndef PC_LOOP_CALL_H
#define PC_LOOP_CALL_H

#include "loop.h"

typedef struct {
    const pc_loop_plan *plan;
    double *values;
    double *record;              /* row k + 1 gets the plan's recorded slots (NULL: none recorded) */
    int k;                       /* the step's index */
    double t;                    /* the step's start */
    double h;                    /* the communication step */
    pc_loop_stop stop;
} pc_loop_call;

/* pc_loop_run of step c->k from c->t; the member that declined (c->stop says where), or -1. */
int pc_loop_call_step(pc_loop_call *c);

#endif
