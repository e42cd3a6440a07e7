/* The position controller's law (law.h; thesis 7.21-7.22, 6.65-6.66, seed 001 section 1.2). */
#include "law.h"

#include <math.h>
#include <string.h>

static double sign_of(double x)
{
    return x == 0.0 ? 0.0 : copysign(1.0, x);
}

/* sat (6.65) */
static double sat(double x)
{
    return (-1.0 <= x && x <= 1.0) ? x : (x > 0.0 ? 1.0 : -1.0);
}

int pc_law_interpolate(const pc_law_table *t, double x, double y, double out[PC_LAW_TERMS], pc_refusal *r)
{
    const double fx = (x - t->x0) * t->inv_step, fy = (y - t->y0) * t->inv_step;
    if (!(0.0 <= fx && fx < t->nx + 1.0)) return pc_refuse(r, PC_LAW_TABLE_OUT, 0, x);
    if (!(0.0 <= fy && fy < t->ny + 1.0)) return pc_refuse(r, PC_LAW_TABLE_OUT, 1, y);
    int ix = (int)fx, iy = (int)fy;               /* floor: both >= 0 here */
    const int nx = (int)t->nx, ny = (int)t->ny;
    if (ix == nx && fx - ix < 1e-9) ix -= 1;      /* the far edge belongs to the last cell */
    if (iy == ny && fy - iy < 1e-9) iy -= 1;
    if (!(0 <= ix && ix < nx)) return pc_refuse(r, PC_LAW_TABLE_OUT, 0, x);
    if (!(0 <= iy && iy < ny)) return pc_refuse(r, PC_LAW_TABLE_OUT, 1, y);
    const size_t row = (size_t)(nx + 1) * PC_LAW_TERMS;
    const double *c00 = t->values + (size_t)iy * row + (size_t)ix * PC_LAW_TERMS;   /* corners [y][x] */
    const double *c01 = c00 + PC_LAW_TERMS, *c10 = c00 + row, *c11 = c10 + PC_LAW_TERMS;
    if (isnan(c00[0]) || isnan(c01[0]) || isnan(c10[0]) || isnan(c11[0]))
        return pc_refuse(r, PC_LAW_TABLE_HOLE, 0, x);
    const double wx = fx - ix, wy = fy - iy;
    for (int j = 0; j < PC_LAW_TERMS; ++j)
        out[j] = (1.0 - wy) * ((1.0 - wx) * c00[j] + wx * c01[j]) + wy * ((1.0 - wx) * c10[j] + wx * c11[j]);
    return PC_OK;
}

static int check_inputs(const pc_law_inputs *in, pc_refusal *r)
{
    const double *v = &in->q1;
    for (int i = 0; i < 12; ++i)
        if (!isfinite(v[i])) return pc_refuse(r, PC_LAW_NONFINITE, i, v[i]);
    return PC_OK;
}

void pc_law_predict(const double measured[4], const double *past, const double bias[2], int a, int b, double h,
                    double joint[4])
{
    for (int i = 0; i < 2; ++i) {
        double q = measured[i], v = measured[2 + i];
        const double o = bias[i];
        for (int k = b; k > a; --k) v += h * (past[2 * (k - 1) + i] - o);        /* the rates, on to the angles' time */
        for (int k = b + 1; k <= a; ++k) v -= h * (past[2 * (k - 1) + i] - o);   /* or back to it */
        for (int k = a; k >= 1; --k) {                                           /* both over the angles' delay */
            const double acc = past[2 * (k - 1) + i] - o;
            q += h * v + 0.5 * h * h * acc;
            v += h * acc;
        }
        joint[i] = q;
        joint[2 + i] = v;
    }
}

int pc_law_prepare(const pc_law_params *p, const pc_law_state *s, pc_law_scratch *w, double h, pc_refusal *r)
{
    const pc_law_inputs *in = &w->in;
    const pc_5r_geometry *g = &p->geometry;
    int rc = check_inputs(in, r);
    if (rc != PC_OK) return rc;
    const double measured[4] = {in->q1, in->q2, in->dq1, in->dq2};
    double *j = w->joint;
    if (p->predict[0] > 0.0 || p->predict[1] > 0.0)
        pc_law_predict(measured, s->past, s->offset, (int)p->predict[0], (int)p->predict[1], h, j);
    else
        memcpy(j, measured, sizeof measured);
    /* The reference at the commands' time: a periods on along its own derivatives. */
    double d[6];
    memcpy(d, &in->x_d, sizeof d);
    const double ahead = p->predict[0] * h;
    if (ahead > 0.0)
        for (int i = 0; i < 2; ++i) {
            d[i] += ahead * d[2 + i] + 0.5 * ahead * ahead * d[4 + i];
            d[2 + i] += ahead * d[4 + i];
        }
    /* The reference: inverse kinematics and the singularity margin; in task space, whose law
     * needs no angles, only when the reference is not clearly in reach and out of the band. */
    double distance = 0.0;
    double *a = w->angles;
    if (p->space != PC_LAW_SPACE_X || !pc_5r_clear(g, d[0], d[1], p->band)) {
        if (pc_5r_chain_ik(g->l11, g->l12, d[0] - g->l0, d[1], 1.0, &a[0], &a[1], &distance) != PC_5R_OK)
            return pc_refuse(r, PC_LAW_REF_OUT, 0, distance);
        if (pc_5r_chain_ik(g->l21, g->l22, d[0] + g->l0, d[1], -1.0, &a[2], &a[3], &distance) != PC_5R_OK)
            return pc_refuse(r, PC_LAW_REF_OUT, 1, distance);
        const double margin = pc_5r_margin(a);
        if (margin < p->band) return pc_refuse(r, PC_LAW_REF_BAND, 0, margin);
    }
    /* The measured task state. */
    pc_5r_task *t = &w->task;
    rc = pc_5r_task_state(g, j[0], j[1], j[2], j[3], in->ddq1, in->ddq2, t);
    if (rc == PC_5R_NO_ASSEMBLY) return pc_refuse(r, PC_LAW_NO_ASSEMBLY, 0, t->distance);
    if (rc == PC_5R_SINGULAR) return pc_refuse(r, PC_LAW_MEASURED_SINGULAR, 0, t->det);
    if (p->space == PC_LAW_SPACE_X) {
        const double task[6] = {t->x, t->y, t->dx, t->dy, t->ddx, t->ddy};
        memcpy(w->r, task, sizeof task);
        memcpy(w->rd, d, sizeof w->rd);
    } else {
        const double joint[6] = {j[0], j[1], j[2], j[3], in->ddq1, in->ddq2};
        memcpy(w->r, joint, sizeof joint);
        if (pc_5r_joint_reference(g, d[0], d[1], d[2], d[3], d[4], d[5], a[0], a[2], w->rd) != PC_5R_OK)
            return pc_refuse(r, PC_LAW_REF_SINGULAR, 0, 0.0);
    }
    return PC_OK;
}

int pc_law_exact_pose(const pc_law_params *p, pc_law_scratch *w, pc_refusal *r)
{
    double distance = 0.0;
    const pc_5r_task *t = &w->task;
    if (pc_5r_thesis_state(&p->geometry, t->x, t->y, t->dx, t->dy, w->q, w->dq, &distance) != PC_5R_OK)
        return pc_refuse(r, PC_LAW_EXACT_OUT, 0, distance);
    return PC_OK;
}

/* The law on component i (7.21-7.22 or seed 001's): advances `s`, returns the commanded
 * acceleration. */
static double component(const pc_law_params *p, pc_law_state *s, int i, double e, double de, double dde,
                        double ddr_d, double h)
{
    const int seed = p->law == PC_LAW_SEED;
    double feedback, sv;
    if (seed) {
        feedback = p->lam * de;
        sv = de + p->lam * e;                                     /* seed 001: s = de + lam e */
    } else {
        feedback = p->kv * de + p->kp * e;
        sv = dde + feedback;                                      /* (7.22) */
    }
    if (p->adaptive != 0.0) {                                     /* (6.66) */
        const double s_prev = s->s_prev[i];
        const int same = sign_of(sv) == sign_of(s_prev);
        if (fabs(sv) >= p->phi || !same) s->k[i] = fabs(s->k[i] + p->gamma[i] * sign_of(sv) * sign_of(s_prev));
    }
    const double k = s->k[i];
    s->s_prev[i] = sv;
    s->s[i] = sv;
    s->e[i] = e;
    if (seed) return ddr_d + feedback + k * sat(sv / p->phi);
    if (k != 0.0) s->integral[i] += h * k * sat(sv / p->phi);    /* (6.65): rectangle rule, this sample included */
    return ddr_d + feedback + s->integral[i];                     /* (7.21) */
}

/* J^-1 (f0, f1) into out (task space; joint space: f itself). */
static void to_joints(const pc_law_params *p, const pc_law_scratch *w, double f0, double f1, double out[2])
{
    if (p->space != PC_LAW_SPACE_X) {
        out[0] = f0;
        out[1] = f1;
        return;
    }
    const double *J = w->task.J;
    const double det = J[0] * J[3] - J[1] * J[2];
    out[0] = (J[3] * f0 - J[1] * f1) / det;
    out[1] = (J[0] * f1 - J[2] * f0) / det;
}

/* With predict: the joint accelerations the commanded (a0, a1) make in the model, newest in
 * s->past (task space: q'' = J^-1 (a' - beta) at the pose the law acted on), and the part of
 * them the plant is taken not to follow (s->offset): the integral, the law's own estimate of
 * what its model misses, and the feedback's low-passed part (at lam: a steady feedback balances
 * a disturbance, it does not accelerate the plant). */
static void remember(const pc_law_params *p, const pc_law_scratch *w, double a0, double a1, double h,
                     pc_law_state *s)
{
    const int n = (int)fmax(p->predict[0], p->predict[1]);
    if (n <= 0) return;
    const double *beta = p->space == PC_LAW_SPACE_X ? w->task.beta : (const double[2]){0.0, 0.0};
    double acc[2], feedback[2], integral[2];
    to_joints(p, w, a0 - beta[0], a1 - beta[1], acc);
    to_joints(p, w, a0 - w->rd[4] - s->integral[0], a1 - w->rd[5] - s->integral[1], feedback);
    to_joints(p, w, s->integral[0], s->integral[1], integral);
    const double alpha = h * p->lam / (1.0 + h * p->lam);
    memmove(s->past + 2, s->past, sizeof(double) * 2 * (size_t)(n - 1));
    for (int i = 0; i < 2; ++i) {
        s->past[i] = acc[i];
        s->bias[i] += alpha * (feedback[i] - s->bias[i]);
        s->offset[i] = s->bias[i] + integral[i];
    }
}

/* u' = J^T f: the torques of a task-space effort (the actuators' power balance). */
static void transpose_times(const double J[4], double f0, double f1, double tau[2])
{
    tau[0] = J[0] * f0 + J[2] * f1;
    tau[1] = J[1] * f0 + J[3] * f1;
}

/* The torques of the commanded accelerations (a0, a1) with the model's H, h. */
static void torques(const pc_law_params *p, const pc_law_scratch *w, const double *H, double h0, double h1,
                    const pc_law_terms *exact, double a0, double a1, double tau[2])
{
    const double *J = w->task.J, *beta = w->task.beta;
    if (p->space == PC_LAW_SPACE_X) {
        const double u0 = H[0] * a0 + H[1] * a1 + h0, u1 = H[1] * a0 + H[2] * a1 + h1;   /* (7.21) */
        if (exact) {                                              /* u' = Z^T u* (5.72) */
            const double *Z = exact->Z;
            const double det = Z[0] * Z[3] - Z[1] * Z[2];
            tau[0] = (Z[3] * u0 - Z[2] * u1) / det;
            tau[1] = -((-Z[1] * u0 + Z[0] * u1) / det);           /* tau2 = -u*_theta21 */
        } else {
            transpose_times(J, u0, u1, tau);
        }
        return;
    }
    /* Joint space: u' = J^T (H (J a + beta) + h). */
    const double ax = J[0] * a0 + J[1] * a1 + beta[0];
    const double ay = J[2] * a0 + J[3] * a1 + beta[1];
    transpose_times(J, H[0] * ax + H[1] * ay + h0, H[1] * ax + H[2] * ay + h1, tau);
}

int pc_law_finish(const pc_law_params *p, const pc_law_table *table, const pc_law_terms *terms,
                  pc_law_state *state, pc_law_scratch *w, double h, pc_refusal *r)
{
    double H[3] = {0.0, 0.0, 0.0}, h0 = 0.0, h1 = 0.0;
    const int pd = p->model == PC_LAW_MODEL_PD;
    if (!pd && terms) {                                           /* exact: M_M, v_M + g_M (5.74-5.77) */
        H[0] = terms->M[0]; H[1] = terms->M[1]; H[2] = terms->M[3];
        h0 = terms->v[0] + terms->g[0];
        h1 = terms->v[1] + terms->g[1];
    } else if (!pd) {                                             /* tabulated: the row at the pose */
        int rc = pc_law_interpolate(table, w->task.x, w->task.y, w->m, r);
        if (rc != PC_OK) return rc;
        const double *m = w->m;
        const double xx = w->task.dx * w->task.dx, yy = w->task.dy * w->task.dy, xy = w->task.dx * w->task.dy;
        H[0] = m[0]; H[1] = m[1]; H[2] = m[2];
        h0 = m[3] * xx + m[5] * yy + m[7] * xy + m[9];
        h1 = m[4] * xx + m[6] * yy + m[8] * xy + m[10];
    }
    pc_law_state next = *state;
    const double *rr = w->r, *rd = w->rd;
    const double a0 = component(p, &next, 0, rd[0] - rr[0], rd[2] - rr[2], rd[4] - rr[4], rd[4], h);
    const double a1 = component(p, &next, 1, rd[1] - rr[1], rd[3] - rr[3], rd[5] - rr[5], rd[5], h);
    remember(p, w, a0, a1, h, &next);
    pc_law_outputs *out = &w->out;
    if (pd) {                                                     /* PD: H^ = m* 1, h^ = 0 */
        const double u0 = p->m_star * a0, u1 = p->m_star * a1;
        if (p->space == PC_LAW_SPACE_X) {
            transpose_times(w->task.J, u0, u1, out->tau);
        } else {
            out->tau[0] = u0;
            out->tau[1] = u1;
        }
    } else {
        torques(p, w, H, h0, h1, p->model == PC_LAW_MODEL_EXACT ? terms : NULL, a0, a1, out->tau);
    }
    out->i_ref[0] = out->tau[0] / p->kt[0];
    out->i_ref[1] = out->tau[1] / p->kt[1];
    out->e[0] = next.e[0];
    out->e[1] = next.e[1];
    const double *o = out->tau;
    for (int i = 0; i < 6; ++i)
        if (!isfinite(o[i])) return pc_refuse(r, PC_LAW_NONFINITE_OUTPUT, i, o[i]);
    *state = next;
    return PC_OK;
}

int pc_law_run(const pc_law_context *c, double h, pc_refusal *r)
{
    const pc_law_params *p = c->params;
    int rc = pc_law_prepare(p, c->state, c->scratch, h, r);
    if (rc != PC_OK) return rc;
    if (p->model != PC_LAW_MODEL_EXACT) return pc_law_finish(p, c->table, NULL, c->state, c->scratch, h, r);
    rc = pc_law_exact_pose(p, c->scratch, r);
    if (rc != PC_OK) return rc;
    if (!c->terms_of) return PC_LAW_NEEDS_TERMS;
    c->terms_of(c->model, c->scratch->q, c->scratch->dq, (double *)c->terms);
    return pc_law_finish(p, c->table, c->terms, c->state, c->scratch, h, r);
}

int pc_law_resume(const pc_law_context *c, double h, pc_refusal *r)
{
    return pc_law_finish(c->params, c->table, c->terms, c->state, c->scratch, h, r);
}

void pc_law_delay(double *delayed, int n, double commands[4])
{
    for (int j = 0; j < 4; ++j) {
        const double fresh = commands[j];
        commands[j] = delayed[j];
        for (int m = 0; m + 1 < n; ++m) delayed[4 * m + j] = delayed[4 * (m + 1) + j];
        delayed[4 * (n - 1) + j] = fresh;
    }
}

int pc_law_io(void *context, double *x, double t, double h, pc_refusal *r)
{
    (void)t;
    const pc_law_context *c = context;
    memcpy(&c->scratch->in, x, sizeof c->scratch->in);
    const int rc = pc_law_run(c, h, r);
    if (rc != PC_OK) return rc;
    memcpy(x + 12, &c->scratch->out, sizeof c->scratch->out);
    if (c->n_delayed > 0) pc_law_delay(c->delayed, c->n_delayed, x + 12);
    return PC_OK;
}

/* Field lists (kernels.layout). */
const pc_field pc_law_params_fields[] = {
    PC_FIELD(pc_law_params, geometry), PC_FIELD(pc_law_params, band), PC_FIELD(pc_law_params, space),
    PC_FIELD(pc_law_params, model), PC_FIELD(pc_law_params, law), PC_FIELD(pc_law_params, kp),
    PC_FIELD(pc_law_params, kv), PC_FIELD(pc_law_params, lam), PC_FIELD(pc_law_params, phi),
    PC_FIELD(pc_law_params, adaptive), PC_FIELD(pc_law_params, gamma), PC_FIELD(pc_law_params, m_star),
    PC_FIELD(pc_law_params, kt), PC_FIELD(pc_law_params, predict), {0, 0, 0}};
const pc_field pc_law_state_fields[] = {
    PC_FIELD(pc_law_state, integral), PC_FIELD(pc_law_state, k), PC_FIELD(pc_law_state, s_prev),
    PC_FIELD(pc_law_state, s), PC_FIELD(pc_law_state, e), PC_FIELD(pc_law_state, past), PC_FIELD(pc_law_state, bias),
    PC_FIELD(pc_law_state, offset), {0, 0, 0}};
const pc_field pc_law_table_fields[] = {
    PC_FIELD(pc_law_table, x0), PC_FIELD(pc_law_table, y0), PC_FIELD(pc_law_table, inv_step),
    PC_FIELD(pc_law_table, nx), PC_FIELD(pc_law_table, ny),
    {"values", (int)(offsetof(pc_law_table, values) / sizeof(double)), 0}, {0, 0, 0}};
const pc_field pc_law_terms_fields[] = {
    PC_FIELD(pc_law_terms, M), PC_FIELD(pc_law_terms, v), PC_FIELD(pc_law_terms, g), PC_FIELD(pc_law_terms, Z),
    {0, 0, 0}};
const pc_field pc_law_scratch_fields[] = {
    PC_FIELD(pc_law_scratch, in), PC_FIELD(pc_law_scratch, out), PC_FIELD(pc_law_scratch, task),
    PC_FIELD(pc_law_scratch, angles), PC_FIELD(pc_law_scratch, r), PC_FIELD(pc_law_scratch, rd),
    PC_FIELD(pc_law_scratch, m), PC_FIELD(pc_law_scratch, q), PC_FIELD(pc_law_scratch, dq),
    PC_FIELD(pc_law_scratch, joint), {0, 0, 0}};
const pc_field pc_5r_task_fields[] = {
    PC_FIELD(pc_5r_task, x), PC_FIELD(pc_5r_task, y), PC_FIELD(pc_5r_task, dx), PC_FIELD(pc_5r_task, dy),
    PC_FIELD(pc_5r_task, ddx), PC_FIELD(pc_5r_task, ddy), PC_FIELD(pc_5r_task, jx), PC_FIELD(pc_5r_task, jt),
    PC_FIELD(pc_5r_task, det), PC_FIELD(pc_5r_task, J), PC_FIELD(pc_5r_task, beta),
    PC_FIELD(pc_5r_task, distance), {0, 0, 0}};
