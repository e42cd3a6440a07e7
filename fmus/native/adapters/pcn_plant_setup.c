/* The 5R plant's set-up and refusals (pcn_plant_setup.h). */
#include "pcn_plant_setup.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "kinematics5r.h"
#include "model5r.h"
#include "model_config.h"

#define ABSURD 1e6             /* fmus/slave/refusals.py */
#define TINY 1e-12
#define PRESET_VALUE (-1.0)
#define PI 3.14159265358979323846   /* math.pi */
#define MAX_SUBSTEPS 10000     /* plant/simulator.py */
#define RESIDUAL_STOP 1e-3
#define SINGULAR_STOP 1e-3
#define BAUMGARTE_RK4_LIMIT 2.0
#define RK4_REAL_STABILITY 2.785293563405282
#define COUNTER_REACH 10.0     /* plant/presets.py */
#define CHAIN_FIELDS 9         /* plant.presets.ChainParams: l1 .. J_rotor (models.py packs them so) */
#define N_NUMERIC 10

/* Python's format(x, ".<digits>g") (C's, without C's sign of a NaN). */
static const char *g(double x, int digits, char *out, size_t size)
{
    if (isnan(x)) snprintf(out, size, "nan");
    else snprintf(out, size, "%.*g", digits, x);
    return out;
}

static int not_finite(const char *name, double v, pcn_text *why)
{
    if (isfinite(v)) return 0;
    pcn_addf(why, "%s = %r is not finite", name, v);
    return 1;
}

static int absurd(const char *name, double v, pcn_text *why)
{
    if (!(isfinite(v) && fabs(v) > ABSURD)) return 0;
    pcn_addf(why, "parameter %s = %r is absurd: |%s| must be <= %G (SI units)", name, v, name, ABSURD);
    return 1;
}

/* The preset's chains (9 words each, ChainParams' order); NULL (why written) if unknown. */
static const double *preset(const pcn_instance *in, pcn_text *why)
{
    const char *name = in->string[PCN_SLOT_preset];
    for (int k = 0; k < PCN_PLANT_PRESET_NAMES_COUNT; ++k)
        if (strcmp(name, pcn_plant_preset_names[k]) == 0) return pcn_plant_preset_chains + 2 * CHAIN_FIELDS * k;
    pcn_addf(why, "preset: unknown preset '%s'; valid: ", name);
    for (int k = 0; k < PCN_PLANT_PRESET_NAMES_COUNT; ++k) pcn_addf(why, k ? ", %s" : "%s", pcn_plant_preset_names[k]);
    return NULL;
}

/* fmus.slave.declarations._chain_overrides: chain k's (1, 2) fields with chain<k>_<field> unless -1. */
static int chain_overrides(const pcn_instance *in, int k, double chain[CHAIN_FIELDS], pcn_text *why)
{
    static const char *const fields[8] = {"l1", "l2", "lg1", "lg2", "m1", "m2", "Jz1", "Jz2"};
    const int slots[2][8] = {
        {PCN_SLOT_chain1_l1, PCN_SLOT_chain1_l2, PCN_SLOT_chain1_lg1, PCN_SLOT_chain1_lg2, PCN_SLOT_chain1_m1,
         PCN_SLOT_chain1_m2, PCN_SLOT_chain1_Jz1, PCN_SLOT_chain1_Jz2},
        {PCN_SLOT_chain2_l1, PCN_SLOT_chain2_l2, PCN_SLOT_chain2_lg1, PCN_SLOT_chain2_lg2, PCN_SLOT_chain2_m1,
         PCN_SLOT_chain2_m2, PCN_SLOT_chain2_Jz1, PCN_SLOT_chain2_Jz2}};
    char name[32];
    for (int f = 0; f < 8; ++f) {
        const double v = in->real[slots[k - 1][f]];
        if (v == PRESET_VALUE) continue;
        snprintf(name, sizeof name, "chain%d_%s", k, fields[f]);
        if (not_finite(name, v, why) || absurd(name, v, why)) return 1;
        const int length = f < 2;
        if (v < 0.0 || (length && v < TINY))
            return pcn_addf(why, "parameter %s = %r must be %s (or -1 for the preset's value)", name, v,
                            length ? "> 0" : ">= 0"), 1;
        chain[f] = v;
    }
    return 0;
}

/* The kernel's chain of the fields l1 .. J_rotor. */
static pc_fivebar_chain chain_of(const double c[CHAIN_FIELDS])
{
    return (pc_fivebar_chain){.l1 = c[0], .l2 = c[1], .lg1 = c[2], .lg2 = c[3], .m1 = c[4], .m2 = c[5], .Jz1 = c[6],
                              .Jz2 = c[7], .J_rotor = c[8]};
}

/* fmus.slave.declarations.with_counter_masses: checked, named as the FMU's variables. */
static int counter_masses(const pcn_instance *in, double chains[2][CHAIN_FIELDS], double M[2], pcn_text *why)
{
    static const char *const names[2] = {"counter_mass1", "counter_mass2"};
    M[0] = in->real[PCN_SLOT_counter_mass1];
    M[1] = in->real[PCN_SLOT_counter_mass2];
    for (int j = 0; j < 2; ++j)
        if (not_finite(names[j], M[j], why)) return 1;
    for (int j = 0; j < 2; ++j)
        if (absurd(names[j], M[j], why)) return 1;
    for (int j = 0; j < 2; ++j)
        if (M[j] < 0.0) return pcn_addf(why, "parameter %s = %r kg must be >= 0", names[j], M[j]), 1;
    char a[32], b[32];
    for (int k = 0; k < 2; ++k) {   /* FiveBarParams.check_counter_masses */
        const double *c = chains[k], reach = COUNTER_REACH * (c[0] + c[1]);
        double L[2];
        const pc_fivebar_chain chain = chain_of(c);
        pc_model5r_counter_offsets(&chain, M[0], M[1], L);   /* plant.presets.ChainParams.counter_offsets */
        for (int j = 0; j < 2; ++j)
            if (fabs(L[j]) > reach)
                return pcn_addf(why, "parameter %s = %r kg is too light to balance chain %d: it would sit %s m behind "
                                "its joint, more than %G times the chain's length (%s m)", names[j], M[j], k + 1,
                                g(fabs(L[j]), 3, a, sizeof a), COUNTER_REACH, g(reach, 3, b, sizeof b)), 1;
    }
    return 0;
}

/* FiveBarParams.validate beyond what the checks before it leave possible. */
static int validate_params(const double *r, const double chains[2][CHAIN_FIELDS], const double M[2], pcn_text *why)
{
    const double l0 = r[PCN_SLOT_l0], m0 = r[PCN_SLOT_m0];
    if (l0 <= 0.0) return pcn_addf(why, "l0 must be > 0, got %r", l0), 1;
    if (m0 < 0.0) return pcn_addf(why, "m0 must be >= 0, got %r", m0), 1;
    if (2.0 * l0 >= chains[0][0] + chains[0][1] + chains[1][0] + chains[1][1])
        return pcn_addf(why, "links cannot close the loop: base distance 2*l0 = %G m exceeds the reach of both "
                        "chains together", 2.0 * l0), 1;
    if (m0 > 0.0 && M[0] + M[1] > 0.0)
        return pcn_addf(why, "m0 = %r kg with counter-masses (counter_mass1/counter_mass2 > 0): the counter-masses "
                        "balance each chain without an end-effector mass (seed 001 (64)), so the pair is refused; "
                        "set m0 = 0 or both counter-masses to 0", m0), 1;
    return 0;
}

/* IntegratorSettings.validate, then what has no C here (refused by name). */
static int validate_settings(const pcn_instance *in, pcn_text *why)
{
    const char *method = in->string[PCN_SLOT_method], *kernel = in->string[PCN_SLOT_kernel];
    const int substeps = in->integer[PCN_SLOT_substeps];
    if (strcmp(method, "rk4") != 0 && strcmp(method, "dopri5") != 0)
        return pcn_addf(why, "method: unknown integrator '%s'; valid: rk4, dopri5", method), 1;
    if (strcmp(kernel, "fast") != 0 && strcmp(kernel, "general") != 0)
        return pcn_addf(why, "kernel: unknown kernel '%s'; valid: fast, general", kernel), 1;
    if (!(1 <= substeps && substeps <= MAX_SUBSTEPS))
        return pcn_addf(why, "substeps must be an integer in [1, %d], got %d", MAX_SUBSTEPS, substeps), 1;
    const char *names[2] = {"rtol", "atol"};
    const double values[2] = {in->real[PCN_SLOT_rtol], in->real[PCN_SLOT_atol]};
    for (int k = 0; k < 2; ++k)
        if (!(values[k] > 0.0)) return pcn_addf(why, "%s must be > 0, got %r", names[k], values[k]), 1;
    const double baumgarte = in->real[PCN_SLOT_baumgarte];
    if (!(baumgarte >= 0.0)) return pcn_addf(why, "baumgarte must be >= 0, got %r", baumgarte), 1;
    if (strcmp(method, "rk4") != 0)
        return pcn_addf(why, "parameter method = '%s': the native %s integrates with 'rk4' only (dopri5 has no C "
                        "implementation); use the pythonfmu %s for dopri5", method, PCN_IDENTIFIER,
                        PCN_IDENTIFIER), 1;
    if (strcmp(kernel, "fast") != 0)
        return pcn_addf(why, "parameter kernel = '%s': the native %s computes with kernel 'fast' only (the general "
                        "algorithm has no C implementation); use the pythonfmu %s for kernel 'general'", kernel,
                        PCN_IDENTIFIER, PCN_IDENTIFIER), 1;
    return 0;
}

/* PlantSimulator.__init__'s start at rest at (x0, y0): q of thesis_coordinates, dq = 0. */
static int start_at_rest(const pcn_instance *in, const pc_fivebar_params *p, double y[PCN_PLANT_STATES],
                         pcn_text *why)
{
    const double x0 = in->real[PCN_SLOT_x0], y0 = in->real[PCN_SLOT_y0];
    if (!(isfinite(x0) && isfinite(y0)))
        return pcn_addf(why, "start point x0=%r, y0=%r: point (%r, %r) is not finite", x0, y0, x0, y0), 1;
    const pc_5r_geometry geometry = {p->l0, p->chain[0].l1, p->chain[0].l2, p->chain[1].l1, p->chain[1].l2};
    double angles[4], distance = 0.0;
    if (pc_5r_inverse(&geometry, x0, y0, angles, &distance) != PC_5R_OK)
        return pcn_addf(why, "start point x0=%r, y0=%r: point (x=%G, y=%G) is outside the workspace: point out of "
                        "reach of a chain (distance %G m)", x0, y0, x0, y0, distance), 1;
    const double margin = pc_5r_margin(angles);
    char text[32];
    if (margin < SINGULAR_STOP)
        return pcn_addf(why, "start point x0=%r, y0=%r is singular (margin %s)", x0, y0,
                        g(margin, 3, text, sizeof text)), 1;
    const double th21 = PI - angles[2];
    const double q[7] = {x0, y0, 0.0, angles[0], angles[1] - angles[0], th21, (PI - angles[3]) - th21};
    for (int k = 0; k < 7; ++k) {
        y[k] = q[k];
        y[7 + k] = 0.0;
    }
    return 0;
}

int pcn_plant_setup(const pcn_instance *in, pcn_plant_config *c, double y[PCN_PLANT_STATES], pcn_text *why)
{
    const double *r = in->real;
    const double *from = preset(in, why);
    if (from == NULL) return 1;
    static const char *const numeric[N_NUMERIC] = {"J_rotor1", "J_rotor2", "m0", "l0", "gravity_x", "gravity_y",
                                                    "gravity_z", "baumgarte", "rtol", "atol"};
    const int slots[N_NUMERIC] = {PCN_SLOT_J_rotor1, PCN_SLOT_J_rotor2, PCN_SLOT_m0, PCN_SLOT_l0,
                                  PCN_SLOT_gravity_x, PCN_SLOT_gravity_y, PCN_SLOT_gravity_z, PCN_SLOT_baumgarte,
                                  PCN_SLOT_rtol, PCN_SLOT_atol};
    for (int k = 0; k < N_NUMERIC; ++k)
        if (not_finite(numeric[k], r[slots[k]], why)) return 1;
    for (int k = 0; k < N_NUMERIC; ++k)
        if (absurd(numeric[k], r[slots[k]], why)) return 1;
    if (0.0 < r[PCN_SLOT_l0] && r[PCN_SLOT_l0] < TINY)
        return pcn_addf(why, "parameter l0 = %r is absurdly small: it must be >= %G (SI units)", r[PCN_SLOT_l0],
                        TINY), 1;
    double chains[2][CHAIN_FIELDS], M[2];
    for (int k = 0; k < 2; ++k) {
        memcpy(chains[k], from + CHAIN_FIELDS * k, sizeof chains[k]);
        const double J = r[k ? PCN_SLOT_J_rotor2 : PCN_SLOT_J_rotor1];
        if (J < 0.0 && J != PRESET_VALUE)
            return pcn_addf(why, "%s = %r must be >= 0 (or -1 for the preset's value)", numeric[k], J), 1;
    }
    for (int k = 0; k < 2; ++k) {
        const double J = r[k ? PCN_SLOT_J_rotor2 : PCN_SLOT_J_rotor1];
        if (J != PRESET_VALUE) chains[k][8] = J;
    }
    if (chain_overrides(in, 1, chains[0], why) || chain_overrides(in, 2, chains[1], why) ||
        counter_masses(in, chains, M, why))
        return 1;
    static const char *const offsets[2] = {"encoder_offset1", "encoder_offset2"};
    const double offset[2] = {r[PCN_SLOT_encoder_offset1], r[PCN_SLOT_encoder_offset2]};
    for (int k = 0; k < 2; ++k)
        if (not_finite(offsets[k], offset[k], why)) return 1;
    for (int k = 0; k < 2; ++k)
        if (absurd(offsets[k], offset[k], why)) return 1;
    if (validate_params(r, (const double(*)[CHAIN_FIELDS])chains, M, why) || validate_settings(in, why)) return 1;
    const int counts = in->integer[PCN_SLOT_encoder_counts];
    if (!(counts > 0)) return pcn_addf(why, "encoder_counts must be a positive integer, got %d", counts), 1;
    if (!in->boolean[PCN_SLOT_link_inertias])
        for (int k = 0; k < 2; ++k) chains[k][6] = chains[k][7] = 0.0;
    memset(c, 0, sizeof *c);
    c->params.l0 = r[PCN_SLOT_l0];
    c->params.m0 = r[PCN_SLOT_m0];
    c->params.gravity[0] = r[PCN_SLOT_gravity_x];
    c->params.gravity[1] = r[PCN_SLOT_gravity_y];
    for (int k = 0; k < 2; ++k) {   /* plant.fast5r._pack_chain */
        c->params.chain[k] = chain_of(chains[k]);
        pc_model5r_pack_chain(&c->params.chain[k], M[0], M[1]);
    }
    c->settings = (pc_fivebar_settings){.lambda = r[PCN_SLOT_baumgarte], .substeps = in->integer[PCN_SLOT_substeps],
                                        .count = 2.0 * PI / counts, .residual_stop = RESIDUAL_STOP,
                                        .singular_stop = SINGULAR_STOP, .offset = {offset[0], offset[1]}};
    return start_at_rest(in, &c->params, y, why);
}

void pcn_plant_publish(pcn_instance *in, const pc_fivebar_report *report)
{
    const int slots[11] = {PCN_SLOT_q1, PCN_SLOT_q2, PCN_SLOT_dq1, PCN_SLOT_dq2, PCN_SLOT_x, PCN_SLOT_y,
                           PCN_SLOT_dx, PCN_SLOT_dy, PCN_SLOT_q1_enc, PCN_SLOT_q2_enc, PCN_SLOT_residual};
    const double values[11] = {report->q1, report->q2, report->dq1, report->dq2, report->x, report->y,
                               report->dx, report->dy, report->q1_enc, report->q2_enc, report->residual};
    for (int k = 0; k < 11; ++k) in->real[slots[k]] = values[k];
}

int pcn_plant_check_step(const pcn_plant_config *c, double t, double dt, pcn_text *why)
{
    const pc_fivebar_settings *s = &c->settings;
    if (!(s->lambda * dt / s->substeps > BAUMGARTE_RK4_LIMIT)) return 0;
    const double h = dt / s->substeps;
    char product[32], limit[32], stability[32];
    pcn_addf(pcn_timed(why), "baumgarte = %r /s with RK4 steps of %G s (step from t = %G s): baumgarte * h = %s > %G, "
             "RK4 no longer damps the loop-closure residual (unstable beyond %s); use baumgarte <= %s /s (the thesis "
             "advises <= 1/h), more substeps or dopri5", s->lambda, h, t, g(s->lambda * h, 4, product, sizeof product),
             BAUMGARTE_RK4_LIMIT, g(RK4_REAL_STABILITY, 4, stability, sizeof stability), g(BAUMGARTE_RK4_LIMIT / h, 4,
             limit, sizeof limit));
    return 1;
}

int pcn_plant_judge(const pcn_plant_config *c, const double *y, pc_fivebar_report *report, pc_refusal *refusal)
{
    pc_fivebar_report_of(&c->params, &c->settings, y, report);
    if (report->finite != 1.0) return pc_refuse(refusal, PC_FIVEBAR_NONFINITE_STATE, 0, NAN);
    if (!(report->residual <= RESIDUAL_STOP)) return pc_refuse(refusal, PC_FIVEBAR_DIVERGED, 0, report->residual);
    for (int k = 0; k < 3; ++k)
        if (fabs(report->measures[k]) < SINGULAR_STOP)
            return pc_refuse(refusal, PC_FIVEBAR_SINGULAR, k, report->measures[k]);
    return PC_OK;
}

void pcn_plant_refusal(const pcn_plant_config *c, int status, const pc_refusal *refusal, const double *trial,
                       double t, double dt, const char *held, pcn_text *why)
{
    static const char *const measures[3] = {"chain 1 elbow (serial)", "chain 2 elbow (serial)",
                                            "distal links (parallel)"};
    char value[32], h[32];
    if (status == PC_FIVEBAR_NONFINITE_STATE) {
        pcn_addf(pcn_timed(why), "state became non-finite in the step from t = %G s (%s)", t, held);
        pcn_quantify(why, status, "nonfinite_state", "state[0]", NAN, "", t);
    } else if (status == PC_FIVEBAR_DIVERGED) {
        pcn_addf(pcn_timed(why), "integration diverged in the step from t = %G s (%s): loop-closure residual %s m > %G "
                 "m, the state no longer closes the loop (motion too fast for RK4 steps of %s s: check the torques, "
                 "use substeps or dopri5)", t, held, g(refusal->value, 3, value, sizeof value), RESIDUAL_STOP,
                 g(dt / c->settings.substeps, 3, h, sizeof h));
        pcn_quantify(why, status, "diverged", "residual", refusal->value, "m", t);
    } else {
        pcn_addf(pcn_timed(why), "singular pose reached at t = %G s: %s measure %s at x = %G m, y = %G m", t + dt,
                 measures[refusal->index], g(refusal->value, 3, value, sizeof value), trial[0], trial[1]);
        pcn_quantify(why, status, "singular", measures[refusal->index], refusal->value, "", t + dt);
    }
}

int pcn_plant_check_data(const pcn_instance *in, const double *data, int states, pcn_text *why)
{
    int zero = 1;
    for (long k = 0; k < PCN_PLANT_CONFIG_WORDS + states; ++k) zero &= data[k] == 0.0;
    if (zero) return 0;
    pcn_plant_config c;
    double y[PCN_PLANT_STATES];
    pcn_text ignored;
    pcn_clear(&ignored);
    if (pcn_plant_setup(in, &c, y, &ignored) || memcmp(&c, data, sizeof c) != 0)
        return pcn_addf(why, "the plant's configuration words (parameters, settings) differ from this instance's"), 1;
    for (int k = 0; k < states; ++k)
        if (!isfinite(data[PCN_PLANT_CONFIG_WORDS + k]))
            return pcn_addf(why, "the plant's state word %d = %r is not finite", k,
                            data[PCN_PLANT_CONFIG_WORDS + k]), 1;
    return 0;
}
