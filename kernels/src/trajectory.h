/* The reference trajectories of the end effector (thesis 7.18, 7.23-7.27), evaluated at a time.
 *
 * controller/trajectories.py defines them as frozen objects; each packs itself into one
 * buffer of doubles whose first word is its kind and whose layout is then the kind's struct
 * below (a circle, a polygon travelled by the polynomial 7.27, a held point).  A sample is
 * (x, y, dx, dy, ddx, ddy) in the world frame [m, m/s, m/s^2].
 *
 * The polygon's number of vertices and of cycles are read from the buffer: the sample checks
 * them (and the kind, and the side time it divides by) against the buffer's length and refuses
 * (PC_TRAJECTORY_BAD_LAYOUT) what does not fit, so a forged buffer cannot make it read outside.
 */
#ifndef PC_TRAJECTORY_H
#define PC_TRAJECTORY_H

#include "pc_common.h"

/* Refusal codes; pc_refusal.index 0 and value: the time (BAD_TIME), or the offending word's
 * index in the buffer and its value (BAD_LAYOUT; -1 and the length for a short buffer). */
#define PC_TRAJECTORY_BAD_TIME 1   /* t < 0 or not a number */
#define PC_TRAJECTORY_BAD_LAYOUT 2 /* unknown kind, or sizes that do not fit the buffer */

#define PC_TRAJECTORY_CIRCLE 0.0
#define PC_TRAJECTORY_POLYGON 1.0
#define PC_TRAJECTORY_HOLD 2.0
/* Most vertices and cycles of a polygon (their product indexes the sides). */
#define PC_TRAJECTORY_MAX_VERTICES 1000000
#define PC_TRAJECTORY_MAX_CYCLES 1000000

/* Uniform motion on a circle (7.18, 7.23): phi = phi0 + omega t, x = cx + r cos phi,
 * y = cy + r sin phi; with `stops`, the point reached at `duration` held from then on. */
typedef struct {
    double kind;     /* PC_TRAJECTORY_CIRCLE */
    double cx, cy;   /* centre [m] */
    double radius;   /* r [m] */
    double phi0;     /* initial angle [rad] */
    double omega;    /* angular velocity [rad/s], negative: clockwise */
    double duration; /* length of the motion [s] */
    double stops;    /* 1.0: hold the last point after `duration`; 0.0: keep circling */
} pc_trajectory_circle;

/* A closed polygon, each side from p_i to p_(i+1) travelled in `side_time` by s(tau) of 7.27:
 * p = p_i + (p_(i+1) - p_i) s(tau), tau = t / side_time - i; after `cycles` rounds the first
 * vertex held. */
typedef struct {
    double kind;            /* PC_TRAJECTORY_POLYGON */
    double side_time;       /* [s] */
    double cycles;          /* rounds, a whole number >= 1 */
    double vertices;        /* n, a whole number >= 1 */
    double position[8];     /* s(tau) of 7.27, ascending powers */
    double velocity[7];     /* s'(tau) */
    double acceleration[6]; /* s''(tau) */
    double points[];        /* the n vertices (x, y) [m] */
} pc_trajectory_polygon;

/* A point held at rest. */
typedef struct {
    double kind; /* PC_TRAJECTORY_HOLD */
    double x, y; /* [m] */
} pc_trajectory_hold;

extern const pc_field pc_trajectory_circle_fields[];
extern const pc_field pc_trajectory_polygon_fields[];
extern const pc_field pc_trajectory_hold_fields[];

/* The compiled loop's context: the packed trajectory and its length in doubles. */
typedef struct {
    const double *trajectory;
    long words;
} pc_trajectory_context;

/* The reference at time t [s]: out = (x, y, dx, dy, ddx, ddy).  Refused (out untouched):
 * BAD_TIME, BAD_LAYOUT. */
int pc_trajectory_sample(const double *trajectory, long words, double t, double *out, pc_refusal *r);

/* Compiled loop: x = [x_d, y_d, dx_d, dy_d, ddx_d, ddy_d], the reference at t + h. */
int pc_trajectory_io(void *context, double *x, double t, double h, pc_refusal *r);

#endif
