/* An SSP package stepped by Ecos's C library (libecosc.so, shipped in the ecospy wheel) in a
 * C program: no Python in the process (issue 28, item 6).
 *
 *     ecos_host PACKAGE.ssp STEP STOP PARAMETER_SET ONE_CPU [INSTANCE::VARIABLE ...]
 *
 * STEP, STOP in seconds; PARAMETER_SET the set ecos_simulation_init applies ("-": none);
 * ONE_CPU 1 binds the process to one CPU first (as fmus.ssp.run runs Ecos: its steps use
 * C++17 parallel algorithms), 0 leaves it on all.  Ecos takes one call per step here, as a
 * host stepping and reading each step would.  It prints "key value" lines: steps,
 * simulated_s, setup_cpu_s (loading, initialising and the first step), timed_s, cpu_s
 * (CPU of all threads, the later steps), thread_cpu_s (the calling thread's), wall_s,
 * threads; then value.INSTANCE::VARIABLE, each Real named after ONE_CPU at the end, %.17g.
 * Exit status 2 on any error, with Ecos's message on stderr.
 *
 * Ecos's C header is not in the wheel: the functions used are declared below from the
 * ctypes signatures of ecospy (EcosSimulation.py, lib.py).
 */
#define _GNU_SOURCE
#include <errno.h>
#include <sched.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "host_clock.h"

void *ecos_simulation_create_from_ssp(const char *ssp_path, double step_size);
bool ecos_simulation_init(void *sim, double start_time, const char *parameter_set);
double ecos_simulation_step(void *sim, size_t steps);
double ecos_simulation_get_time(void *sim);
bool ecos_simulation_get_real(void *sim, const char *identifier, double *value);
bool ecos_simulation_terminate(void *sim);
void ecos_simulation_destroy(void *sim);
const char *ecos_last_error_msg(void);
void ecos_set_log_level(const char *level);

enum { LINE_SIZE = 4096 };

static void fail(const char *what)
{
    const char *why = ecos_last_error_msg();
    fprintf(stderr, "ecos_host: %s%s%s\n", what, why && *why ? ": " : "", why ? why : "");
    exit(2);
}

static double parse_number(const char *text, const char *what)
{
    char *end;
    errno = 0;
    double value = strtod(text, &end);
    if (end == text || *end || errno) {
        fprintf(stderr, "ecos_host: %s is not a number: %s\n", what, text);
        exit(2);
    }
    return value;
}

/* Binds the process to the lowest CPU it may run on. */
static void one_cpu(void)
{
    cpu_set_t set;
    if (sched_getaffinity(0, sizeof set, &set) != 0)
        fail("cannot read the CPU affinity");
    for (int cpu = 0; cpu < CPU_SETSIZE; cpu++)
        if (CPU_ISSET(cpu, &set)) {
            CPU_ZERO(&set);
            CPU_SET(cpu, &set);
            if (sched_setaffinity(0, sizeof set, &set) != 0)
                fail("cannot bind to one CPU");
            return;
        }
}

int main(int argc, char **argv)
{
    if (argc < 6) {
        fprintf(stderr, "usage: %s PACKAGE.ssp STEP STOP PARAMETER_SET|- ONE_CPU(0|1) [INSTANCE::VARIABLE ...]\n",
                argv[0]);
        return 2;
    }
    const double step = parse_number(argv[2], "STEP"), stop = parse_number(argv[3], "STOP");
    const char *parameters = strcmp(argv[4], "-") ? argv[4] : NULL;
    if (!(step > 0.0) || !(stop >= step)) {
        fprintf(stderr, "ecos_host: need STEP > 0 and STOP >= STEP\n");
        return 2;
    }
    if (parse_number(argv[5], "ONE_CPU") != 0.0)
        one_cpu();
    ecos_set_log_level("err");
    const long steps = (long)(stop / step + 0.5);
    double setup_cpu = clock_seconds(CLOCK_PROCESS_CPUTIME_ID);
    void *sim = ecos_simulation_create_from_ssp(argv[1], step);
    if (!sim)
        fail("cannot load the SSP package");
    if (!ecos_simulation_init(sim, 0.0, parameters))
        fail("cannot initialise");
    ecos_simulation_step(sim, 1);
    setup_cpu = clock_seconds(CLOCK_PROCESS_CPUTIME_ID) - setup_cpu;
    double cpu = clock_seconds(CLOCK_PROCESS_CPUTIME_ID), own = clock_seconds(CLOCK_THREAD_CPUTIME_ID),
           wall = clock_seconds(CLOCK_MONOTONIC);
    for (long k = 1; k < steps; k++)
        ecos_simulation_step(sim, 1);
    cpu = clock_seconds(CLOCK_PROCESS_CPUTIME_ID) - cpu;
    own = clock_seconds(CLOCK_THREAD_CPUTIME_ID) - own;
    wall = clock_seconds(CLOCK_MONOTONIC) - wall;
    const double reached = ecos_simulation_get_time(sim);
    if (reached < stop - step / 2)
        fail("the simulation stopped early");
    printf("steps %ld\nsimulated_s %.9f\ntimed_s %.9f\nsetup_cpu_s %.6f\ncpu_s %.6f\nthread_cpu_s %.6f\nwall_s %.6f\n"
           "threads %ld\n", steps, reached, reached - step, setup_cpu, cpu, own, wall, thread_count());
    for (int i = 6; i < argc; i++) {
        double value;
        if (!ecos_simulation_get_real(sim, argv[i], &value))
            fail(argv[i]);
        printf("value.%s %.17g\n", argv[i], value);
    }
    ecos_simulation_terminate(sim);
    ecos_simulation_destroy(sim);
    return 0;
}
