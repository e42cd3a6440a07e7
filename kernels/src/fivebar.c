/* The 5R and the actuated 5R (fivebar.h): chain terms, forward dynamics (5.66), RK4, the
 * report of a state, projection, residual, inverse dynamics terms, the compiled loop's I/O.
 *
 * Forward dynamics: the z rows of (7.7) decouple (z'' = -2 lambda z' - lambda^2 z), leaving
 * A Q° = blockdiag(-E_k J_v,k), invertible away from serial singularities, so
 * C = [1; (E_1 J_1)^-1; (E_2 J_2)^-1] (5.56).  (5.66) is solved by eliminating the constraint
 * rows: the Baumgarte rows give theta'' = C x'' + e, the projected dynamics a 2x2 system
 * C^T M' C x'' = C^T (u' - v' - g' - M' e).
 */
#include "fivebar.h"

#include "pc_motor.h"
#include "pc_rk4.h"
#include "pc_trig.h"

#define N_Q 7
#define PI 3.14159265358979323846
#define N_Y 14

/* The RK4 evaluation's helpers inlined whole, so their chains of operations interleave. */
#define INLINE static inline __attribute__((always_inline))

/* Two doubles, chain 1 in lane 0 and chain 2 in lane 1 (or a chain's two angles): GCC's and
 * clang's vector extension (one SSE2 register on x86-64), each lane's operation the scalar one, so
 * the same bits as computing the lanes one by one; the two chains' terms cost one chain's. */
#if !defined(__GNUC__)
#error "fivebar.c computes the two chains in the lanes of GCC's or clang's vector extension"
#endif
typedef double lanes __attribute__((vector_size(16)));

const pc_field pc_fivebar_params_fields[] = {
    PC_FIELD(pc_fivebar_params, l0), PC_FIELD(pc_fivebar_params, m0), PC_FIELD(pc_fivebar_params, gravity),
    /* chain[2], each pc_fivebar_chain_fields (PC_FIELD's count is for arrays of doubles) */
    {"chain", (int)(offsetof(pc_fivebar_params, chain) / sizeof(double)),
     (int)(2 * (sizeof(pc_fivebar_chain) / sizeof(double)))},
    {0, 0, 0}};
const pc_field pc_fivebar_chain_fields[] = {
    PC_FIELD(pc_fivebar_chain, l1), PC_FIELD(pc_fivebar_chain, l2), PC_FIELD(pc_fivebar_chain, lg1),
    PC_FIELD(pc_fivebar_chain, lg2), PC_FIELD(pc_fivebar_chain, m1), PC_FIELD(pc_fivebar_chain, m2),
    PC_FIELD(pc_fivebar_chain, Jz1), PC_FIELD(pc_fivebar_chain, Jz2), PC_FIELD(pc_fivebar_chain, J_rotor),
    {0, 0, 0}};
const pc_field pc_fivebar_motor_fields[] = {
    PC_FIELD(pc_fivebar_motor, joint), PC_FIELD(pc_fivebar_motor, R), PC_FIELD(pc_fivebar_motor, L),
    PC_FIELD(pc_fivebar_motor, kt), PC_FIELD(pc_fivebar_motor, ke), PC_FIELD(pc_fivebar_motor, b),
    PC_FIELD(pc_fivebar_motor, mu), PC_FIELD(pc_fivebar_motor, omega_eps), {0, 0, 0}};
const pc_field pc_fivebar_settings_fields[] = {
    PC_FIELD(pc_fivebar_settings, lambda), PC_FIELD(pc_fivebar_settings, substeps),
    PC_FIELD(pc_fivebar_settings, count), PC_FIELD(pc_fivebar_settings, residual_stop),
    PC_FIELD(pc_fivebar_settings, singular_stop), PC_FIELD(pc_fivebar_settings, offset), {0, 0, 0}};
const pc_field pc_fivebar_state_fields[] = {
    PC_FIELD(pc_fivebar_state, q), PC_FIELD(pc_fivebar_state, dq),
    {"current", (int)(offsetof(pc_fivebar_state, current) / sizeof(double)), 0}, {0, 0, 0}};
const pc_field pc_fivebar_terms_fields[] = {
    PC_FIELD(pc_fivebar_terms, tip), PC_FIELD(pc_fivebar_terms, J), PC_FIELD(pc_fivebar_terms, a_bias),
    PC_FIELD(pc_fivebar_terms, M), PC_FIELD(pc_fivebar_terms, v), PC_FIELD(pc_fivebar_terms, g), {0, 0, 0}};
const pc_field pc_fivebar_report_fields[] = {
    PC_FIELD(pc_fivebar_report, finite), PC_FIELD(pc_fivebar_report, residual),
    PC_FIELD(pc_fivebar_report, measures), PC_FIELD(pc_fivebar_report, q1), PC_FIELD(pc_fivebar_report, q2),
    PC_FIELD(pc_fivebar_report, dq1), PC_FIELD(pc_fivebar_report, dq2), PC_FIELD(pc_fivebar_report, x),
    PC_FIELD(pc_fivebar_report, y), PC_FIELD(pc_fivebar_report, dx), PC_FIELD(pc_fivebar_report, dy),
    PC_FIELD(pc_fivebar_report, q1_enc), PC_FIELD(pc_fivebar_report, q2_enc), {0, 0, 0}};
const pc_field pc_fivebar_inverse_fields[] = {
    PC_FIELD(pc_fivebar_inverse, M), PC_FIELD(pc_fivebar_inverse, v), PC_FIELD(pc_fivebar_inverse, g),
    PC_FIELD(pc_fivebar_inverse, Z), PC_FIELD(pc_fivebar_inverse, c), {0, 0, 0}};

int pc_fivebar_context_size(void)
{
    return (int)sizeof(pc_fivebar_context);
}

int pc_fivebar_scratch_words(int n)
{
    return PC_FIVEBAR_SCRATCH(n);
}

/* s_k of E_k (7.3-7.4) and the chain's base x (7.8). */
static double chain_sign(int k)
{
    return k == 0 ? 1.0 : -1.0;
}

static double chain_base(const pc_fivebar_params *p, int k)
{
    return k == 0 ? p->l0 : -p->l0;
}

/* sin and cos of a chain's angles: theta_k1 = a, theta_k1 + theta_k2 = a + b, theta_k2 = b. */
typedef struct {
    double s1, c1, s12, c12, sb, cb;
} chain_trig;

INLINE void chain_trig_of(double a, double b, chain_trig *g)
{
    pc_sincos(a, &g->s1, &g->c1);
    pc_sincos(b, &g->sb, &g->cb);
    g->s12 = g->s1 * g->cb + g->c1 * g->sb;   /* the angle sum's: two sin/cos pairs instead of three */
    g->c12 = g->c1 * g->cb - g->s1 * g->sb;
}

/* Both chains' sines and cosines (chain_trig's), chain k in lane k. */
typedef struct {
    lanes s1, c1, s12, c12, sb, cb;
} trig_lanes;

static trig_lanes both_trig(const chain_trig *g0, const chain_trig *g1)
{
    return (trig_lanes){{g0->s1, g1->s1}, {g0->c1, g1->c1}, {g0->s12, g1->s12},
                        {g0->c12, g1->c12}, {g0->sb, g1->sb}, {g0->cb, g1->cb}};
}

/* pc_fivebar_terms of both chains, chain k in lane k. */
typedef struct {
    lanes tip[2], J[4], a_bias[2], M[4], v[2], g[2];
} terms_lanes;

/* A field of both chains' parameters, chain 1 in lane 0. */
#define BOTH(p, f) ((lanes){(p)->chain[0].f, (p)->chain[1].f})

/* pc_fivebar_chain_terms of both chains from their trigonometry g and joint rates (da, db). */
INLINE void chain_terms_of(const pc_fivebar_params *p, const trig_lanes *g, lanes da, lanes db, terms_lanes *t)
{
    const lanes s = {chain_sign(0), chain_sign(1)};
    const lanes l1 = BOTH(p, l1), l2 = BOTH(p, l2), lg1 = BOTH(p, lg1), lg2 = BOTH(p, lg2);
    const lanes m1 = BOTH(p, m1), m2 = BOTH(p, m2);
    const lanes c1 = g->c1, s1 = g->s1, c12 = g->c12, s12 = g->s12, cb = g->cb, sb = g->sb;
    const lanes w1 = da, w12 = da + db;
    /* Tip (4.4) and J_v (4.13) in the chain frame; only the x, y rows are non-zero. */
    t->tip[0] = s * (l1 * c1 + l2 * c12);
    t->tip[1] = l1 * s1 + l2 * s12;
    t->J[0] = s * (-l1 * s1 - l2 * s12);
    t->J[1] = s * (-l2 * s12);
    t->J[2] = l1 * c1 + l2 * c12;
    t->J[3] = l2 * c12;
    /* Velocity-quadratic tip acceleration (4.57-4.58): centripetal terms. */
    t->a_bias[0] = s * (-l1 * c1 * w1 * w1 - l2 * c12 * w12 * w12);
    t->a_bias[1] = -l1 * s1 * w1 * w1 - l2 * s12 * w12 * w12;
    /* (4.85) with the rotor of (4.139) on joint 1. */
    const lanes h = m2 * l1 * lg2;
    const lanes m22 = m2 * lg2 * lg2 + BOTH(p, Jz2);
    t->M[0] = m1 * lg1 * lg1 + BOTH(p, Jz1) + m2 * l1 * l1 + m22 + 2.0 * h * cb + BOTH(p, J_rotor);
    t->M[1] = m22 + h * cb;
    t->M[2] = t->M[1];
    t->M[3] = m22;
    /* (4.86): Coriolis and centripetal efforts. */
    t->v[0] = -h * sb * (2.0 * da * db + db * db);
    t->v[1] = h * sb * da * da;
    /* (4.87) with gravity in the chain frame, E_k^T g; none without gravity. */
    if (p->gravity[0] == 0.0 && p->gravity[1] == 0.0) {
        t->g[0] = t->g[1] = (lanes){0.0, 0.0};
        return;
    }
    const lanes gx = s * p->gravity[0], gy = {p->gravity[1], p->gravity[1]};
    const lanes gc1x = lg1 * -s1, gc1y = lg1 * c1;
    const lanes g2ax = -l1 * s1 - lg2 * s12, g2ay = l1 * c1 + lg2 * c12;
    const lanes g2bx = -lg2 * s12, g2by = lg2 * c12;
    t->g[0] = -(m1 * (gc1x * gx + gc1y * gy) + m2 * (g2ax * gx + g2ay * gy));
    t->g[1] = -(m2 * (g2bx * gx + g2by * gy));
}

/* Chain k at joint angles (a, b) and rates (da, db): tip, J_v, tip bias, M, v, g, the tip rows
 * world-aligned (E_k applied) and gravity written in the chain frame (E_k^T g). */
void pc_fivebar_chain_terms(const pc_fivebar_params *p, int k, double a, double b, double da, double db,
                            pc_fivebar_terms *t)
{
    chain_trig g;
    chain_trig_of(a, b, &g);
    const trig_lanes gl = both_trig(&g, &g);   /* (a, b) in both lanes: lane k is chain k's */
    terms_lanes tl;
    chain_terms_of(p, &gl, (lanes){da, da}, (lanes){db, db}, &tl);
    for (int i = 0; i < 2; ++i) {
        t->tip[i] = tl.tip[i][k];
        t->a_bias[i] = tl.a_bias[i][k];
        t->v[i] = tl.v[i][k];
        t->g[i] = tl.g[i][k];
    }
    for (int i = 0; i < 4; ++i) {
        t->J[i] = tl.J[i][k];
        t->M[i] = tl.M[i][k];
    }
}

/* The trigonometry of a state's chains kept in a step's scratch (PC_FIVEBAR_TRIG_WORDS after
 * the RK4 work): [mark, theta11, theta12, theta21, theta22, chain_trig of chain 1, of chain 2].
 * pc_fivebar_step's report writes it for the trial state; the next step, which starts from that
 * state once it is taken, reads it in its first evaluation instead of computing the six sin/cos
 * pairs again.  Read only when marked and its angles are the state's bit for bit (a restored
 * state, a refused step, another plant sharing the scratch: computed afresh), so the results
 * are the same bits either way. */
#define TRIG_MARK 0x1.5ca1ab1e5eedp-3

/* x is k bit for bit (== alone takes -0 for +0, whose sines differ). */
static int same_bits(double x, double k)
{
    return x == k && signbit(x) == signbit(k);
}

/* Largest angle an RK4 stage's trigonometry is turned by from the step's start, rad (2^-5). */
#define TURN_MAX 0x1p-5

/* sin and cos of x + d from those of x (s, c) and |d| <= TURN_MAX, two angles in the lanes: sin d
 * and cos d by their Taylor series (through d^7 and d^8, the first left out below 3e-18 of the kept
 * at 2^-5), then the angle sum. */
INLINE void turned(lanes s, lanes c, lanes d, lanes *sin_xd, lanes *cos_xd)
{
    const lanes z = d * d;
    const lanes sd = d + d * z * (-1.0 / 6.0 + z * (8.333333333333333e-03 + z * -1.984126984126984e-04));
    const lanes cd = 1.0 - z * (0.5 - z * (0.041666666666666664 + z * (-0.001388888888888889 +
                                                                      z * 2.48015873015873e-05)));
    *sin_xd = s * cd + c * sd;
    *cos_xd = c * cd - s * sd;
}

/* Chain k's trigonometry at angles (a, b): from the cache when it holds them, turned from the
 * cache's when `turn` and both are within TURN_MAX of its (an RK4 stage from the step's start),
 * else computed. */
INLINE void trig_at(const double *cache, int k, double a, double b, int turn, chain_trig *g)
{
    if (cache && cache[0] == TRIG_MARK) {
        const double *v = cache + 5 + 6 * k;
        if (same_bits(a, cache[1 + 2 * k]) && same_bits(b, cache[2 + 2 * k])) {
            *g = (chain_trig){v[0], v[1], v[2], v[3], v[4], v[5]};
            return;
        }
        const double da = a - cache[1 + 2 * k], db = b - cache[2 + 2 * k];
        if (turn && fabs(da) <= TURN_MAX && fabs(db) <= TURN_MAX) {
            lanes sn, cs;   /* theta_k1 in lane 0, theta_k2 in lane 1 */
            turned((lanes){v[0], v[4]}, (lanes){v[1], v[5]}, (lanes){da, db}, &sn, &cs);
            g->s1 = sn[0];
            g->c1 = cs[0];
            g->sb = sn[1];
            g->cb = cs[1];
            g->s12 = g->s1 * g->cb + g->c1 * g->sb;
            g->c12 = g->c1 * g->cb - g->s1 * g->sb;
            return;
        }
    }
    chain_trig_of(a, b, g);
}

/* Both chains' trigonometry at y's angles, chain k in lane k: trig_at's, the turning done for
 * both chains at once when both take it (an RK4 stage: neither chain at the cache's angles, each
 * within TURN_MAX of them; theta_k1 and theta_k2 in turned's lanes otherwise). */
INLINE void trig_lanes_at(const double *cache, const double *y, trig_lanes *g)
{
    int both = cache && cache[0] == TRIG_MARK;
    for (int k = 0; k < 2 && both; ++k) {
        const double a = y[3 + 2 * k], b = y[4 + 2 * k], a0 = cache[1 + 2 * k], b0 = cache[2 + 2 * k];
        both = !(same_bits(a, a0) && same_bits(b, b0)) && fabs(a - a0) <= TURN_MAX && fabs(b - b0) <= TURN_MAX;
    }
    if (!both) {
        chain_trig g0, g1;
        trig_at(cache, 0, y[3], y[4], 1, &g0);
        trig_at(cache, 1, y[5], y[6], 1, &g1);
        *g = both_trig(&g0, &g1);
        return;
    }
    const double *v = cache + 5, *w = cache + 11;
    const lanes da = {y[3] - cache[1], y[5] - cache[3]}, db = {y[4] - cache[2], y[6] - cache[4]};
    turned((lanes){v[0], w[0]}, (lanes){v[1], w[1]}, da, &g->s1, &g->c1);
    turned((lanes){v[4], w[4]}, (lanes){v[5], w[5]}, db, &g->sb, &g->cb);
    g->s12 = g->s1 * g->cb + g->c1 * g->sb;   /* chain_trig_of's angle sums */
    g->c12 = g->c1 * g->cb - g->s1 * g->sb;
}

/* Keep chain k's trigonometry g at (a, b) in the cache (mark it once both chains are in). */
static void keep_trig(double *cache, int k, double a, double b, const chain_trig *g)
{
    double *v = cache + 5 + 6 * k;
    cache[1 + 2 * k] = a;
    cache[2 + 2 * k] = b;
    v[0] = g->s1;
    v[1] = g->c1;
    v[2] = g->s12;
    v[3] = g->c12;
    v[4] = g->sb;
    v[5] = g->cb;
}

/* The inverse of the 2x2 row-major m into inv. */
INLINE void inverse2(const double *m, double *inv)
{
    const double det = m[0] * m[3] - m[1] * m[2];
    inv[0] = m[3] / det;
    inv[1] = -m[1] / det;
    inv[2] = -m[2] / det;
    inv[3] = m[0] / det;
}

/* Chain k's terms at y's angles with its joints at rest (the projection reads the tip and J only). */
static void terms_at(const pc_fivebar_params *p, int k, const double *y, pc_fivebar_terms *t)
{
    pc_fivebar_chain_terms(p, k, y[3 + 2 * k], y[4 + 2 * k], 0.0, 0.0, t);
}

/* pc_fivebar_derivative, the chains' trigonometry from `cache` when it holds y's angles (NULL: none);
 * chain k's rows in lane k. */
static void derivative_of(const pc_fivebar_params *p, const double *y, double u1, double u2, double lambda,
                          const double *cache, double *dydt)
{
    trig_lanes g;
    trig_lanes_at(cache, y, &g);
    const lanes da = {y[10], y[12]}, db = {y[11], y[13]};
    terms_lanes t;
    chain_terms_of(p, &g, da, db, &t);
    const lanes base = {chain_base(p, 0), chain_base(p, 1)};
    const lanes rx = y[0] - base - t.tip[0], ry = y[1] - t.tip[1];   /* residual (5.18) */
    const lanes vrx = y[7] - (t.J[0] * da + t.J[1] * db);             /* A dq */
    const lanes vry = y[8] - (t.J[2] * da + t.J[3] * db);
    /* A q'' + b + 2 lam A dq + lam^2 res = 0, A = [1, -E J], b = -E a_bias:
     * E J theta'' = x'' - E a_bias + 2 lam (A dq) + lam^2 res. */
    const lanes wx = -t.a_bias[0] + 2.0 * lambda * vrx + lambda * lambda * rx;
    const lanes wy = -t.a_bias[1] + 2.0 * lambda * vry + lambda * lambda * ry;
    /* Cinv_k = (E_k J_v,k)^-1 = adj / det, det E J = s l1 l2 sin theta_k2 (4.13). */
    const lanes id = (lanes){chain_sign(0), chain_sign(1)} / (BOTH(p, l1) * BOTH(p, l2) * g.sb);
    const lanes c0 = t.J[3] * id, c1 = -t.J[1] * id, c2 = -t.J[2] * id, c3 = t.J[0] * id;
    const lanes e0 = c0 * wx + c1 * wy, e1 = c2 * wx + c3 * wy;   /* theta_k'' at x'' = 0 */
    /* Projected dynamics: (C^T M' C) x'' = C^T (u' - v' - g' - M' e), the chains' terms summed
     * chain 1 first. */
    const lanes *M = t.M;
    const lanes f0 = (lanes){u1, u2} - t.v[0] - t.g[0] - (M[0] * e0 + M[1] * e1);
    const lanes f1 = -t.v[1] - t.g[1] - (M[2] * e0 + M[3] * e1);
    const lanes mc00 = M[0] * c0 + M[1] * c2, mc01 = M[0] * c1 + M[1] * c3;
    const lanes mc10 = M[2] * c0 + M[3] * c2, mc11 = M[2] * c1 + M[3] * c3;
    const lanes A00 = c0 * mc00 + c2 * mc10, A01 = c0 * mc01 + c2 * mc11, A11 = c1 * mc01 + c3 * mc11;
    const lanes R0 = c0 * f0 + c2 * f1, R1 = c1 * f0 + c3 * f1;
    const double a00 = (p->m0 + A00[0]) + A00[1], a01 = (0.0 + A01[0]) + A01[1];
    const double a11 = (p->m0 + A11[0]) + A11[1];
    /* -g' of the platform (5.9) */
    const double r0 = (p->m0 * p->gravity[0] + R0[0]) + R0[1], r1 = (p->m0 * p->gravity[1] + R1[0]) + R1[1];
    const double det = a00 * a11 - a01 * a01;
    const double inv = 1.0 / det;
    const double ddx = (a11 * r0 - a01 * r1) * inv;
    const double ddy = (a00 * r1 - a01 * r0) * inv;
    for (int i = 0; i < N_Q; ++i) dydt[i] = y[N_Q + i];
    dydt[7] = ddx;
    dydt[8] = ddy;
    dydt[9] = -2.0 * lambda * y[9] - lambda * lambda * y[2];
    const lanes dd1 = c0 * ddx + c1 * ddy + e0, dd2 = c2 * ddx + c3 * ddy + e1;
    dydt[10] = dd1[0];
    dydt[11] = dd2[0];
    dydt[12] = dd1[1];
    dydt[13] = dd2[1];
}

/* dy/dt for y = [q, dq] with u* = (u1, u2) on theta11, theta21 (5.66). */
void pc_fivebar_derivative(const pc_fivebar_params *p, const double *y, double u1, double u2, double lambda,
                           double *dydt)
{
    derivative_of(p, y, u1, u2, lambda, NULL, dydt);
}

/* The world speed of motor m's joint (plant.fivebar.world_rates). */
static double motor_speed(const pc_fivebar_motor *m, const double *z)
{
    return m->joint == 0.0 ? z[10] : -z[12];
}

/* pc_fivebar_actuated_derivative with the trigonometry cache of derivative_of (NULL: none). */
static void actuated_derivative_of(const pc_fivebar_held *m, const double *cache, const double *z, double *dzdt)
{
    double u1 = m->u1, u2 = m->u2;
    for (int n = 0; n < m->n_motors; ++n) {
        const pc_fivebar_motor *r = &m->motors[n];
        const double omega = motor_speed(r, z), i = z[N_Y + n];
        const double tau = pc_shaft_torque(r->kt, r->b, r->mu, r->omega_eps, i, omega);
        if (r->joint == 0.0)
            u1 += tau;
        else
            u2 -= tau;
        dzdt[N_Y + n] = pc_armature_rate(r->R, r->L, r->ke, m->voltages[n], i, omega);
    }
    derivative_of(m->params, z, u1, u2, m->lambda, cache, dzdt);
}

/* dz/dt for z = [q, dq, i_1 .. i_n]: the plant (5.66) with each motor's shaft torque (B.2) added
 * to the held efforts on its joint (world -> thesis sign on chain 2), and the armature
 * circuits (4.162).  `held` is a pc_fivebar_held (the signature of pc_rk4's derivative). */
void pc_fivebar_actuated_derivative(const void *held, const double *z, double *dzdt)
{
    actuated_derivative_of(held, NULL, z, dzdt);
}

/* What pc_fivebar_step's RK4 holds: the held inputs and the trigonometry cache. */
typedef struct {
    const pc_fivebar_held *held;
    const double *cache;
} cached_model;

static void cached_derivative(const void *model, const double *z, double *dzdt)
{
    const cached_model *m = model;
    actuated_derivative_of(m->held, m->cache, z, dzdt);
}

/* RK4 of the actuated derivative over dt, `substeps` steps, z (n words) in place, each stage's
 * trigonometry turned from z's at the start (z's own from `cache` when it holds them, or NULL);
 * work: 5 n doubles.  pc_fivebar_step and pc_fivebar_advance both integrate through here, so a
 * step and an advance of the same state give the same bits. */
static void advance_turned(const pc_fivebar_held *held, const double *cache, double *z, int n, double dt,
                           int substeps, double *work)
{
    double start[PC_FIVEBAR_TRIG_WORDS];
    for (int k = 0; k < 2; ++k) {
        chain_trig g;
        trig_at(cache, k, z[3 + 2 * k], z[4 + 2 * k], 0, &g);   /* the cache's if it holds z's angles */
        keep_trig(start, k, z[3 + 2 * k], z[4 + 2 * k], &g);
    }
    start[0] = TRIG_MARK;
    const cached_model model = {held, start};
    pc_rk4(cached_derivative, &model, z, n, dt, substeps, work);
}

/* RK4 of the actuated derivative over dt, `substeps` steps, z in place; work: 5 (14 + n) doubles. */
void pc_fivebar_advance(const pc_fivebar_held *held, double *z, double dt, int substeps, double *work)
{
    advance_turned(held, NULL, z, N_Y + held->n_motors, dt, substeps, work);
}

/* Chain k's rows of the position constraint residual (5.18, 7.7) at y, from the sines and
 * cosines of theta_k1 and theta_k1 + theta_k2 (chain_trig_of's): its tip is that of
 * pc_fivebar_chain_terms (the same expressions, so the same bits). */
static void residual_rows(const pc_fivebar_params *p, int k, const double *y, double c1, double s1, double c12,
                          double s12, double *out)
{
    const pc_fivebar_chain *c = &p->chain[k];
    out[0] = y[0] - chain_base(p, k) - chain_sign(k) * (c->l1 * c1 + c->l2 * c12);
    out[1] = y[1] - (c->l1 * s1 + c->l2 * s12);
    out[2] = y[2];
}

/* The position constraint residual q̄ (5.18, 7.7): 6 entries. */
void pc_fivebar_residual(const pc_fivebar_params *p, const double *y, double *out)
{
    for (int k = 0; k < 2; ++k) {
        chain_trig g;
        chain_trig_of(y[3 + 2 * k], y[4 + 2 * k], &g);
        residual_rows(p, k, y, g.c1, g.s1, g.c12, g.s12, out + 3 * k);
    }
}

/* The encoder's reading of q with zero error `offset`, quantised to `count`. */
static double encoder(double q, double offset, double count)
{
    return count * pc_floor((q + offset) / count + 0.5);
}

/* pc_fivebar_report_of; the chains' trigonometry kept in `cache` (NULL: not kept). */
static void report_of(const pc_fivebar_params *p, const pc_fivebar_settings *s, const double *y,
                      pc_fivebar_report *out, double *cache)
{
    int finite = 1;
    for (int i = 0; i < N_Y; ++i) finite = finite && isfinite(y[i]);
    out->finite = finite ? 1.0 : 0.0;
    double res[6], sum = 0.0;
    chain_trig g[2];
    for (int k = 0; k < 2; ++k) {
        chain_trig_of(y[3 + 2 * k], y[4 + 2 * k], &g[k]);
        residual_rows(p, k, y, g[k].c1, g[k].s1, g[k].c12, g[k].s12, res + 3 * k);
        if (cache) keep_trig(cache, k, y[3 + 2 * k], y[4 + 2 * k], &g[k]);
    }
    if (cache) cache[0] = TRIG_MARK;
    for (int i = 0; i < 6; ++i) sum += res[i] * res[i];
    out->residual = sqrt(sum);
    out->measures[0] = g[0].sb;   /* sin theta12 */
    out->measures[1] = g[1].sb;   /* sin theta22 */
    /* sin(phi12 - phi22) = sin(theta11 + theta12 - (pi - (theta21 + theta22))) = -sin(sum of both) */
    out->measures[2] = -(g[0].s12 * g[1].c12 + g[0].c12 * g[1].s12);
    out->q1 = y[3];
    out->q2 = PI - y[5];
    out->dq1 = y[10];
    out->dq2 = -y[12];
    out->x = y[0];
    out->y = y[1];
    out->dx = y[7];
    out->dy = y[8];
    out->q1_enc = encoder(out->q1, s->offset[0], s->count);
    out->q2_enc = encoder(out->q2, s->offset[1], s->count);
}

/* What PlantSimulator checks and publishes for the plant state y (14 entries). */
void pc_fivebar_report_of(const pc_fivebar_params *p, const pc_fivebar_settings *s, const double *y,
                          pc_fivebar_report *out)
{
    report_of(p, s, y, out, NULL);
}

/* The verdict on a trial state z (n = 14 + motors) and its report: PlantSimulator.accept's
 * checks, the currents first (ActuatedPlant.advance). */
static int judge(const pc_fivebar_settings *s, const double *z, int n, const pc_fivebar_report *rep,
                 pc_refusal *refusal)
{
    for (int i = N_Y; i < n; ++i)
        if (!isfinite(z[i])) return pc_refuse(refusal, PC_FIVEBAR_NONFINITE_STATE, i, z[i]);
    if (rep->finite != 1.0) {
        int i = 0;
        while (i < N_Y - 1 && isfinite(z[i])) ++i;
        return pc_refuse(refusal, PC_FIVEBAR_NONFINITE_STATE, i, z[i]);
    }
    if (!(rep->residual <= s->residual_stop)) return pc_refuse(refusal, PC_FIVEBAR_DIVERGED, 0, rep->residual);
    for (int k = 0; k < 3; ++k)
        if (fabs(rep->measures[k]) < s->singular_stop)
            return pc_refuse(refusal, PC_FIVEBAR_SINGULAR, k, rep->measures[k]);
    return PC_OK;
}

/* One step: RK4 from z over dt with the efforts (u1, u2) on theta11, theta21, the motors and
 * their voltages held; the trial state goes to scratch[0 .. n) (n = 14 + n_motors) and its
 * report to `report`, z itself is never written.  Returns PC_OK when the caller may take the
 * trial state, else the refusal (non-finite input before integrating; non-finite state,
 * divergence or a singular pose after it). */
int pc_fivebar_step(const pc_fivebar_params *p, const pc_fivebar_settings *s, const pc_fivebar_motor *motors,
                    int n_motors, const double *z, const double *voltages, double u1, double u2, double dt,
                    double *scratch, pc_fivebar_report *report, pc_refusal *refusal)
{
    if (!isfinite(u1)) return pc_refuse(refusal, PC_FIVEBAR_NONFINITE_INPUT, 0, u1);
    if (!isfinite(u2)) return pc_refuse(refusal, PC_FIVEBAR_NONFINITE_INPUT, 1, u2);
    for (int k = 0; k < n_motors; ++k)
        if (!isfinite(voltages[k])) return pc_refuse(refusal, PC_FIVEBAR_NONFINITE_INPUT, 2 + k, voltages[k]);
    const int n = N_Y + n_motors;
    double *trial = scratch;
    for (int i = 0; i < n; ++i) trial[i] = z[i];
    const pc_fivebar_held held = {p, motors, voltages, u1, u2, s->lambda, n_motors};
    double *cache = scratch + 6 * n;   /* the trigonometry of z when the last step's report kept it */
    advance_turned(&held, cache, trial, n, dt, (int)s->substeps, scratch + n);
    report_of(p, s, trial, report, cache);
    return judge(s, trial, n, report, refusal);
}

/* Newton on the residual with x, y fixed, then dq = C dq# (PlantSimulator.project); y in place. */
void pc_fivebar_project(const pc_fivebar_params *p, double *y, int iterations)
{
    pc_fivebar_terms t;
    double inv[4];
    for (int k = 0; k < 2; ++k) {
        const double base = chain_base(p, k);
        for (int it = 0; it < iterations; ++it) {
            terms_at(p, k, y, &t);
            const double rx = y[0] - base - t.tip[0], ry = y[1] - t.tip[1];
            inverse2(t.J, inv);
            y[3 + 2 * k] += inv[0] * rx + inv[1] * ry;
            y[4 + 2 * k] += inv[2] * rx + inv[3] * ry;
        }
        terms_at(p, k, y, &t);
        inverse2(t.J, inv);
        y[10 + 2 * k] = inv[0] * y[7] + inv[1] * y[8];
        y[11 + 2 * k] = inv[2] * y[7] + inv[3] * y[8];
    }
    y[2] = 0.0;
    y[9] = 0.0;
}

/* The inverse dynamics terms of (5.67-5.77) at (q, dq), as plant.parallel.inverse_dynamics_terms,
 * by the elimination of pc_fivebar_derivative (Cinv_k = (E_k J_v,k)^-1, the chain blocks of C):
 * M_M = m0 1 + sum_k Cinv_k^T M_k Cinv_k (5.75); c_k = -Cinv_k E_k a_bias,k (5.69, platform rows
 * 0); v_M = sum_k Cinv_k^T (M_k c_k + v_k) (5.76); g_M = -m0 g_xy + sum_k Cinv_k^T g_k (5.77,
 * 5.9); Z = U^T C, the rows of C of theta11 and theta21 (5.72). */
void pc_fivebar_inverse_terms(const pc_fivebar_params *p, const double *q, const double *dq,
                              pc_fivebar_inverse *out)
{
    pc_fivebar_terms t;
    double i[4];
    const double m0 = p->m0;
    double m00 = m0, m01 = 0.0, m11 = m0, v0 = 0.0, v1 = 0.0;
    double g0 = -m0 * p->gravity[0], g1 = -m0 * p->gravity[1];
    for (int n = 0; n < N_Q; ++n) out->c[n] = 0.0;
    for (int k = 0; k < 2; ++k) {
        pc_fivebar_chain_terms(p, k, q[3 + 2 * k], q[4 + 2 * k], dq[3 + 2 * k], dq[4 + 2 * k], &t);
        inverse2(t.J, i);
        const double c0 = i[0] * -t.a_bias[0] + i[1] * -t.a_bias[1];
        const double c1 = i[2] * -t.a_bias[0] + i[3] * -t.a_bias[1];
        out->c[3 + 2 * k] = c0;
        out->c[4 + 2 * k] = c1;
        const double *M = t.M;
        const double mc00 = M[0] * i[0] + M[1] * i[2], mc01 = M[0] * i[1] + M[1] * i[3];
        const double mc10 = M[2] * i[0] + M[3] * i[2], mc11 = M[2] * i[1] + M[3] * i[3];
        m00 += i[0] * mc00 + i[2] * mc10;
        m01 += i[0] * mc01 + i[2] * mc11;
        m11 += i[1] * mc01 + i[3] * mc11;
        const double f0 = M[0] * c0 + M[1] * c1 + t.v[0];
        const double f1 = M[2] * c0 + M[3] * c1 + t.v[1];
        v0 += i[0] * f0 + i[2] * f1;
        v1 += i[1] * f0 + i[3] * f1;
        g0 += i[0] * t.g[0] + i[2] * t.g[1];
        g1 += i[1] * t.g[0] + i[3] * t.g[1];
        out->Z[2 * k] = i[0];
        out->Z[2 * k + 1] = i[1];
    }
    out->M[0] = m00;
    out->M[1] = m01;
    out->M[2] = m01;
    out->M[3] = m11;
    out->v[0] = v0;
    out->v[1] = v1;
    out->g[0] = g0;
    out->g[1] = g1;
}

/* pc_fivebar_inverse_terms in the shape of the position law's terms function (pc_law_terms_fn,
 * law.h): `model` is a pc_fivebar_params, `terms` a pc_fivebar_inverse (its first words are
 * pc_law_terms: M_M, v_M, g_M, Z). */
void pc_fivebar_terms_of(const void *model, const double *q, const double *dq, double *terms)
{
    pc_fivebar_inverse_terms(model, q, dq, (pc_fivebar_inverse *)terms);
}

/* The plant's outputs (fmus.slave.declarations.PLANT_OUTPUTS order) from a report into x[first ..]. */
static void publish(const pc_fivebar_report *rep, double *x, int first)
{
    const double o[11] = {rep->q1, rep->q2, rep->dq1, rep->dq2, rep->x, rep->y, rep->dx, rep->dy, rep->q1_enc,
                          rep->q2_enc, rep->residual};
    for (int k = 0; k < 11; ++k) x[first + k] = o[k];
}

/* Take an accepted trial state: copy it into the state and publish the outputs. */
static void take(pc_fivebar_context *c, const pc_fivebar_report *rep, double *x, int first)
{
    const int n = N_Y + c->n_motors;
    for (int i = 0; i < n; ++i) c->state[i] = c->scratch[i];
    publish(rep, x, first);
}

/* FiveBarPlant with RK4, no projection: x = [tau1, tau2 | the 11 plant outputs].  Refused, the
 * state and x are unchanged. */
int pc_fivebar_plant_io(void *context, double *x, double t, double h, pc_refusal *refusal)
{
    (void)t;
    pc_fivebar_context *c = context;
    pc_fivebar_report rep;
    if (!isfinite(x[0])) return pc_refuse(refusal, PC_FIVEBAR_NONFINITE_INPUT, 0, x[0]);
    if (!isfinite(x[1])) return pc_refuse(refusal, PC_FIVEBAR_NONFINITE_INPUT, 1, x[1]);
    const int status = pc_fivebar_step(c->params, c->settings, c->motors, 0, c->state, c->voltages, x[0], -x[1],
                                       h, c->scratch, &rep, refusal);
    if (status == PC_OK) take(c, &rep, x, 2);
    return status;
}

/* ActuatedFiveBarPlant's integration with the drives' voltages (context) held, and the held
 * efforts on theta11, theta21 (context->held, the drives' LuGre bristle torques; NULL: none).
 * Accepted: the state is replaced, x[first .. first + 11) gets the plant's outputs and
 * x[first + 11 + n] motor n's shaft torque at the new current and joint speed (B.2).  Refused:
 * nothing changes. */
int pc_fivebar_actuated_io(void *context, double *x, double t, double h, pc_refusal *refusal)
{
    (void)t;
    pc_fivebar_context *c = context;
    pc_fivebar_report rep;
    const double u1 = c->held ? c->held[0] : 0.0, u2 = c->held ? c->held[1] : 0.0;
    const int status = pc_fivebar_step(c->params, c->settings, c->motors, c->n_motors, c->state, c->voltages, u1,
                                       u2, h, c->scratch, &rep, refusal);
    if (status != PC_OK) return status;
    take(c, &rep, x, c->first);
    for (int n = 0; n < c->n_motors; ++n) {
        const pc_fivebar_motor *r = &c->motors[n];
        x[c->first + 11 + n] = pc_shaft_torque(r->kt, r->b, r->mu, r->omega_eps, c->state[N_Y + n],
                                               motor_speed(r, c->state));
    }
    return PC_OK;
}
