/* A timing stand-in for a compiled loop member (benchmarks/profile_members.py builds it beside
 * the kernels and puts it in the loop's plan in place of each member's I/O step): it calls the
 * member's own step (pc_io_fn) with its own context and adds the time-stamp counter's ticks of
 * the call to the member's tally.  The loop, the member's inputs and outputs and every result
 * stay what they are; only the ticks are added.  x86-64 reads the TSC (rdtsc, a few ns), other
 * machines CLOCK_MONOTONIC in ns. */
#define _POSIX_C_SOURCE 199309L
#include <stdint.h>
#include <time.h>

#include "pc_common.h"

#if defined(__x86_64__) || defined(__i386__)
#include <x86intrin.h>
static inline uint64_t ticks(void)
{
    return __rdtsc();
}
#else
static inline uint64_t ticks(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (uint64_t)ts.tv_sec * 1000000000u + (uint64_t)ts.tv_nsec;
}
#endif

/* One member's tally: its step and context, the ticks and the calls so far; a call longer than
 * `cap` ticks (the thread descheduled meanwhile, on a shared machine) is counted in `dropped`
 * instead. */
typedef struct {
    pc_io_fn io;
    void *context;
    double ticks;
    double calls;
    double cap;
    double dropped;
} pc_timed_member;

int pc_timed_io(void *context, double *x, double t, double h, pc_refusal *r)
{
    pc_timed_member *m = context;
    const uint64_t start = ticks();
    const int status = m->io(m->context, x, t, h, r);
    const double spent = (double)(ticks() - start);
    if (spent > m->cap) {
        m->dropped += 1.0;
    } else {
        m->ticks += spent;
        m->calls += 1.0;
    }
    return status;
}

/* A member that does nothing: timed in the loop, its tally is the timer's own cost a call. */
int pc_timed_nothing(void *context, double *x, double t, double h, pc_refusal *r)
{
    (void)context, (void)x, (void)t, (void)h, (void)r;
    return PC_OK;
}

/* The counter now (ticks). */
double pc_timed_now(void)
{
    return (double)ticks();
}
