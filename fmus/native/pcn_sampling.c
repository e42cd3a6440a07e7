/* Sub-stepping of the native sampled FMUs (pcn_sampling.h), worded as fmus/slave/sampling.py. */
#include "pcn_sampling.h"

#include <math.h>
#include <stdio.h>

#include "pcn_model.h"

/* A whole number held in a double, as Python prints the int (n can pass INT_MAX). */
static const char *whole(double x, char *out, size_t size)
{
    snprintf(out, size, "%.0f", x);
    return out;
}

int pcn_sampling_check(pcn_sampling *s, const pcn_instance *in, double T, int phase, double t, double h,
                       pcn_text *why)
{
    char n_text[32], substep_text[32], counted_text[32];
    double n = pc_sampling_substeps(T, h);
    if (n == 0.0) {
        pcn_text because;
        pcn_clear(&because);
        pcn_addf(&because, "does not divide the sample time T = %r s", T);
        pcn_step_size_message(in, why, t, h, because.text);
        return 1;
    }
    if (!(phase >= 0 && phase < n))
        return pcn_addf(pcn_timed(why), "parameter sample_phase = %d must be a whole number in [0, T / h) = [0, %s) "
                        "for the step size h = %r s at t = %r s (T = %r s)", phase, whole(n, n_text, sizeof n_text), h,
                        t, T), 1;
    if (pc_sampling_changes_period(s->substep, s->substeps, n))
        return pcn_addf(pcn_timed(why), "step size h = %r s at t = %r s changes the step within a sample period (T = "
                        "%r s, sub-step %s of %s, steps of %r s): %s accepts a new step size only at a period's start",
                        h, t, T, whole(s->substep, substep_text, sizeof substep_text), whole(s->substeps, counted_text,
                        sizeof counted_text), T / s->substeps, pcn_this_model.identifier), 1;
    s->substeps = n;
    return 0;
}

int pcn_sampling_check_data(const pcn_sampling *s, pcn_text *why)
{
    double k = s->substep, n = s->substeps;
    int counted = n == floor(n) && n >= 1.0 && k == floor(k) && k >= 0.0 && k < n;
    if (counted || (n == 0.0 && k == 0.0)) return 0;
    pcn_addf(why, "the sub-step counter (sub-step %r of %r) is not a whole number in [0, n)", k, n);
    return 1;
}
