/* A DC motor drive with DCMotorDrive's interface, written in C from docs/motor.md
   ("The drive's computation, step by step") alone: the test's foreign FMU.

   Supports the presets' current controllers (fixed coefficients: changing R, L, kt, ke
   or b in current mode is refused), current and voltage mode, the exact electrics,
   torque_output "end" and "mean".  No J_design, b_design or method parameters. */
#define NR 18
#define NI 0
#define NB 0
#define NS 3

enum { I_REF, V_REF, OMEGA, I_HAT, TAU, V, I, R_, L_, KT, KE, B_, MU, V_MAX, OMEGA_EPS, T_, OMEGA0, I0 };
enum { PRESET, MODE, TORQUE_OUTPUT };

struct Model {
    double R, L, kt, ke, b, mu, v_max, omega_eps;
    double alpha, beta, gamma, delta;
    int current_mode, mean;
    double u1, u2, e1, e2, i;
    int steps_per_sample, phase;
};

#define START_R {0, 0, 0, 0, 0, 0, 0, -1, -1, -1, -1, -1, -1, -1, -1, 1e-3, 0, 0}
#define START_I {0}
#define START_B {0}
#define START_S {"motor1", "current", "end"}

#include "skeleton.h"

/* Table 16 / Table 18, then alpha, beta, gamma, delta of the current controller. */
static const double PRESETS[2][12] = {
    {1.101, 0.000667, 0.05598, 0.05138, 0.0001226, 0.04357, 24.0, 0.5,
     1.2001839318004226, -1.2984158805745907, 0.26249878741314603, 0.999163808625058},
    {0.829, 0.000667, 0.05666, 0.052, 0.0002039, 0.04992, 24.0, 0.5,
     1.139387003682184, -1.3361737896889487, 0.33714761017284567, 0.9989179745656754},
};

static const char *NAMES[8] = {"R", "L", "kt", "ke", "b", "mu", "v_max", "omega_eps"};

static double saturate(double v, double v_max) { return v < -v_max ? -v_max : (v > v_max ? v_max : v); }

static double torque(const struct Model *m, double current, double omega) {
    return m->kt * current - m->b * omega - m->mu * tanh(omega / m->omega_eps);
}

static int model_exit_init(Instance *inst) {
    struct Model *m = &inst->m;
    double *p;
    const double *preset;
    int k;
    if (strcmp(inst->s[PRESET], "motor1") == 0) preset = PRESETS[0];
    else if (strcmp(inst->s[PRESET], "motor2") == 0) preset = PRESETS[1];
    else {
        snprintf(inst->message, sizeof inst->message, "parameter preset = '%s': not 'motor1' or 'motor2'",
                 inst->s[PRESET]);
        return 1;
    }
    if (strcmp(inst->s[MODE], "current") && strcmp(inst->s[MODE], "voltage")) {
        snprintf(inst->message, sizeof inst->message, "parameter mode = '%s': not 'current' or 'voltage'",
                 inst->s[MODE]);
        return 1;
    }
    if (strcmp(inst->s[TORQUE_OUTPUT], "end") && strcmp(inst->s[TORQUE_OUTPUT], "mean")) {
        snprintf(inst->message, sizeof inst->message, "parameter torque_output = '%s': not 'end' or 'mean'",
                 inst->s[TORQUE_OUTPUT]);
        return 1;
    }
    m->current_mode = strcmp(inst->s[MODE], "current") == 0;
    m->mean = strcmp(inst->s[TORQUE_OUTPUT], "mean") == 0;
    p = &m->R;   /* R, L, kt, ke, b, mu, v_max, omega_eps: -1 = the preset's value */
    for (k = 0; k < 8; k++) {
        double value = inst->r[R_ + k];
        if (value != -1.0 && !(value >= 0.0)) {
            snprintf(inst->message, sizeof inst->message, "parameter %s = %g is negative (use -1 for the preset's "
                     "value)", NAMES[k], value);
            return 1;
        }
        if (value != -1.0 && m->current_mode && k < 5 && value != preset[k]) {
            snprintf(inst->message, sizeof inst->message, "this drive's current controller is the preset's: "
                     "R, L, kt, ke and b cannot be changed in current mode");
            return 1;
        }
        p[k] = value == -1.0 ? preset[k] : value;
    }
    m->alpha = preset[8]; m->beta = preset[9]; m->gamma = preset[10]; m->delta = preset[11];
    m->i = inst->r[I0];
    m->u1 = m->u2 = saturate(m->R * inst->r[I0] + m->ke * inst->r[OMEGA0], m->v_max);
    m->e1 = m->e2 = 0.0;
    m->phase = 0;
    m->steps_per_sample = 0;
    inst->r[I] = m->i;
    inst->r[V] = m->u1;
    inst->r[TAU] = torque(m, m->i, inst->r[OMEGA0]);
    return 0;
}

static int model_do_step(Instance *inst, fmi2Real t, fmi2Real h) {
    struct Model *m = &inst->m;
    double omega = inst->r[OMEGA], v, x, a, g, u, current, i_next;
    if (!isfinite(inst->r[I_REF]) || !isfinite(inst->r[V_REF]) || !isfinite(omega) || !isfinite(inst->r[I_HAT])) {
        snprintf(inst->message, sizeof inst->message, "an input is not finite (step from t = %g s)", t);
        return 1;
    }
    if (m->current_mode) {
        double n = inst->r[T_] / h;
        if (n < 1.0 - 1e-6 || fabs(n - floor(n + 0.5)) > 1e-6 * n) {
            snprintf(inst->message, sizeof inst->message, "the step %g s must divide T = %g s (t = %g s)",
                     h, inst->r[T_], t);
            return 1;
        }
        m->steps_per_sample = (int)floor(n + 0.5);
        if (m->phase == 0) {
            double e = inst->r[I_REF] - inst->r[I_HAT];
            v = (1.0 + m->delta) * m->u1 - m->delta * m->u2 + m->alpha * e + m->beta * m->e1 + m->gamma * m->e2;
            v = saturate(v, m->v_max);
            m->u2 = m->u1; m->u1 = v;
            m->e2 = m->e1; m->e1 = e;
        } else {
            v = m->u1;
        }
        m->phase = (m->phase + 1) % m->steps_per_sample;
    } else {
        v = saturate(inst->r[V_REF], m->v_max);
    }
    x = m->R * h / m->L;
    a = exp(-x);
    g = -expm1(-x) / m->R;
    u = v - m->ke * omega;
    i_next = a * m->i + g * u;
    if (m->mean) {
        double w_i = -expm1(-x) / x;
        double w_u = (1.0 - w_i) / m->R;
        current = w_i * m->i + w_u * u;
    } else {
        current = i_next;
    }
    m->i = i_next;
    inst->r[V] = v;
    inst->r[I] = i_next;
    inst->r[TAU] = torque(m, current, omega);
    return 0;
}

static void model_outputs(Instance *inst) { (void)inst; }
