/* The 5R's closed-form kinematics in the world frame (seed 002 eq. 1-20), once for every
 * kernel: inverse kinematics in the "elbows outward" working mode (eq. 1-6, 12), direct
 * kinematics (eq. 7-11), the Jacobians J_X, J_Theta of J_X dX + J_Theta dq = 0 (eq. 15-17),
 * their time derivatives, and the thesis' coordinates q (7.12) and rates dq = C dq# (5.56).
 *
 * World convention: chain 1's base at (+l0, 0), chain 2's at (-l0, 0), angles counter-
 * clockwise from +x.  The change of variables x = FK(q):
 *   dx = J dq,        J = -J_X^-1 J_Theta,
 *   ddx = J ddq + beta, beta = -J_X^-1 (dJ_X dx + dJ_Theta dq).
 * Python: the binding plant/kinematics5r.py, used by plant/fivebar.py and controller/kinematics.py;
 * the tests hold these against the general algorithm (plant/serial.py + plant/parallel.py).
 */
#ifndef PC_KINEMATICS5R_H
#define PC_KINEMATICS5R_H

/* The lengths the kinematics use, m. */
typedef struct {
    double l0;    /* half the base distance: chain 1 at (+l0, 0), chain 2 at (-l0, 0) */
    double l11;   /* chain 1: proximal link */
    double l12;   /* chain 1: distal link */
    double l21;   /* chain 2: proximal link */
    double l22;   /* chain 2: distal link */
} pc_5r_geometry;

/* Results of the functions below: 0 is success. */
enum {
    PC_5R_OK = 0,
    PC_5R_OUT_OF_REACH = 1,   /* a chain cannot reach the point: `distance` is its base-to-point distance */
    PC_5R_NO_ASSEMBLY = 2,    /* the distal links cannot meet: `distance` is the elbows' distance */
    PC_5R_SINGULAR = 3        /* det J_X = 0 (parallel singularity) */
};

/* The task state of a joint measurement (Kinematics.task_state). */
typedef struct {
    double x, y;        /* end effector, m */
    double dx, dy;      /* m/s */
    double ddx, ddy;    /* m/s^2 */
    double jx[4];       /* J_X = [[a, b], [c, d]] row-major (eq. 15-16) */
    double jt[2];       /* diagonal of J_Theta (eq. 17) */
    double det;         /* det J_X */
    double J[4];        /* J = -J_X^-1 J_Theta, row-major: dx = J dq */
    double beta[2];     /* ddx = J ddq + beta */
    double distance;    /* without assembly: the elbows' distance, m */
} pc_5r_task;

/* (phi1, phi2): world angles of a chain's two links reaching (px, py) from its base;
 * elbow_sign +1 puts the elbow right of the base-to-tip line (chain 1 outward), -1 left. */
int pc_5r_chain_ik(double l1, double l2, double px, double py, double elbow_sign, double *phi1, double *phi2,
                   double *distance);

/* World link angles (phi11, phi12, phi21, phi22) reaching (x, y) (eq. 1-6, 12). */
int pc_5r_inverse(const pc_5r_geometry *g, double x, double y, double angles[4], double *distance);

/* Singularity margin of the angles: min |sin| of both elbow angles and of the distal links'
 * angle (plant.fivebar.singularity(...).margin). */
double pc_5r_margin(const double angles[4]);

/* 1 when both chains reach (x, y) and its singularity margin is above `band` by more than
 * PC_5R_CLEAR_SLACK, from the sines and cosines of the law of cosines alone (no acos, atan2);
 * 0 otherwise (out of reach, an elbow within 1e-3 of stretched or folded, or near the band),
 * where the caller computes the angles and pc_5r_margin: a refusal's code and value are those. */
int pc_5r_clear(const pc_5r_geometry *g, double x, double y, double band);
/* What pc_5r_clear's margin may be off from pc_5r_margin's: both round by a few ulps of their
 * O(1) operands, pc_5r_clear's by at most ~1e2 eps (l1 + l2) / (sqrt(l1 l2) 1e-3) beyond: 1e-11
 * for links within 1:100. */
#define PC_5R_CLEAR_SLACK 1e-9

/* End effector (x, y) from the actuated angles (eq. 7-11), the assembly mode of the thesis'
 * figure (the tip left of the line from chain 2's elbow to chain 1's). */
int pc_5r_forward(const pc_5r_geometry *g, double q1, double q2, double *x, double *y, double *distance);

/* J_X = [[a, b], [c, d]] (row-major) and J_Theta's diagonal (t1, t2) at (x, y, q1, q2). */
void pc_5r_jacobians(const pc_5r_geometry *g, double x, double y, double q1, double q2, double jx[4],
                     double jt[2]);

/* dJ_X dx + dJ_Theta dq: the velocity-quadratic part of the differentiated constraint. */
void pc_5r_bias_rhs(const pc_5r_geometry *g, double x, double y, double q1, double q2, double dx, double dy,
                    double dq1, double dq2, double rhs[2]);

/* The task state (x, dx, ddx, J, beta) of joint angles, rates and accelerations. */
int pc_5r_task_state(const pc_5r_geometry *g, double q1, double q2, double dq1, double dq2, double ddq1,
                     double ddq2, pc_5r_task *task);

/* (q1, q2, dq1, dq2, ddq1, ddq2) following the task motion (x, dx, ddx) at the actuated angles
 * (p11, p21) of the point: dq = -J_Theta^-1 J_X dx, ddq = -J_Theta^-1 (J_X ddx + dJ_X dx +
 * dJ_Theta dq).  PC_5R_SINGULAR where J_Theta is (a chain stretched or folded). */
int pc_5r_joint_reference(const pc_5r_geometry *g, double x, double y, double dx, double dy, double ddx,
                          double ddy, double p11, double p21, double joint[6]);

/* The thesis' q (7.12) and dq = C dq# (5.56) of the end effector at (x, y) moving at (dx, dy):
 * q = (x, y, 0, theta11, theta12, theta21, theta22) with theta11 = phi11, theta12 = phi12 -
 * phi11, theta21 = pi - phi21, theta22 = phi21 - phi22. */
int pc_5r_thesis_state(const pc_5r_geometry *g, double x, double y, double dx, double dy, double q[7],
                       double dq[7], double *distance);

/* Link rates (w1, w2) of a chain whose tip moves at (dx, dy): l1 w1 n(p1) + l2 w2 n(p2) = (dx, dy),
 * n(p) = (-sin p, cos p). */
void pc_5r_link_rates(double l1, double l2, double p1, double p2, double dx, double dy, double w[2]);

#endif
