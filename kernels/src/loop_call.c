#include "loop_call.h"

int pc_loop_call_step(pc_loop_call *c)
{
    pc_loop_run(c->plan, c->values, c->record, c->k, c->k + 1, c->t, c->h, &c->stop);
    return c->stop.member;
}
