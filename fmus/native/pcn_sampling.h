/* Sub-stepping of the native sampled FMUs (fmus/slave/sampling.py's SampledSteps): the counter in
 * the model data, the step-size rule with the twin's messages, the restored counter's check.
 * The counting rule itself is the kernels' (pc_sampling.h). */
#ifndef PCN_SAMPLING_H
#define PCN_SAMPLING_H

#include "pc_sampling.h"
#include "pcn_model.h"

/* fmus.sampling.accepted_steps_text(). */
#define PCN_SAMPLING_ACCEPTS                                                                                     \
    "h dividing the sample time T (T / h = n a whole number, 1e-9 relative), the same n within a period; it "    \
    "samples on sub-step sample_phase (0 <= sample_phase < n) of each period and holds its outputs in between"

/* The counter, FMU state (the model data's last PCN_SAMPLING_WORDS doubles). */
typedef struct {
    double substep;    /* the next step's index in its period, whole */
    double substeps;   /* n = T / h of the steps counted, whole; 0: none yet */
} pcn_sampling;

#define PCN_SAMPLING_WORDS ((long)(sizeof(pcn_sampling) / sizeof(double)))

/* Whether the step from t samples (SampledSteps.step): on sub-step sample_phase, except the step
 * from the start time when hold_first_step is true.  A macro: the slots are the adapter's. */
#define PCN_SAMPLES(s, in, t)                                                                            \
    (pc_sampling_samples((s)->substep, (in)->integer[PCN_SLOT_sample_phase]) &&                          \
     !((in)->boolean[PCN_SLOT_hold_first_step] && (t) == (in)->start_time))

/* SampledSteps.check_step_size's own rule for a step h at t (the generic one passed): h
 * divides T, 0 <= phase < n, n unchanged within a period.  Accepted: s->substeps = n, 0
 * returned; refused: the twin's message (in's step-size message) in `why`, nonzero, nothing
 * changed. */
int pcn_sampling_check(pcn_sampling *s, const pcn_instance *in, double T, int phase, double t, double h,
                       pcn_text *why);

/* Whether a restored counter is whole numbers with 0 <= substep < substeps (or both 0). */
int pcn_sampling_check_data(const pcn_sampling *s, pcn_text *why);

#endif
