/* The two-wheeled inverted pendulum of seed 000: equations in wheeled.h. */
#include "wheeled.h"

#include <string.h>

#include "pc_rk4.h"

const int pc_wheeled_max_substeps = PC_WHEELED_MAX_SUBSTEPS;

const pc_field pc_wheeled_params_fields[] = {
    PC_FIELD(pc_wheeled_params, g), PC_FIELD(pc_wheeled_params, m), PC_FIELD(pc_wheeled_params, R),
    PC_FIELD(pc_wheeled_params, J_w), PC_FIELD(pc_wheeled_params, M), PC_FIELD(pc_wheeled_params, W),
    PC_FIELD(pc_wheeled_params, D), PC_FIELD(pc_wheeled_params, H), PC_FIELD(pc_wheeled_params, L),
    PC_FIELD(pc_wheeled_params, J_psi), PC_FIELD(pc_wheeled_params, J_phi),
    PC_FIELD(pc_wheeled_params, nonholonomic), PC_FIELD(pc_wheeled_params, yaw), {0, 0, 0}};

const pc_field pc_wheeled_state_fields[] = {
    PC_FIELD(pc_wheeled_state, theta), PC_FIELD(pc_wheeled_state, psi), PC_FIELD(pc_wheeled_state, phi),
    PC_FIELD(pc_wheeled_state, x), PC_FIELD(pc_wheeled_state, y), PC_FIELD(pc_wheeled_state, dtheta),
    PC_FIELD(pc_wheeled_state, dpsi), PC_FIELD(pc_wheeled_state, dphi), {0, 0, 0}};

const pc_field pc_wheeled_settings_fields[] = {
    PC_FIELD(pc_wheeled_settings, substeps), PC_FIELD(pc_wheeled_settings, count),
    PC_FIELD(pc_wheeled_settings, push_torque), PC_FIELD(pc_wheeled_settings, push_start),
    PC_FIELD(pc_wheeled_settings, push_duration), PC_FIELD(pc_wheeled_settings, limit), {0, 0, 0}};

/* The state as the vector RK4 advances (a struct of 8 doubles, no padding). */
enum { THETA, PSI, PHI, X, Y, DTHETA, DPSI, DPHI };

static const double HALF_PI = 1.57079632679489661923;   /* M_PI is not C11 */

/* The right-hand side's model: the parameters and the held torques. */
typedef struct {
    const pc_wheeled_params *p;
    double tau_l, tau_r, tau_d;
} held_torques;

/* (17)-(20) solved for nu'': the (theta, psi) block by Cramer's rule, the yaw row apart. */
void pc_wheeled_derivative(const pc_wheeled_params *p, const double *y, double tau_l, double tau_r,
                           double tau_d, double *dydt)
{
    const double s = sin(y[PSI]), c = cos(y[PSI]);
    const double dth = y[DTHETA], dps = y[DPSI], dph = y[DPHI];
    const double mb = p->M, R = p->R, L = p->L, k = p->nonholonomic;
    const double m11 = (2.0 * p->m + mb) * R * R + 2.0 * p->J_w;
    const double m12 = mb * R * L * c;
    const double m22 = mb * L * L + p->J_psi;
    const double c1 = -mb * R * L * s * dps * dps - k * mb * L * R * s * dph * dph;
    const double c2 = -mb * L * L * s * c * dph * dph;
    const double g2 = -mb * p->g * L * s;
    const double f = tau_l + tau_r;
    const double r1 = f - c1;
    const double r2 = -f + tau_d - c2 - g2;
    const double det = m11 * m22 - m12 * m12;
    dydt[THETA] = dth;
    dydt[PSI] = dps;
    dydt[PHI] = dph;
    dydt[X] = R * dth * cos(y[PHI]);   /* (2) */
    dydt[Y] = R * dth * sin(y[PHI]);
    dydt[DTHETA] = (m22 * r1 - m12 * r2) / det;
    dydt[DPSI] = (m11 * r2 - m12 * r1) / det;
    if (p->yaw != 0.0) {
        const double W = p->W;
        const double m33 = 0.5 * p->m * W * W + mb * L * L * s * s + p->J_phi + W * W / (2.0 * R * R) * p->J_w;
        const double c3 = 2.0 * mb * L * L * s * c * dps * dph + k * mb * L * R * s * dth * dph;
        dydt[DPHI] = (W / (2.0 * R) * (tau_r - tau_l) - c3) / m33;
    } else {
        dydt[DPHI] = 0.0;
    }
}

static void held_derivative(const void *model, const double *y, double *dydt)
{
    const held_torques *h = model;
    pc_wheeled_derivative(h->p, y, h->tau_l, h->tau_r, h->tau_d, dydt);
}

/* A box of depth D and height H standing on the axle (at height R), tilted by psi. */
double pc_wheeled_lowest_body_point(const pc_wheeled_params *p, double psi)
{
    return p->R + fmin(0.0, p->H * cos(psi)) - 0.5 * p->D * fabs(sin(psi));
}

static int condition_of(const pc_wheeled_params *p, const double *y, pc_refusal *r)
{
    for (int i = 0; i < PC_WHEELED_N_STATE; ++i)
        if (!isfinite(y[i])) return pc_refuse(r, PC_WHEELED_NONFINITE, i, y[i]);
    if (fabs(y[PSI]) >= HALF_PI) return pc_refuse(r, PC_WHEELED_FALLEN_PITCH, 0, y[PSI]);
    if (pc_wheeled_lowest_body_point(p, y[PSI]) <= 0.0) return pc_refuse(r, PC_WHEELED_FALLEN_FLOOR, 0, y[PSI]);
    return PC_OK;
}

int pc_wheeled_condition(const pc_wheeled_params *p, const pc_wheeled_state *s, pc_refusal *r)
{
    return condition_of(p, &s->theta, r);
}

int pc_wheeled_step(const pc_wheeled_params *p, pc_wheeled_state *s, double tau_l, double tau_r, double tau_d,
                    double dt, int substeps, int *taken, pc_refusal *r)
{
    const double tau[3] = {tau_l, tau_r, tau_d};
    for (int i = 0; i < 3; ++i)
        if (!isfinite(tau[i])) return pc_refuse(r, PC_WHEELED_BAD_INPUT, i, tau[i]);
    if (!(isfinite(dt) && dt > 0.0)) return pc_refuse(r, PC_WHEELED_BAD_STEP, 0, dt);
    if (substeps < 1 || substeps > PC_WHEELED_MAX_SUBSTEPS) return pc_refuse(r, PC_WHEELED_BAD_SETTING, 0, substeps);
    const held_torques model = {p, tau_l, tau_r, tau_d};
    double z[PC_WHEELED_N_STATE], work[5 * PC_WHEELED_N_STATE];   /* fixed size: the stack is scratch enough */
    memcpy(z, &s->theta, sizeof z);
    /* one substep at a time: a fall is caught at the substep where it happens */
    for (int n = 0; n < substeps; ++n) {
        pc_rk4(held_derivative, &model, z, PC_WHEELED_N_STATE, dt / substeps, 1, work);
        const int code = condition_of(p, z, r);
        if (code != PC_OK) {
            if (taken) *taken = n + 1;
            return code;
        }
    }
    memcpy(&s->theta, z, sizeof z);
    if (taken) *taken = substeps;
    return PC_OK;
}

double pc_wheeled_energy(const pc_wheeled_params *p, const pc_wheeled_state *st)
{
    const double s = sin(st->psi), c = cos(st->psi);
    const double dth = st->dtheta, dps = st->dpsi, dph = st->dphi;
    const double mb = p->M, R = p->R, L = p->L, W = p->W;
    const double t1 = 0.5 * (p->m * (2.0 * R * R * dth * dth + 0.5 * W * W * dph * dph)
                             + mb * (R * R * dth * dth + L * L * dps * dps + L * L * s * s * dph * dph
                                     + 2.0 * R * L * c * dth * dps));
    const double t2 = p->J_w * dth * dth + 0.5 * p->J_psi * dps * dps
                      + 0.5 * (p->J_phi + W * W / (2.0 * R * R) * p->J_w) * dph * dph;
    const double u = 2.0 * p->m * p->g * R + mb * p->g * (R + L * c);
    return t1 + t2 + u;
}

void pc_wheeled_sensors(const pc_wheeled_params *p, const pc_wheeled_state *s, double count, double *out)
{
    const double half = p->W / (2.0 * p->R);
    const double enc_l = s->theta - half * s->phi - s->psi;   /* (10), relative to the body */
    const double enc_r = s->theta + half * s->phi - s->psi;
    out[0] = s->theta;
    out[1] = s->psi;
    out[2] = s->phi;
    out[3] = s->dtheta;
    out[4] = s->dpsi;
    out[5] = s->dphi;
    out[6] = s->x;
    out[7] = s->y;
    out[8] = s->dtheta - half * s->dphi - s->dpsi;
    out[9] = s->dtheta + half * s->dphi - s->dpsi;
    out[10] = count * floor(enc_l / count + 0.5);
    out[11] = count * floor(enc_r / count + 0.5);
    out[12] = s->dpsi;
    out[13] = pc_wheeled_energy(p, s);
}

int pc_wheeled_step_io(const pc_wheeled_params *p, pc_wheeled_state *s, const pc_wheeled_settings *settings,
                       double *x, double t, double h, pc_refusal *r)
{
    for (int i = 0; i < 3; ++i) {
        if (!isfinite(x[i])) return pc_refuse(r, PC_WHEELED_BAD_INPUT, i, x[i]);
        if (!(fabs(x[i]) <= settings->limit)) return pc_refuse(r, PC_WHEELED_INPUT_LIMIT, i, x[i]);
    }
    /* the settings are words of a buffer: a forged substep count or count is refused, not cast */
    const double substeps = settings->substeps;
    if (!(substeps >= 1.0 && substeps <= PC_WHEELED_MAX_SUBSTEPS && substeps == floor(substeps)))
        return pc_refuse(r, PC_WHEELED_BAD_SETTING, 0, substeps);
    if (!(settings->count > 0.0 && isfinite(settings->count)))
        return pc_refuse(r, PC_WHEELED_BAD_SETTING, 1, settings->count);
    double tau_d = x[2];
    const double start = settings->push_start;
    if (start - 1e-9 <= t && t < start + settings->push_duration - 1e-9)   /* 1e-9 s: rounding of t */
        tau_d += settings->push_torque;
    const int code = pc_wheeled_step(p, s, x[0], x[1], tau_d, h, (int)substeps, NULL, r);
    if (code != PC_OK) return code;
    pc_wheeled_sensors(p, s, settings->count, x + 3);
    return PC_OK;
}

int pc_wheeled_io(void *context, double *x, double t, double h, pc_refusal *r)
{
    const pc_wheeled_context *c = context;
    return pc_wheeled_step_io(c->params, c->state, c->settings, x, t, h, r);
}
