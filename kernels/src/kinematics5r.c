/* The 5R's closed-form kinematics (kinematics5r.h; seed 002 eq. 1-20). */
#include "kinematics5r.h"

#include <math.h>

#include "pc_trig.h"

#define PC_PI 3.141592653589793   /* math.pi */

int pc_5r_chain_ik(double l1, double l2, double px, double py, double elbow_sign, double *phi1, double *phi2,
                   double *distance)
{
    const double r2 = px * px + py * py;
    const double cos_b = (r2 - l1 * l1 - l2 * l2) / (2.0 * l1 * l2);   /* law of cosines (eq. 3) */
    if (!(-1.0 <= cos_b && cos_b <= 1.0)) {
        if (distance) *distance = sqrt(r2);
        return PC_5R_OUT_OF_REACH;
    }
    const double beta = elbow_sign * acos(cos_b);                     /* the distal link's relative angle */
    const double sb = elbow_sign * sqrt((1.0 - cos_b) * (1.0 + cos_b)), cb = cos_b;   /* sin beta, cos beta */
    /* phi1 = atan2(py, px) - atan2(b, a): the angle of (px, py) turned back by that of (a, b), one atan2;
     * then the difference's own branch, (-2 pi, 2 pi): past +-pi when the two angles' signs (their
     * y's sign bits, as atan2 takes them) differ and the turned angle came out of the other sign. */
    const double a = l1 + l2 * cb, b = l2 * sb;
    double p1 = atan2(a * py - b * px, a * px + b * py);
    if (!signbit(py) && signbit(b) && p1 < 0.0) p1 += 2.0 * PC_PI;
    else if (signbit(py) && !signbit(b) && p1 > 0.0) p1 -= 2.0 * PC_PI;
    *phi1 = p1;
    *phi2 = p1 + beta;
    return PC_5R_OK;
}

int pc_5r_inverse(const pc_5r_geometry *g, double x, double y, double angles[4], double *distance)
{
    int rc = pc_5r_chain_ik(g->l11, g->l12, x - g->l0, y, 1.0, &angles[0], &angles[1], distance);
    if (rc != PC_5R_OK) return rc;
    return pc_5r_chain_ik(g->l21, g->l22, x + g->l0, y, -1.0, &angles[2], &angles[3], distance);
}

double pc_5r_margin(const double angles[4])
{
    const double serial1 = fabs(pc_sin(angles[1] - angles[0]));
    const double serial2 = fabs(pc_sin(angles[3] - angles[2]));
    const double parallel = fabs(pc_sin(angles[1] - angles[3]));
    return fmin(fmin(serial1, serial2), parallel);
}

/* The smallest |sin| of an elbow pc_5r_clear judges (below, the distal link's direction, through
 * 1 / r^2 with r^2 >= l1 l2 sin^2 beta, is too ill-conditioned to bound). */
#define CLEAR_ELBOW 1e-3

/* Chain (l1, l2) reaching (px, py) from its base with the elbow on `elbow_sign`'s side: sin beta
 * and l2 times the distal link's direction (vx, vy), by pc_5r_chain_ik's law of cosines (0 when
 * out of reach) and cos phi1 = (a px + b py) / r^2, sin phi1 = (a py - b px) / r^2, (a, b) =
 * (l1 + l2 cos beta, l2 sin beta) with a^2 + b^2 = r^2. */
static int chain_directions(double l1, double l2, double px, double py, double elbow_sign, double *sb,
                            double *vx, double *vy)
{
    const double r2 = px * px + py * py;
    const double cos_b = (r2 - l1 * l1 - l2 * l2) / (2.0 * l1 * l2);
    if (!(-1.0 <= cos_b && cos_b <= 1.0)) return 0;
    *sb = elbow_sign * sqrt((1.0 - cos_b) * (1.0 + cos_b));
    const double a = l1 + l2 * cos_b, b = l2 * *sb, k = l1 / r2;
    *vx = px - k * (a * px + b * py);
    *vy = py - k * (a * py - b * px);
    return 1;
}

int pc_5r_clear(const pc_5r_geometry *g, double x, double y, double band)
{
    double sb1, vx1, vy1, sb2, vx2, vy2;
    if (!chain_directions(g->l11, g->l12, x - g->l0, y, 1.0, &sb1, &vx1, &vy1)) return 0;
    if (!chain_directions(g->l21, g->l22, x + g->l0, y, -1.0, &sb2, &vx2, &vy2)) return 0;
    const double serial = fmin(fabs(sb1), fabs(sb2));
    if (!(serial >= CLEAR_ELBOW)) return 0;
    const double parallel = fabs(vy1 * vx2 - vx1 * vy2) / (g->l12 * g->l22);   /* sin(phi12 - phi22) */
    return fmin(serial, parallel) > band + PC_5R_CLEAR_SLACK;
}

/* cos and sin of the two actuated angles, computed once for the forward kinematics, the
 * Jacobians and the bias of one task state. */
typedef struct {
    double c1, s1, c2, s2;
} actuated_trig;

static actuated_trig trig_of(double q1, double q2)
{
    actuated_trig t;
    pc_sincos(q1, &t.s1, &t.c1);
    pc_sincos(q2, &t.s2, &t.c2);
    return t;
}

static int forward(const pc_5r_geometry *g, const actuated_trig *t, double *x, double *y, double *distance)
{
    /* Elbows A1, A2 (eq. 7-8); the tip is where circles of radii l12, l22 about them meet. */
    const double a1x = g->l0 + g->l11 * t->c1, a1y = g->l11 * t->s1;
    const double a2x = -g->l0 + g->l21 * t->c2, a2y = g->l21 * t->s2;
    const double dx = a1x - a2x, dy = a1y - a2y;
    const double dist2 = dx * dx + dy * dy;
    const double dist = sqrt(dist2);
    const double r1 = g->l12, r2 = g->l22;
    if (dist == 0.0 || dist > r1 + r2 || dist < fabs(r1 - r2)) {
        if (distance) *distance = dist;
        return PC_5R_NO_ASSEMBLY;
    }
    const double inv = 1.0 / dist;
    const double along = (dist2 + r2 * r2 - r1 * r1) * (0.5 * inv);   /* from A2 along A2->A1 to the chord */
    const double height = sqrt(fmax(r2 * r2 - along * along, 0.0));   /* half-chord */
    const double ux = dx * inv, uy = dy * inv;
    *x = a2x + along * ux - height * uy;                               /* left of A2 -> A1 */
    *y = a2y + along * uy + height * ux;
    return PC_5R_OK;
}

int pc_5r_forward(const pc_5r_geometry *g, double q1, double q2, double *x, double *y, double *distance)
{
    const actuated_trig t = trig_of(q1, q2);
    return forward(g, &t, x, y, distance);
}

static void jacobians(const pc_5r_geometry *g, double x, double y, const actuated_trig *t, double jx[4],
                      double jt[2])
{
    const double c1 = t->c1, s1 = t->s1, c2 = t->c2, s2 = t->s2;
    jx[0] = x - g->l0 - g->l11 * c1;                    /* (eq. 16: l1 where l2 is printed) */
    jx[1] = y - g->l11 * s1;
    jx[2] = x + g->l0 - g->l21 * c2;
    jx[3] = y - g->l21 * s2;
    jt[0] = g->l11 * ((x - g->l0) * s1 - y * c1);       /* (eq. 17) */
    jt[1] = g->l21 * ((x + g->l0) * s2 - y * c2);
}

void pc_5r_jacobians(const pc_5r_geometry *g, double x, double y, double q1, double q2, double jx[4],
                     double jt[2])
{
    const actuated_trig t = trig_of(q1, q2);
    jacobians(g, x, y, &t, jx, jt);
}

static void bias_rhs(const pc_5r_geometry *g, double x, double y, const actuated_trig *t, double dx, double dy,
                     double dq1, double dq2, double rhs[2])
{
    const double c1 = t->c1, s1 = t->s1, c2 = t->c2, s2 = t->s2;
    const double da1x = -g->l11 * dq1 * s1, da1y = g->l11 * dq1 * c1;     /* elbow velocities */
    const double da2x = -g->l21 * dq2 * s2, da2y = g->l21 * dq2 * c2;
    double r1 = (dx - da1x) * dx + (dy - da1y) * dy;                      /* dJ_X dx */
    double r2 = (dx - da2x) * dx + (dy - da2y) * dy;
    r1 += g->l11 * (dx * s1 + (x - g->l0) * c1 * dq1 - dy * c1 + y * s1 * dq1) * dq1;   /* dJ_Theta dq */
    r2 += g->l21 * (dx * s2 + (x + g->l0) * c2 * dq2 - dy * c2 + y * s2 * dq2) * dq2;
    rhs[0] = r1;
    rhs[1] = r2;
}

void pc_5r_bias_rhs(const pc_5r_geometry *g, double x, double y, double q1, double q2, double dx, double dy,
                    double dq1, double dq2, double rhs[2])
{
    const actuated_trig t = trig_of(q1, q2);
    bias_rhs(g, x, y, &t, dx, dy, dq1, dq2, rhs);
}

int pc_5r_task_state(const pc_5r_geometry *g, double q1, double q2, double dq1, double dq2, double ddq1,
                     double ddq2, pc_5r_task *t)
{
    const actuated_trig trig = trig_of(q1, q2);
    int rc = forward(g, &trig, &t->x, &t->y, &t->distance);
    if (rc != PC_5R_OK) return rc;
    jacobians(g, t->x, t->y, &trig, t->jx, t->jt);
    const double a = t->jx[0], b = t->jx[1], c = t->jx[2], d = t->jx[3];
    const double det = a * d - b * c;
    t->det = det;
    if (det == 0.0) return PC_5R_SINGULAR;
    const double id = 1.0 / det;
    t->J[0] = -d * t->jt[0] * id;
    t->J[1] = b * t->jt[1] * id;
    t->J[2] = c * t->jt[0] * id;
    t->J[3] = -a * t->jt[1] * id;
    t->dx = t->J[0] * dq1 + t->J[1] * dq2;
    t->dy = t->J[2] * dq1 + t->J[3] * dq2;
    double r[2];
    bias_rhs(g, t->x, t->y, &trig, t->dx, t->dy, dq1, dq2, r);
    t->beta[0] = -(d * r[0] - b * r[1]) * id;
    t->beta[1] = -(-c * r[0] + a * r[1]) * id;
    t->ddx = t->J[0] * ddq1 + t->J[1] * ddq2 + t->beta[0];
    t->ddy = t->J[2] * ddq1 + t->J[3] * ddq2 + t->beta[1];
    return PC_5R_OK;
}

int pc_5r_joint_reference(const pc_5r_geometry *g, double x, double y, double dx, double dy, double ddx,
                          double ddy, double p11, double p21, double joint[6])
{
    double jx[4], jt[2], r[2];
    const actuated_trig trig = trig_of(p11, p21);
    jacobians(g, x, y, &trig, jx, jt);
    if (jt[0] == 0.0 || jt[1] == 0.0) return PC_5R_SINGULAR;
    const double dq1 = -(jx[0] * dx + jx[1] * dy) / jt[0];
    const double dq2 = -(jx[2] * dx + jx[3] * dy) / jt[1];
    bias_rhs(g, x, y, &trig, dx, dy, dq1, dq2, r);
    joint[0] = p11;
    joint[1] = p21;
    joint[2] = dq1;
    joint[3] = dq2;
    joint[4] = -(jx[0] * ddx + jx[1] * ddy + r[0]) / jt[0];
    joint[5] = -(jx[2] * ddx + jx[3] * ddy + r[1]) / jt[1];
    return PC_5R_OK;
}

void pc_5r_link_rates(double l1, double l2, double p1, double p2, double dx, double dy, double w[2])
{
    double s1, c1, s2, c2;
    pc_sincos(p1, &s1, &c1);
    pc_sincos(p2, &s2, &c2);
    const double m00 = -l1 * s1, m01 = -l2 * s2;
    const double m10 = l1 * c1, m11 = l2 * c2;
    const double det = m00 * m11 - m01 * m10;
    w[0] = (m11 * dx - m01 * dy) / det;
    w[1] = (-m10 * dx + m00 * dy) / det;
}

int pc_5r_thesis_state(const pc_5r_geometry *g, double x, double y, double dx, double dy, double q[7],
                       double dq[7], double *distance)
{
    double p[4], w1[2], w2[2];
    int rc = pc_5r_inverse(g, x, y, p, distance);
    if (rc != PC_5R_OK) return rc;
    q[0] = x; q[1] = y; q[2] = 0.0;
    q[3] = p[0];
    q[4] = p[1] - p[0];
    q[5] = PC_PI - p[2];          /* chain 2's mirrored frame (7.4) */
    q[6] = p[2] - p[3];
    pc_5r_link_rates(g->l11, g->l12, p[0], p[1], dx, dy, w1);
    pc_5r_link_rates(g->l21, g->l22, p[2], p[3], dx, dy, w2);
    dq[0] = dx; dq[1] = dy; dq[2] = 0.0;
    dq[3] = w1[0];
    dq[4] = w1[1] - w1[0];
    dq[5] = -w2[0];
    dq[6] = w2[0] - w2[1];
    return PC_5R_OK;
}
