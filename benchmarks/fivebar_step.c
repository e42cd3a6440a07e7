/* The 5R's C step alone (benchmarks/bench_fivebar_kernel.py builds and runs it): the compiled
 * loop's pc_fivebar_plant_io, `steps` (argv[2]) 1 ms steps with the torques of bench_plant.py
 * (20 Hz cosine, 0.02 N m), from the parameters, settings and state read from the file argv[1];
 * prints the best µs per step of `runs` (argv[3], default 7) runs, in CPU time of the thread
 * (a run another process interrupts is not charged for the wait). */
#define _POSIX_C_SOURCE 199309L   /* clock_gettime */
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "fivebar.h"

int main(int argc, char **argv)
{
    double p[sizeof(pc_fivebar_params) / sizeof(double)], s[sizeof(pc_fivebar_settings) / sizeof(double)];
    double y0[14], y[14], scratch[PC_FIVEBAR_SCRATCH(14)] = {0}, x[13];
    FILE *f = argc == 3 || argc == 4 ? fopen(argv[1], "r") : NULL;
    if (!f) return 2;
    for (size_t i = 0; i < sizeof p / sizeof *p; ++i) if (fscanf(f, "%lf", &p[i]) != 1) return 2;
    for (size_t i = 0; i < sizeof s / sizeof *s; ++i) if (fscanf(f, "%lf", &s[i]) != 1) return 2;
    for (int i = 0; i < 14; ++i) if (fscanf(f, "%lf", &y0[i]) != 1) return 2;
    fclose(f);
    const int steps = atoi(argv[2]), runs = argc == 4 ? atoi(argv[3]) : 7;
    pc_fivebar_context c = {(pc_fivebar_params *)p, (pc_fivebar_settings *)s, NULL, y, NULL, NULL, scratch, 0, 2};
    pc_refusal r;
    double best = 1e300;
    for (int run = 0; run < runs; ++run) {
        for (int i = 0; i < 14; ++i) y[i] = y0[i];
        struct timespec a, b;
        clock_gettime(CLOCK_THREAD_CPUTIME_ID, &a);
        for (int k = 0; k < steps; ++k) {
            const double torque = 0.02 * cos(2.0 * 3.14159265358979323846 * 20.0 * k * 1e-3);
            x[0] = torque;
            x[1] = -torque;
            if (pc_fivebar_plant_io(&c, x, k * 1e-3, 1e-3, &r) != PC_OK) {
                printf("refused: code %d at step %d\n", r.code, k);
                return 1;
            }
        }
        clock_gettime(CLOCK_THREAD_CPUTIME_ID, &b);
        const double us = ((double)(b.tv_sec - a.tv_sec) * 1e9 + (double)(b.tv_nsec - a.tv_nsec)) / 1e3 / steps;
        if (us < best) best = us;
    }
    printf("%.4f\n", best);
    return 0;
}
