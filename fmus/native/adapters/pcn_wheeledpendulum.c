/* Native WheeledPendulum (fmus/slaves/parcosim_wheeledpendulum.py) over pc_wheeled_step.
 *
 * Every parameter works as in the pythonfmu FMU: the kernel's parameter struct is the
 * parameters themselves (plant.wheeled.pack), so nothing is fixed at build.  The checks and
 * messages are the slave's and plant.wheeled.WheeledPendulum's, in their order.
 * Model data (FMU state): pc_wheeled_params, then pc_wheeled_state.
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "model_config.h"
#include "pcn_model.h"
#include "wheeled.h"

#define ABSURD 1e6   /* fmus/slave/refusals.py */
#define TINY 1e-12
#define N_PARAMS 11
#define N_INITIAL 8
#define PI 3.14159265358979323846   /* math.pi */

typedef struct {
    pc_wheeled_params params;
    pc_wheeled_state state;
} pendulum;

/* Seed 000's parameters in WheeledParams' field order, and where each goes. */
static const char *const PARAM_NAMES[N_PARAMS] = {"g", "m", "R", "J_w", "M", "W", "D", "H", "L", "J_psi", "J_phi"};
static const int PARAM_SLOTS[N_PARAMS] = {PCN_SLOT_g, PCN_SLOT_m, PCN_SLOT_R, PCN_SLOT_J_w, PCN_SLOT_M, PCN_SLOT_W,
                                          PCN_SLOT_D, PCN_SLOT_H, PCN_SLOT_L, PCN_SLOT_J_psi, PCN_SLOT_J_phi};
static const int POSITIVE[N_PARAMS] = {0, 0, 1, 0, 1, 1, 0, 0, 1, 0, 0};
/* The initial-state parameters in the slave's INITIAL order. */
static const char *const INITIAL_NAMES[N_INITIAL] = {"theta0", "psi0", "phi0", "dtheta0", "dpsi0", "dphi0", "x0",
                                                     "y0"};
static const int INITIAL_SLOTS[N_INITIAL] = {PCN_SLOT_theta0, PCN_SLOT_psi0, PCN_SLOT_phi0, PCN_SLOT_dtheta0,
                                             PCN_SLOT_dpsi0, PCN_SLOT_dphi0, PCN_SLOT_x0, PCN_SLOT_y0};
static const char *const PUSH_NAMES[3] = {"push_torque", "push_start", "push_duration"};
static const int PUSH_SLOTS[3] = {PCN_SLOT_push_torque, PCN_SLOT_push_start, PCN_SLOT_push_duration};

static int not_finite(const double *r, const char *const *names, const int *slots, int n, pcn_text *why)
{
    for (int k = 0; k < n; ++k)
        if (!isfinite(r[slots[k]]))
            return pcn_addf(why, "parameter %s = %r is not finite", names[k], r[slots[k]]), 1;
    return 0;
}

static int absurd(const double *r, const char *const *names, const int *slots, int n, pcn_text *why)
{
    for (int k = 0; k < n; ++k)
        if (fabs(r[slots[k]]) > ABSURD)
            return pcn_addf(why, "parameter %s = %r is absurd: |%s| must be <= %G (SI units)", names[k], r[slots[k]],
                            names[k], ABSURD), 1;
    return 0;
}

/* The slave's setup checks up to the simulator's, and WheeledParams.validate. */
static int check_parameters(const pcn_instance *in, pcn_text *why)
{
    const double *r = in->real;
    if (not_finite(r, PARAM_NAMES, PARAM_SLOTS, N_PARAMS, why) ||
        not_finite(r, INITIAL_NAMES, INITIAL_SLOTS, N_INITIAL, why) || not_finite(r, PUSH_NAMES, PUSH_SLOTS, 3, why) ||
        absurd(r, PARAM_NAMES, PARAM_SLOTS, N_PARAMS, why) || absurd(r, PUSH_NAMES, PUSH_SLOTS, 3, why) ||
        absurd(r, INITIAL_NAMES, INITIAL_SLOTS, N_INITIAL, why))
        return 1;
    if (r[PCN_SLOT_push_duration] < 0.0)
        return pcn_addf(why, "parameter push_duration = %r s must be >= 0", r[PCN_SLOT_push_duration]), 1;
    for (int k = 0; k < N_PARAMS; ++k) {
        double v = r[PARAM_SLOTS[k]];
        if (POSITIVE[k] && 0.0 < v && v < TINY)
            return pcn_addf(why, "parameter %s = %r is absurdly small: it must be >= %G (SI units)", PARAM_NAMES[k], v,
                            TINY), 1;
    }
    for (int k = 0; k < N_PARAMS; ++k) {
        double v = r[PARAM_SLOTS[k]];
        if (POSITIVE[k] && !(v > 0.0)) return pcn_addf(why, "parameter %s = %r must be > 0", PARAM_NAMES[k], v), 1;
        if (v < 0.0) return pcn_addf(why, "parameter %s = %r must be >= 0", PARAM_NAMES[k], v), 1;
    }
    return 0;
}

/* plant.wheeled.pack: the kernel's parameters are the FMU's; nonzero when `model` is unknown. */
static int pack(const pcn_instance *in, pc_wheeled_params *p, pcn_text *why)
{
    const char *model = in->string[PCN_SLOT_model];
    if (strcmp(model, "exact") != 0 && strcmp(model, "seed") != 0)
        return pcn_addf(why, "model = '%s'; valid: exact, seed", model), 1;
    double *words = (double *)p;
    for (int k = 0; k < N_PARAMS; ++k) words[k] = in->real[PARAM_SLOTS[k]];
    p->nonholonomic = strcmp(model, "exact") == 0;
    p->yaw = in->boolean[PCN_SLOT_yaw] != 0;
    return 0;
}

static void publish(pcn_instance *in)
{
    const pendulum *pd = (const pendulum *)in->data;
    double out[PC_WHEELED_N_OUTPUTS];
    pc_wheeled_sensors(&pd->params, &pd->state, 2.0 * PI / in->integer[PCN_SLOT_encoder_counts], out);
    const int slots[PC_WHEELED_N_OUTPUTS] = {PCN_SLOT_theta, PCN_SLOT_psi, PCN_SLOT_phi, PCN_SLOT_dtheta,
                                             PCN_SLOT_dpsi, PCN_SLOT_dphi, PCN_SLOT_x, PCN_SLOT_y, PCN_SLOT_omega_l,
                                             PCN_SLOT_omega_r, PCN_SLOT_enc_l, PCN_SLOT_enc_r, PCN_SLOT_gyro,
                                             PCN_SLOT_energy};
    for (int k = 0; k < PC_WHEELED_N_OUTPUTS; ++k) in->real[slots[k]] = out[k];
}

static int setup(pcn_instance *in, pcn_text *why)
{
    pendulum pd;
    if (check_parameters(in, why) || pack(in, &pd.params, why)) return 1;
    int substeps = in->integer[PCN_SLOT_substeps], counts = in->integer[PCN_SLOT_encoder_counts];
    if (!(1 <= substeps && substeps <= PC_WHEELED_MAX_SUBSTEPS))
        return pcn_addf(why, "parameter substeps = %d must be an integer in [1, %d]", substeps,
                        PC_WHEELED_MAX_SUBSTEPS), 1;
    if (!(counts > 0)) return pcn_addf(why, "parameter encoder_counts = %d must be a positive integer", counts), 1;
    const double *r = in->real;
    pd.state = (pc_wheeled_state){.theta = r[PCN_SLOT_theta0], .psi = r[PCN_SLOT_psi0], .phi = r[PCN_SLOT_phi0],
                                  .x = r[PCN_SLOT_x0], .y = r[PCN_SLOT_y0], .dtheta = r[PCN_SLOT_dtheta0],
                                  .dpsi = r[PCN_SLOT_dpsi0], .dphi = r[PCN_SLOT_dphi0]};
    if (!in->boolean[PCN_SLOT_yaw] && pd.state.dphi != 0.0)
        return pcn_addf(why, "initial dphi0 = %r with the yaw locked (yaw = false) must be 0", pd.state.dphi), 1;
    pc_refusal refusal;
    int code = pc_wheeled_condition(&pd.params, &pd.state, &refusal);
    if (code != PC_OK) {    /* as plant.wheeled.initial_refusal, the entry named as its parameter */
        static const char *const entries[8] = {"theta0", "psi0", "phi0", "x0", "y0", "dtheta0", "dpsi0", "dphi0"};
        const int fell = code == PC_WHEELED_FALLEN_PITCH || code == PC_WHEELED_FALLEN_FLOOR;
        const char *reason = code == PC_WHEELED_FALLEN_PITCH   ? "fallen_pitch"
                             : code == PC_WHEELED_FALLEN_FLOOR ? "fallen_floor"
                                                               : "nonfinite_state";
        const int entry = fell ? 1 : (0 <= refusal.index && refusal.index < 8 ? refusal.index : 1);
        return pcn_addf(why, "initial %s = %r%s is no standing robot (%s)", entries[entry], refusal.value,
                        fell ? " rad" : "", reason), 1;
    }
    memcpy(in->data, &pd, sizeof pd);
    publish(in);
    return 0;
}

static int step(pcn_instance *in, double t, double h, pcn_text *why)
{
    static const char *const inputs[3] = {"tau_l", "tau_r", "tau_d"};
    double *r = in->real, tau[3] = {r[PCN_SLOT_tau_l], r[PCN_SLOT_tau_r], r[PCN_SLOT_tau_d]};
    for (int k = 0; k < 3; ++k)
        if (fabs(tau[k]) > ABSURD)
            return pcn_addf(pcn_timed(why), "input %s = %r at t = %G s is absurd: |%s| must be <= %G", inputs[k],
                            tau[k], t, inputs[k], ABSURD), 1;
    double start = r[PCN_SLOT_push_start], duration = r[PCN_SLOT_push_duration];
    if (start - 1e-9 <= t && t < start + duration - 1e-9) tau[2] += r[PCN_SLOT_push_torque];
    pendulum *pd = (pendulum *)in->data;
    int substeps = in->integer[PCN_SLOT_substeps], taken = 0;
    pc_refusal refusal;
    int code = pc_wheeled_step(&pd->params, &pd->state, tau[0], tau[1], tau[2], h, substeps, &taken, &refusal);
    if (code == PC_OK) {
        publish(in);
        return 0;
    }
    /* plant.wheeled.REASONS */
    static const char *const states[8] = {"theta", "psi", "phi", "x", "y", "dtheta", "dpsi", "dphi"};
    if (code == PC_WHEELED_BAD_INPUT) {
        pcn_quantify(why, code, "input_not_finite", inputs[refusal.index], refusal.value, "N m", t);
        return pcn_addf(pcn_timed(why), "input %s = %r at t = %G s is not finite", inputs[refusal.index], refusal.value,
                        t), 1;
    }
    if (code != PC_WHEELED_FALLEN_PITCH && code != PC_WHEELED_FALLEN_FLOOR && code != PC_WHEELED_NONFINITE) {
        if (code == PC_WHEELED_BAD_STEP) pcn_quantify(why, code, "bad_step", "dt", refusal.value, "s", t);
        return pcn_addf(pcn_timed(why), "step size %r at t = %G s must be > 0", h, t), 1;
    }
    in->boolean[PCN_SLOT_fallen] = 1;
    double end = t + h * taken / substeps;
    char degrees[32];
    snprintf(degrees, sizeof degrees, "%.4g", pd->state.psi * (180.0 / PI));
    const char *what = code == PC_WHEELED_FALLEN_PITCH   ? "the robot fell over (pitch beyond 90 degrees)"
                       : code == PC_WHEELED_FALLEN_FLOOR ? "the robot fell over (body touching the floor)"
                                                         : "the state became non-finite";
    if (code == PC_WHEELED_NONFINITE)
        pcn_quantify(why, code, "nonfinite_state", states[refusal.index], refusal.value, "", end);
    else
        pcn_quantify(why, code, code == PC_WHEELED_FALLEN_PITCH ? "fallen_pitch" : "fallen_floor", "psi", refusal.value,
                     "rad", end);
    return pcn_addf(pcn_timed(why), "%s at t = %G s: psi = %s deg at the last good state", what, end, degrees), 1;
}

/* Restored data: the parameter words are the instance's parameters (or all zero, before set-up). */
static int check_data(const pcn_instance *in, const double *data, pcn_text *why)
{
    int zero = 1;
    for (size_t k = 0; k < sizeof(pendulum) / sizeof(double); ++k) zero &= data[k] == 0.0;
    if (zero) return 0;
    pc_wheeled_params p;
    pcn_text ignored;
    pcn_clear(&ignored);
    if (pack(in, &p, &ignored) || memcmp(&p, data, sizeof p) != 0)
        return pcn_addf(why, "the pendulum's parameter words differ from this instance's parameters"), 1;
    return 0;
}

const pcn_model pcn_this_model = {
    .identifier = PCN_IDENTIFIER,
    .accepted_steps = "any step size h with 1e-09 s <= h and t + h <= 1e+09 s",
    .data_words = sizeof(pendulum) / sizeof(double),
    .scratch_words = 0,
    .setup = setup,
    .step = step,
    .check_data = check_data,
};
