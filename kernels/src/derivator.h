/* The derivator (thesis 7.2.3): velocity and acceleration estimates of sampled angles.
 *
 * controller/derivators.py designs the chain with scipy: the backward difference (7.19), the
 * Bessel low-pass F_v, the backward difference again, the Bessel low-pass F_a, each low-pass as
 * second-order sections [b0 b1 b2 1 a1 a2].  Every sample runs that cascade on each channel c:
 *
 *     y = rate (u - p),  p' = u                               (a difference, rate = 1/T)
 *     y = b0 u + s0,  s0' = (b1 u + s1) - a1 y,  s1' = b2 u - a2 y   (a section, direct form II
 *                                                                     transposed)
 *
 * the velocity the output of F_v, the acceleration that of F_a.  The state of a channel, n = 2 +
 * 2 S words (S sections in all), in the chain's order: p of the first difference, s0 s1 of each
 * of F_v's S_v sections, p of the second difference, s0 s1 of each of F_a's S - S_v sections.
 * At rest at q: p = q for the first difference, every other word 0.
 *
 * One buffer of doubles holds the sizes, the design and the run state: pc_derivator, whose
 * flexible array `data` holds, in this order,
 *   rate, 1/T;
 *   the sections, S rows of 5: b0 b1 b2 a1 a2 (F_v's, then F_a's);
 *   the state with the newest input, (n + 1) rows of m: row j < n is state word j of every
 *   channel, row n the last angles.
 * The sizes are read from the buffer: every entry point checks them against the buffer's
 * length and refuses (PC_DERIVATOR_BAD_LAYOUT) a buffer they do not fit, so a forged FMU
 * state cannot make a step read or write outside it.
 */
#ifndef PC_DERIVATOR_H
#define PC_DERIVATOR_H

#include "pc_common.h"

/* Refusal codes; pc_refusal.index: the channel (BAD_INPUT, NONFINITE_OUTPUT: the first
 * non-finite estimate, velocities 0..m-1 then accelerations m..2m-1) or the size word
 * (BAD_LAYOUT: 0 states, 1 channels, 2 the buffer's length, 3 the scratch's length, 4 the
 * velocity sections). */
#define PC_DERIVATOR_BAD_INPUT 1        /* an angle not finite or beyond the limit */
#define PC_DERIVATOR_NONFINITE_OUTPUT 2 /* an estimate came out non-finite: the state not advanced */
#define PC_DERIVATOR_BAD_LAYOUT 3       /* sizes that do not fit the buffer */

/* Largest number of filter states and of channels a buffer may declare. */
#define PC_DERIVATOR_MAX_STATES 64
#define PC_DERIVATOR_MAX_CHANNELS 64

typedef struct {
    double states;            /* n = 2 + 2 S: state words of one channel (difference, F_v, difference, F_a) */
    double channels;          /* m: angles filtered side by side */
    double started;           /* 1.0 once at rest at some angles (run state); 0.0: at the first sample's */
    double velocity_sections; /* S_v: F_v's sections, the first S_v of the S */
    double data[];            /* rate, sections, state (see above) */
} pc_derivator;

extern const pc_field pc_derivator_fields[];

/* The buffers of one derivator, for its step and the compiled loop (pc_io_fn). */
typedef struct {
    pc_derivator *derivator; /* the buffer */
    double *scratch;         /* n m doubles: the next state before it replaces the state (over two channels) */
    long words;              /* doubles in the buffer */
    long scratch_words;      /* doubles in scratch */
    double limit;            /* pc_derivator_io: largest |q| accepted [rad] */
} pc_derivator_context;

/* The doubles a buffer of n states (even, >= 2) and m channels takes. */
long pc_derivator_words(long states, long channels);

/* The scratch a buffer of `words` doubles needs, n m; 0 when its sizes do not fit it. */
long pc_derivator_scratch_words(const pc_derivator *d, long words);

/* At rest at the angles q0[m]: both estimates zero from the next sample on. */
int pc_derivator_reset(const pc_derivator_context *c, const double *q0, pc_refusal *r);

/* Take the angles q[m] of a sample; out[2 m]: velocities (rad/s) then accelerations
 * (rad/s^2).  Not started: first at rest at q.  Refused: BAD_INPUT (nothing changed, out
 * untouched), NONFINITE_OUTPUT (out written, the state and `started` unchanged), BAD_LAYOUT. */
int pc_derivator_step(const pc_derivator_context *c, const double *q, double limit, double *out,
                      pc_refusal *r);

/* Compiled loop: x = [q1, q2 | dq1, dq2, ddq1, ddq2], |q| <= c->limit (two channels). */
int pc_derivator_io(void *context, double *x, double t, double h, pc_refusal *r);

#endif
