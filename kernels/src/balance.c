/* The wheeled pendulum's balance controller sample: see balance.h. */
#include "balance.h"

#define P(field) PC_FIELD(pc_balance_params, field)
const pc_field pc_balance_params_fields[] = {
    P(n), P(ny), P(yaw), P(r_over_w), P(radius), P(v_max), P(gain), P(distance), P(turn), P(drive), P(turning),
    P(smooth), P(slope), P(states), P(K), P(Lo), P(C), P(Ad), P(Bd), {0, 0, 0}};
#undef P

const pc_field pc_balance_state_fields[] = {
    PC_FIELD(pc_balance_state, started), PC_FIELD(pc_balance_state, x_hat), PC_FIELD(pc_balance_state, u),
    {0, 0, 0}};

const pc_field pc_balance_fields[] = {PC_FIELD(pc_balance, params), PC_FIELD(pc_balance, state), {0, 0, 0}};

enum { THETA, PSI, PHI, DTHETA, DPSI, DPHI };

/* The word index of a field of pc_balance_params, for a refusal. */
#define WORD(field) ((int)(offsetof(pc_balance, params.field) / sizeof(double)))

/* An integer-valued word in [low, high]: a size or an index read from the buffer. */
static int integer_in(double v, double low, double high)
{
    return v >= low && v <= high && v == floor(v);
}

/* The sizes and kept-state indices before any of them indexes an array. */
static int check_layout(const pc_balance_params *p, pc_refusal *r)
{
    if (!integer_in(p->n, 0, PC_BALANCE_N_MAX)) return pc_refuse(r, PC_BALANCE_BAD_BUFFER, WORD(n), p->n);
    if (!integer_in(p->ny, 0, PC_BALANCE_NY_MAX)) return pc_refuse(r, PC_BALANCE_BAD_BUFFER, WORD(ny), p->ny);
    for (int i = 0; i < (int)p->n; ++i)
        if (!integer_in(p->states[i], 0, PC_BALANCE_N_MAX - 1))
            return pc_refuse(r, PC_BALANCE_BAD_BUFFER, WORD(states) + i, p->states[i]);
    return PC_OK;
}

/* (s, s') of the smooth step (7.27) over `window` at t (Horner). */
static void smooth_step(const pc_balance_params *p, const double window[2], double t, double *s, double *ds)
{
    const double start = window[0], end = window[1];
    if (t <= start) {
        *s = 0.0, *ds = 0.0;
        return;
    }
    if (t >= end) {
        *s = 1.0, *ds = 0.0;
        return;
    }
    const double tau = (t - start) / (end - start);
    double value = 0.0, slope = 0.0;
    for (int i = 7; i >= 0; --i) value = value * tau + p->smooth[i];
    for (int i = 6; i >= 0; --i) slope = slope * tau + p->slope[i];
    *s = value;
    *ds = slope / (end - start);
}

/* x_hat <- x_hat + Lo (y - C x_hat); the first sample starts at rest at the encoders' theta - psi. */
static void correct(const pc_balance_params *p, pc_balance_state *st, const double y[PC_BALANCE_NY_MAX], double gyro)
{
    const int n = (int)p->n, ny = (int)p->ny;
    if (st->started == 0.0) {   /* psi unknown: 0 */
        const double full[PC_BALANCE_N_MAX] = {y[0], 0.0, y[2], 0.0, gyro, 0.0};
        for (int i = 0; i < n; ++i) st->x_hat[i] = full[(int)p->states[i]];
        st->started = 1.0;
    }
    double innovation[PC_BALANCE_NY_MAX];
    for (int k = 0; k < ny; ++k) {
        double acc = 0.0;
        for (int j = 0; j < n; ++j) acc += p->C[k][j] * st->x_hat[j];
        innovation[k] = y[k] - acc;
    }
    for (int i = 0; i < n; ++i) {
        double acc = 0.0;
        for (int k = 0; k < ny; ++k) acc += p->Lo[i][k] * innovation[k];
        st->x_hat[i] = st->x_hat[i] + acc;
    }
}

/* u = sat(-K (x_hat - x_ref)), then x_hat <- Ad x_hat + Bd u. */
static void command_and_predict(const pc_balance_params *p, pc_balance_state *st, const double ref[PC_BALANCE_N_MAX])
{
    const int n = (int)p->n;
    for (int k = 0; k < 2; ++k) {
        double acc = 0.0;
        for (int j = 0; j < n; ++j) acc += p->K[k][j] * (st->x_hat[j] - ref[(int)p->states[j]]);
        st->u[k] = fmin(fmax(-acc, -p->v_max), p->v_max);
    }
    double predicted[PC_BALANCE_N_MAX];
    for (int i = 0; i < n; ++i) {
        double acc = 0.0;
        for (int j = 0; j < n; ++j) acc += p->Ad[i][j] * st->x_hat[j];
        predicted[i] = acc + (p->Bd[i][0] * st->u[0] + p->Bd[i][1] * st->u[1]);
    }
    for (int i = 0; i < n; ++i) st->x_hat[i] = predicted[i];
}

int pc_balance_sample(pc_balance *b, double *x, double t, double limit, pc_refusal *r)
{
    for (int i = 0; i < PC_BALANCE_N_INPUTS; ++i) {
        if (!isfinite(x[i])) return pc_refuse(r, PC_BALANCE_BAD_INPUT, i, x[i]);
        if (!(fabs(x[i]) <= limit)) return pc_refuse(r, PC_BALANCE_INPUT_LIMIT, i, x[i]);
    }
    const pc_balance_params *p = &b->params;
    pc_balance_state *st = &b->state;
    const int code = check_layout(p, r);
    if (code != PC_OK) return code;
    const double enc_l = x[0], enc_r = x[1], gyro = x[2];
    const double y[PC_BALANCE_NY_MAX] = {0.5 * (enc_l + enc_r), gyro,
                                         p->yaw != 0.0 ? p->r_over_w * (enc_r - enc_l) : 0.0};
    correct(p, st, y, gyro);
    double s, ds, a, da;
    smooth_step(p, p->drive, t, &s, &ds);
    smooth_step(p, p->turning, t, &a, &da);
    const double R = p->radius;
    const double ref[PC_BALANCE_N_MAX] = {p->distance * s / R, 0.0, p->turn * a, p->distance * ds / R, 0.0,
                                          p->turn * da};
    command_and_predict(p, st, ref);
    double *out = x + PC_BALANCE_N_INPUTS;
    out[0] = st->u[0];
    out[1] = st->u[1];
    out[2] = p->gain * st->u[0];
    out[3] = p->gain * st->u[1];
    out[4] = p->distance * s;   /* x_d, y_d: the route starts along +x */
    out[5] = 0.0;
    double *hat = out + 6;
    for (int i = 0; i < PC_BALANCE_N_MAX; ++i) hat[i] = 0.0;
    for (int i = 0; i < (int)p->n; ++i) hat[(int)p->states[i]] = st->x_hat[i];
    return PC_OK;
}

int pc_balance_io(void *context, double *x, double t, double h, pc_refusal *r)
{
    (void)h;   /* a sampled controller: the sample time is its design's */
    const pc_balance_context *c = context;
    return pc_balance_sample(c->balance, x, t, c->limit, r);
}
