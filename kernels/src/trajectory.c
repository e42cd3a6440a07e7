/* The reference trajectories at a time (thesis 7.18, 7.23-7.27); layouts in trajectory.h. */
#include "trajectory.h"

#include "pc_trig.h"

/* The most rounds of a polygon, for the Python layer to refuse by name. */
const int pc_trajectory_max_cycles = PC_TRAJECTORY_MAX_CYCLES;

#define WORDS(type) ((long)(sizeof(type) / sizeof(double)))
#define WORD(type, field) ((int)(offsetof(type, field) / sizeof(double)))

const pc_field pc_trajectory_circle_fields[] = {
    PC_FIELD(pc_trajectory_circle, kind),   PC_FIELD(pc_trajectory_circle, cx),
    PC_FIELD(pc_trajectory_circle, cy),     PC_FIELD(pc_trajectory_circle, radius),
    PC_FIELD(pc_trajectory_circle, phi0),   PC_FIELD(pc_trajectory_circle, omega),
    PC_FIELD(pc_trajectory_circle, duration), PC_FIELD(pc_trajectory_circle, stops),
    {0, 0, 0},
};

const pc_field pc_trajectory_polygon_fields[] = {
    PC_FIELD(pc_trajectory_polygon, kind),
    PC_FIELD(pc_trajectory_polygon, side_time),
    PC_FIELD(pc_trajectory_polygon, cycles),
    PC_FIELD(pc_trajectory_polygon, vertices),
    PC_FIELD(pc_trajectory_polygon, position),
    PC_FIELD(pc_trajectory_polygon, velocity),
    PC_FIELD(pc_trajectory_polygon, acceleration),
    {"points", WORD(pc_trajectory_polygon, points), 0},
    {0, 0, 0},
};

const pc_field pc_trajectory_hold_fields[] = {
    PC_FIELD(pc_trajectory_hold, kind),
    PC_FIELD(pc_trajectory_hold, x),
    PC_FIELD(pc_trajectory_hold, y),
    {0, 0, 0},
};

static void put(double *out, double x, double y, double dx, double dy, double ddx, double ddy)
{
    out[0] = x;
    out[1] = y;
    out[2] = dx;
    out[3] = dy;
    out[4] = ddx;
    out[5] = ddy;
}

/* Horner's rule on c[0..count-1], ascending powers. */
static double polynomial(const double *c, int count, double tau)
{
    double value = 0.0;
    for (int k = count - 1; k >= 0; --k) value = value * tau + c[k];
    return value;
}

/* (7.18, 7.23): position on the circle, its velocity r omega and centripetal acceleration. */
static void circle(const pc_trajectory_circle *c, double t, double *out)
{
    const int moving = !(c->stops != 0.0 && t >= c->duration);
    const double w = c->omega;
    const double angle = c->phi0 + w * (moving ? t : c->duration);
    double sine, cosine;
    pc_sincos(angle, &sine, &cosine);
    const double r = c->radius;
    const double x = c->cx + r * cosine, y = c->cy + r * sine;
    if (!moving) {
        put(out, x, y, 0.0, 0.0, 0.0, 0.0);
        return;
    }
    const double speed = r * w, centripetal = r * (w * w);
    put(out, x, y, -speed * sine, speed * cosine, -centripetal * cosine, -centripetal * sine);
}

/* A whole number in [1, most]. */
static int whole(double value, double most)
{
    return value >= 1.0 && value <= most && value == (double)(long)value;
}

static int polygon_layout(const pc_trajectory_polygon *p, long words, pc_refusal *r)
{
    if (words < WORDS(pc_trajectory_polygon)) return pc_refuse(r, PC_TRAJECTORY_BAD_LAYOUT, -1, (double)words);
    if (!whole(p->vertices, PC_TRAJECTORY_MAX_VERTICES) ||
        WORDS(pc_trajectory_polygon) + 2 * (long)p->vertices > words)
        return pc_refuse(r, PC_TRAJECTORY_BAD_LAYOUT, WORD(pc_trajectory_polygon, vertices), p->vertices);
    if (!whole(p->cycles, PC_TRAJECTORY_MAX_CYCLES))
        return pc_refuse(r, PC_TRAJECTORY_BAD_LAYOUT, WORD(pc_trajectory_polygon, cycles), p->cycles);
    if (!(isfinite(p->side_time) && p->side_time > 0.0))
        return pc_refuse(r, PC_TRAJECTORY_BAD_LAYOUT, WORD(pc_trajectory_polygon, side_time), p->side_time);
    return PC_OK;
}

/* (7.24-7.27): side i from vertex i to vertex i + 1 by s(tau); the first vertex after the last
 * side. */
static void polygon(const pc_trajectory_polygon *p, double t, double *out)
{
    const long n = (long)p->vertices, sides = (long)p->cycles * n;
    const double side_time = p->side_time;
    if (t >= (double)sides * side_time) {
        put(out, p->points[0], p->points[1], 0.0, 0.0, 0.0, 0.0);
        return;
    }
    long side = (long)floor(t / side_time);
    if (side > sides - 1) side = sides - 1;
    const double tau = t / side_time - (double)side;
    const double *p0 = p->points + 2 * (side % n), *p1 = p->points + 2 * ((side + 1) % n);
    const double position = polynomial(p->position, 8, tau);
    const double velocity = polynomial(p->velocity, 7, tau) / side_time;
    const double acceleration = polynomial(p->acceleration, 6, tau) / (side_time * side_time);
    const double dx = p1[0] - p0[0], dy = p1[1] - p0[1];
    put(out, p0[0] + dx * position, p0[1] + dy * position, dx * velocity, dy * velocity, dx * acceleration,
        dy * acceleration);
}

int pc_trajectory_sample(const double *trajectory, long words, double t, double *out, pc_refusal *r)
{
    if (!trajectory || words < 1) return pc_refuse(r, PC_TRAJECTORY_BAD_LAYOUT, -1, (double)words);
    if (!(t >= 0.0)) return pc_refuse(r, PC_TRAJECTORY_BAD_TIME, 0, t);
    const double kind = trajectory[0];
    if (kind == PC_TRAJECTORY_HOLD) {
        if (words < WORDS(pc_trajectory_hold)) return pc_refuse(r, PC_TRAJECTORY_BAD_LAYOUT, -1, (double)words);
        const pc_trajectory_hold *hold = (const pc_trajectory_hold *)trajectory;
        put(out, hold->x, hold->y, 0.0, 0.0, 0.0, 0.0);
        return PC_OK;
    }
    if (kind == PC_TRAJECTORY_CIRCLE) {
        if (words < WORDS(pc_trajectory_circle)) return pc_refuse(r, PC_TRAJECTORY_BAD_LAYOUT, -1, (double)words);
        circle((const pc_trajectory_circle *)trajectory, t, out);
        return PC_OK;
    }
    if (kind == PC_TRAJECTORY_POLYGON) {
        const pc_trajectory_polygon *p = (const pc_trajectory_polygon *)trajectory;
        int code = polygon_layout(p, words, r);
        if (code != PC_OK) return code;
        polygon(p, t, out);
        return PC_OK;
    }
    return pc_refuse(r, PC_TRAJECTORY_BAD_LAYOUT, 0, kind);
}

int pc_trajectory_io(void *context, double *x, double t, double h, pc_refusal *r)
{
    const pc_trajectory_context *c = context;
    return pc_trajectory_sample(c->trajectory, c->words, t + h, x, r);
}
