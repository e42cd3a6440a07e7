/* The position controller's law (thesis 7.21-7.22; seed 001's sliding-mode law), the eight
 * strategies of 7.2.6 and seed 001's two, with the PD, tabulated (7.2.5) and exact (5.74-5.77)
 * models.  Python: controller/law.py (bindings), controller/position.py (PositionController).
 *
 * One sample, period T:
 *   e = r_d - r,  s = ddr_d - ddr + kv de + kp e                 (6.5, 7.22)
 *   k <- |k + gamma sign(s) sign(s_prev)|  if |s| >= phi or the sign changed   (6.66)
 *   I <- I + h k sat(s / phi)                                   (6.65, the integral of 7.21)
 *   u' = H^ (ddr_d + kv de + kp e + I) + h^                       (7.21), kp = lam^2, kv = 2 lam
 * Seed 001 (section 1.2): s = de + lam e, u' = H^ (ddr_d + lam de + k sat(s/phi)) + h^, no integral.
 * r = q (joint space) or x (task space, x = FK(q), kinematics5r.h).  PD: H^ = m* 1, h^ = 0.
 * Model terms are task-space H, h at the measured pose; joint space uses u' = J^T (H (J a +
 * beta) + h).  Torques: joint space u' itself; task space J^T u' (PD, tabulated) or u* solving
 * u' = Z^T u* (5.72) with the exact model's Z (tau2 = -u*_theta21).  Current references tau/kt.
 *
 * Delay compensation (predict = a, b periods of T, the sample's h): the angles were measured a
 * periods and the rates b periods before the commands take effect (a per-component package in
 * a Jacobi master at 1 ms: 2 and 3, docs/ssp.md).  The law predicts the joint state at that
 * time with its own model, r'' = a' (the commanded acceleration, which the model's torques
 * produce when the model is exact), over the commands it has sent since: the rates from b
 * periods back to a, then angles and rates over the a periods, constant acceleration over each
 * period, and acts on the prediction, against the reference at that time (a T on along its
 * given derivatives, x_d + a T dx_d + (a T)^2 ddx_d / 2, dx_d + a T ddx_d).  Less what the
 * plant is taken not to follow: the integral I (the law's estimate of what its model misses)
 * and the rest of the feedback low-passed at lam (a steady feedback balances a disturbance:
 * without this the prediction runs ahead of the plant by the disturbance, and the damping
 * term acts on that, e_ef x1.43 on bench_circle_PDx).  It keeps the last max(a, b) commanded joint accelerations
 * (task space: J^-1 (a' - beta) at the pose it acted on).  ddq is taken as measured.
 *
 * A sample refuses (nothing in the state changes, `pc_refusal` names the quantity): a non-
 * finite input, a reference out of reach or in the near-singular band, a measured pose without
 * assembly, a point off the table or in a cell with a left-out corner, non-finite outputs.
 */
#ifndef PC_LAW_H
#define PC_LAW_H

#include "kinematics5r.h"
#include "pc_common.h"

/* Entries of a table row and of the interpolated terms: H00, H01, H11, cxx (2), cyy (2),
 * cxy (2), g (2): h(x, dx) = cxx dx^2 + cyy dy^2 + cxy dx dy + g (controller/model.py). */
#define PC_LAW_TERMS 11

/* Modes (doubles in the parameters). */
#define PC_LAW_SPACE_Q 0.0
#define PC_LAW_SPACE_X 1.0
#define PC_LAW_MODEL_PD 0.0
#define PC_LAW_MODEL_TABULATED 1.0
#define PC_LAW_MODEL_EXACT 2.0
#define PC_LAW_UNIFIED 0.0
#define PC_LAW_SEED 1.0

/* Most periods of feedback delay the law predicts over (pc_law_params.predict). */
#define PC_LAW_MAX_PREDICT 8

/* Refusal codes; `index` and `value` of each in brackets. */
enum {
    PC_LAW_NONFINITE = 1,          /* [input 0-11, its value] */
    PC_LAW_REF_OUT = 2,            /* reference out of reach [chain 0/1, its base-to-point distance, m] */
    PC_LAW_REF_BAND = 3,           /* reference in the near-singular band [0, margin] */
    PC_LAW_NO_ASSEMBLY = 4,        /* measured pose without assembly [0, elbow distance, m] */
    PC_LAW_MEASURED_SINGULAR = 5,  /* measured pose with det J_X = 0 [0, det] */
    PC_LAW_REF_SINGULAR = 6,       /* J_Theta singular at the reference [0, 0] */
    PC_LAW_TABLE_OUT = 7,          /* measured pose outside the table [0 x / 1 y, its value] */
    PC_LAW_TABLE_HOLE = 8,         /* its cell has a left-out corner [0, x] */
    PC_LAW_EXACT_OUT = 9,          /* the exact model's pose out of a chain's reach [0, distance, m] */
    PC_LAW_NONFINITE_OUTPUT = 10,  /* [output 0-5, its value] */
    PC_LAW_NEEDS_TERMS = 11        /* not a refusal: the exact model's terms are wanted at scratch q, dq */
};

/* Read-only after set-up. */
typedef struct {
    pc_5r_geometry geometry;   /* the model's lengths, m */
    double band;               /* references with a singularity margin below it are refused */
    double space;              /* PC_LAW_SPACE_Q or _X */
    double model;              /* PC_LAW_MODEL_PD, _TABULATED or _EXACT */
    double law;                /* PC_LAW_UNIFIED (7.21-7.22) or PC_LAW_SEED (seed 001) */
    double kp, kv;             /* lam^2, 2 lam (7.29-7.30) */
    double lam;                /* seed 001's s = de + lam e */
    double phi;                /* boundary layer of sat(s / phi) (6.65) */
    double adaptive;           /* 1: the adaptive gain (6.66), 0: constant k */
    double gamma[2];           /* adaptation rates (6.66) */
    double m_star;             /* PD: H^ = m* 1 (kg m^2 or kg) */
    double kt[2];              /* torque constants, N m/A: i_ref = tau / kt */
    double predict[2];         /* delay compensation: periods of delay of the angles and of the rates
                                * (0 0: the law acts on the measurements as they are, see below) */
} pc_law_params;

/* What a sample advances (FMU state). */
typedef struct {
    double integral[2];        /* I of (7.21) */
    double k[2];               /* sliding gains (6.66) */
    double s_prev[2];          /* s of the previous sample */
    double s[2];               /* s of the last sample (7.22) */
    double e[2];               /* e = r_d - r of the last sample (6.5) */
    double past[2 * PC_LAW_MAX_PREDICT];   /* with predict: the joint accelerations (q1, q2) the last
                                            * samples commanded, newest first, rad/s^2 */
    double bias[2];            /* with predict: their feedback part (integral aside), low-passed at lam */
    double offset[2];          /* bias + the integral in joints: what the plant is taken not to follow */
} pc_law_state;

/* The tabulated model (7.2.5): a square grid, row-major (ny + 1) x (nx + 1) rows of
 * PC_LAW_TERMS, NaN at left-out points. */
typedef struct {
    double x0, y0;             /* first grid point, m */
    double inv_step;           /* 1 / grid step, 1/m */
    double nx, ny;             /* cells along x and y */
    double values[];
} pc_law_table;

/* The exact model's terms at the pose (5.74-5.77), the first words of the plant's inverse
 * terms: M_M (2x2), v_M, g_M, Z (2x2, 5.72). */
typedef struct {
    double M[4];
    double v[2];
    double g[2];
    double Z[4];
} pc_law_terms;

typedef struct {
    double q1, q2, dq1, dq2, ddq1, ddq2;          /* measured, rad, rad/s, rad/s^2 (world) */
    double x_d, y_d, dx_d, dy_d, ddx_d, ddy_d;    /* reference, m, m/s, m/s^2 */
} pc_law_inputs;

typedef struct {
    double tau[2];             /* world torques, CCW positive, N m */
    double i_ref[2];           /* tau / kt, A */
    double e[2];               /* errors of the sample */
} pc_law_outputs;

/* Caller-owned working storage; after a refusal it tells where the sample stopped. */
typedef struct {
    pc_law_inputs in;
    pc_law_outputs out;
    pc_5r_task task;           /* the measured task state */
    double angles[4];          /* the reference's world link angles (task space: only if not pc_5r_clear) */
    double r[6];               /* r, dr, ddr (measured) */
    double rd[6];              /* r_d, dr_d, ddr_d */
    double m[PC_LAW_TERMS];    /* the interpolated table row */
    double q[7], dq[7];        /* the thesis' coordinates of the measured pose (exact model) */
    double joint[4];           /* q1, q2, dq1, dq2 the law acts on: measured, or predicted (predict) */
} pc_law_scratch;

/* A terms function: the exact model's terms at the thesis' q, dq (the plant's inverse terms). */
typedef void (*pc_law_terms_fn)(const void *model, const double q[7], const double dq[7], double *terms);

/* The buffers of one controller (pc_law_io's context). */
typedef struct {
    const pc_law_params *params;
    const pc_law_table *table;     /* NULL unless tabulated */
    pc_law_terms *terms;           /* the exact model's terms (the tabulated model's fallback too) */
    pc_law_state *state;
    pc_law_scratch *scratch;
    pc_law_terms_fn terms_of;      /* NULL: PC_LAW_NEEDS_TERMS, the caller computes them */
    const void *model;             /* terms_of's model */
    double *delayed;               /* the computation delay's queue: n_delayed rows of
                                    * (tau1, tau2, i_ref1, i_ref2), oldest first (pc_law_delay) */
    int n_delayed;                 /* 0: the commands apply at once */
} pc_law_context;

/* The table's PC_LAW_TERMS values at (x, y), bilinear in the cell (7.2.5): PC_LAW_TABLE_OUT,
 * PC_LAW_TABLE_HOLE, or PC_OK. */
int pc_law_interpolate(const pc_law_table *table, double x, double y, double out[PC_LAW_TERMS], pc_refusal *r);

/* The checks and kinematics of a sample (scratch->in set): inputs finite, reference in
 * reach and out of the band, the joint state the law acts on (predicted over p->predict with
 * s->past), its task state, r and r_d. */
int pc_law_prepare(const pc_law_params *p, const pc_law_state *s, pc_law_scratch *w, double h, pc_refusal *r);

/* The joint state (q1, q2, dq1, dq2) at the commands' time from angles measured a periods and
 * rates b periods before it, with `past` the joint accelerations commanded over the last
 * max(a, b) periods, newest first (constant over each period of length h). */
void pc_law_predict(const double measured[4], const double *past, const double bias[2], int a, int b, double h,
                    double joint[4]);

/* The thesis' q, dq of the prepared measured pose into scratch (the exact model's point). */
int pc_law_exact_pose(const pc_law_params *p, pc_law_scratch *w, pc_refusal *r);

/* The law on a prepared sample: model terms (the table's, or `terms` when given), gains,
 * integral, torques into scratch->out; the state changes only when it returns PC_OK. */
int pc_law_finish(const pc_law_params *p, const pc_law_table *table, const pc_law_terms *terms,
                  pc_law_state *s, pc_law_scratch *w, double h, pc_refusal *r);

/* One sample from scratch->in, outputs into scratch->out (PC_LAW_NEEDS_TERMS: the exact model
 * without terms_of; the caller computes the terms at scratch->q, dq and resumes). */
int pc_law_run(const pc_law_context *c, double h, pc_refusal *r);

/* The rest of a sample whose exact-model terms the caller put in c->terms (after
 * PC_LAW_NEEDS_TERMS, or after a table refusal: the exact model off the table). */
int pc_law_resume(const pc_law_context *c, double h, pc_refusal *r);

/* The computation delay (the FMU's delay_steps = n > 0): `commands` (tau1, tau2, i_ref1, i_ref2)
 * take the oldest row of `delayed` (n rows of 4, oldest first) and join the queue as its newest. */
void pc_law_delay(double *delayed, int n, double commands[4]);

/* The compiled loop's I/O (pc_io_fn): x = the 12 inputs of pc_law_inputs, then the 6 outputs
 * (the commands through the context's delay queue). */
int pc_law_io(void *context, double *x, double t, double h, pc_refusal *r);

#endif
