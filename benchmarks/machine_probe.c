/* A fixed CPU workload that touches nothing of ours: 64 doubles turned by sin, each step
 * depending on the last, so its time is the core's speed and nothing else.  Timed before
 * and after every round of a benchmark (benchmarks/machine_probe.py): on a shared host the
 * core's speed changes by 1.5-2x from second to second, and the probe says when. */
#include <math.h>

double machine_probe(int sweeps)
{
    double x[64];
    for (int i = 0; i < 64; ++i) x[i] = 0.1 * i;
    for (int k = 0; k < sweeps; ++k)
        for (int i = 0; i < 64; ++i) x[i] = sin(x[i]) * 1.0001 + 0.3 * x[(i + 7) & 63];
    return x[3];
}
