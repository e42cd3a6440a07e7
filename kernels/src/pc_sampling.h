/* The sub-step counting rule of a sampled component (docs/master.md "Sub-stepping sampled
 * components"), once for every user: the drive's current controller (drive.c), the native
 * FMUs' adapters and, through the kernels' library, fmus/slave/sampling.py.
 *
 * A component sampled at T accepts steps h = T / n (n a whole number, 1e-9 relative).  It
 * counts its steps in the period with a whole-number counter (never fmod of the time, which
 * drifts when a tool accumulates t + h), samples on sub-step `sample_phase` and holds its
 * outputs on the others; n may change only at a period's start.  The counter and n are
 * doubles holding whole numbers, as every kernel's state is.
 */
#ifndef PC_SAMPLING_H
#define PC_SAMPLING_H

/* Relative tolerance of "h divides T": |T / h - n| <= PC_SAMPLING_TOLERANCE n. */
#define PC_SAMPLING_TOLERANCE 1e-9

/* n = T / h when h divides T (a whole number n >= 1, rounded half to even as Python's
 * round), else 0 (h not dividing T, or T, h not finite). */
double pc_sampling_substeps(double T, double h);

/* Whether a step with n = T / h is refused because it changes the step within a period:
 * the next sub-step `substep` is past the period's start and n differs from the `counted` one. */
int pc_sampling_changes_period(double substep, double counted, double n);

/* Whether the step at sub-step `substep` takes the sample (its index is `sample_phase`). */
int pc_sampling_samples(double substep, double sample_phase);

/* The sub-step after `substep` in a period of `substeps` steps (0 after the last). */
double pc_sampling_next(double substep, double substeps);

#endif
