/* The sub-step counting rule of sampled components (pc_sampling.h). */
#include "pc_sampling.h"

#include <math.h>

double pc_sampling_substeps(double T, double h)
{
    double n = T / h, whole = nearbyint(n);   /* the default rounding: half to even */
    if (whole >= 1.0 && fabs(n - whole) <= PC_SAMPLING_TOLERANCE * whole) return whole;
    return 0.0;
}

int pc_sampling_changes_period(double substep, double counted, double n)
{
    return substep != 0.0 && n != counted;
}

int pc_sampling_samples(double substep, double sample_phase)
{
    return substep == sample_phase;
}

double pc_sampling_next(double substep, double substeps)
{
    double next = substep + 1.0;
    return next >= substeps ? 0.0 : next;
}
