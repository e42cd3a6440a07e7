/* Native PositionController (fmus/slaves/parcosim_positioncontroller.py) over the law's kernel
 * (law.c: pc_law_run, the exact model's terms from fivebar.c's pc_fivebar_terms_of).
 *
 * The law's set-up is here, in the slave's order with its words: the strategy presets (Tables
 * 6-8, seed 001's; pcn_strategies, from controller/strategies.py at the build, per trajectory
 * name), the parameters' overrides of lam, m_star, phi, k, gamma and kt, the table's and
 * delay's checks, the plant preset's geometry and its counter-mass check (pcn_preset_*), and
 * the kernel's pc_law_params (delay_compensation, velocity_delay_compensation: its predict).  The model (H^, h^) of a model-based strategy is made here at
 * set-up (model5r.c) from the preset's data (pcn_preset_model) and the plant parameters
 * (gravity_x, gravity_y, counter_mass1, counter_mass2, model_error), as the twin's
 * PositionController makes it (perturbed_params, plant.fast5r.pack_params): the exact model's
 * pc_fivebar_params, and with model = tabulated the table on the grid of grid_step, x_min ...
 * y_max (controller.model.TabulatedModel's kernel_table).  PD strategies need no model.
 *
 * Steps h = T / n sample on sub-step sample_phase and hold the outputs in between
 * (pcn_sampling.h).  Model data (FMU state): the law's state and parameters (as the twin's
 * buffer), the delay queue, the table-fallback count, the sub-step counter; scratch: the
 * kernel's pc_law_scratch, the exact model's terms, the model (what it was made for, its
 * pc_fivebar_params, its table: configuration of the parameters, made again when a sample
 * finds it made for others, e.g. after a state was restored into an instance never set up).
 */
#include <math.h>
#include <string.h>

#include "fivebar.h"
#include "law.h"
#include "model5r.h"
#include "model_config.h"
#include "pcn_model.h"
#include "pcn_sampling.h"

#define ABSURD 1e6          /* fmus/slave/refusals.py */
#define TINY 1e-12
#define PRESET_VALUE (-1.0)
#define MIN_STEP 1e-9       /* fmus/slave/base.py */
#define N_NUMERIC 18
#define N_INPUTS 12

typedef struct {
    pc_law_state state;     /* the twin's buffer: state, then parameters */
    pc_law_params params;
    double delayed[4 * PCN_MAX_DELAY_STEPS];   /* the computation delay's queue, oldest first */
    double fallbacks;       /* samples that used the exact model in place of the table */
    pcn_sampling counter;
} controller;

#define MODEL_KEY 12   /* what the model was made for: model kind, preset, the 10 plant and grid values */
#define PRESET_MODEL_WORDS (2 + 2 * 9)   /* l0, m0, each chain's 9 fields (models.PLANT_CHAIN_FIELDS) */
/* The largest table: TabulatedModel's checks allow ((x_max - x_min) / step + 1) ((y_max - y_min) / step + 1)
 * <= MAX_TABLE_POINTS; rounding each count to the nearest whole number gives at most 1.5 times that plus 1. */
#define TABLE_POINTS ((long)(1.5 * PCN_MAX_TABLE_POINTS) + 1)
#define TABLE_WORDS ((long)(sizeof(pc_law_table) / sizeof(double)) + TABLE_POINTS * PC_LAW_TERMS)

typedef struct {
    pc_law_scratch w;
    pc_fivebar_inverse terms;   /* its first words are pc_law_terms */
    double key[MODEL_KEY];      /* NaN words before a model is made */
    pc_fivebar_params model;    /* the exact model's parameters */
    double table[];             /* TABLE_WORDS: the tabulated model's pc_law_table */
} workspace;

#define WORDS(type) ((long)(sizeof(type) / sizeof(double)))

_Static_assert(PCN_PRESET_MODEL_WORDS == PCN_PRESET_NAMES_COUNT * PRESET_MODEL_WORDS, "preset_model rows");
_Static_assert(PCN_STRATEGY_WORDS == 11, "a strategy row: space, model_based, lam, m_star, phi, k, gamma, law");

enum { S_SPACE, S_MODEL_BASED, S_LAM, S_M_STAR, S_PHI, S_K1, S_K2, S_ADAPTIVE, S_GAMMA1, S_GAMMA2, S_LAW };

static const char *const INPUTS[N_INPUTS] = {"q1", "q2", "dq1", "dq2", "ddq1", "ddq2",
                                             "x_d", "y_d", "dx_d", "dy_d", "ddx_d", "ddy_d"};

static controller *data_of(pcn_instance *in) { return (controller *)in->data; }

static int find(const char *name, const char *const *names, int n)
{
    for (int k = 0; k < n; ++k)
        if (strcmp(name, names[k]) == 0) return k;
    return -1;
}

/* ", "-joined names after `head`. */
static void add_names(pcn_text *why, const char *head, const char *const *names, int n)
{
    pcn_addf(why, "%s", head);
    for (int k = 0; k < n; ++k) pcn_addf(why, k ? ", %s" : "%s", names[k]);
}

/* get_strategy(strategy, trajectory): the preset's row, NULL with the reason. */
static const double *strategy_row(const pcn_instance *in, pcn_text *why)
{
    const char *trajectory = in->string[PCN_SLOT_trajectory], *name = in->string[PCN_SLOT_strategy];
    int j = find(trajectory, pcn_trajectory_names, PCN_TRAJECTORY_NAMES_COUNT);
    if (j < 0)
        return pcn_addf(why, "trajectory = '%s': valid: %s, %s (%s and %s use the circle table)", trajectory,
                        pcn_trajectory_names[0], pcn_trajectory_names[1], pcn_trajectory_names[2],
                        pcn_trajectory_names[3]), NULL;
    int k = find(name, pcn_strategy_names, PCN_STRATEGY_NAMES_COUNT);
    if (k < 0) {
        pcn_addf(why, "strategy = '%s' is unknown", name);
        return add_names(why, "; valid: ", pcn_strategy_names, PCN_STRATEGY_NAMES_COUNT), NULL;
    }
    return pcn_strategies + ((long)j * PCN_STRATEGY_NAMES_COUNT + k) * PCN_STRATEGY_WORDS;
}

/* The slave's numeric checks: finite, absurd, signs, the table's grid, the delay, kt. */
static int check_numbers(const pcn_instance *in, const double *v, double kt[2], pcn_text *why)
{
    static const char *const names[N_NUMERIC] = {"lam", "m_star", "phi", "k1", "k2", "gamma1", "gamma2",
                                                 "model_error", "kt1", "kt2", "grid_step", "x_min", "x_max",
                                                 "y_min", "y_max", "T", "gravity_x", "gravity_y"};
    for (int k = 0; k < N_NUMERIC; ++k)
        if (!isfinite(v[k])) return pcn_addf(why, "%s = %r is not finite", names[k], v[k]), 1;
    for (int k = 0; k < N_NUMERIC; ++k)
        if (fabs(v[k]) > ABSURD)
            return pcn_addf(why, "parameter %s = %r is absurd: |%s| must be <= %G (SI units)", names[k], v[k],
                            names[k], ABSURD), 1;
    for (int k = 5; k < 10; ++k)   /* gamma1, gamma2, kt1, kt2 */
        if (k != 7 && v[k] < 0.0 && !(k >= 8 && v[k] == PRESET_VALUE))
            return pcn_addf(why, "parameter %s = %r must be >= 0", names[k], v[k]), 1;
    const double step = v[10];
    if (!(step > 0.0)) return pcn_addf(why, "parameter grid_step = %r m must be > 0", step), 1;
    for (int k = 11; k < 15; k += 2)
        if (!(v[k + 1] > v[k]))
            return pcn_addf(why, "parameters %s = %r, %s = %r: the table's range is empty (%s must be > %s)", names[k],
                            v[k], names[k + 1], v[k + 1], names[k + 1], names[k]), 1;
    const double points = ((v[12] - v[11]) / step + 1.0) * ((v[14] - v[13]) / step + 1.0);
    if (points > PCN_MAX_TABLE_POINTS)
        return pcn_addf(why, "parameters grid_step = %r, x_min = %r, x_max = %r, y_min = %r, y_max = %r m give a "
                        "table of %g points, more than %G (building it would take initialisation over 10 s)", step,
                        v[11], v[12], v[13], v[14], points, PCN_MAX_TABLE_POINTS), 1;
    const int delay = in->integer[PCN_SLOT_delay_steps];
    if (!(delay >= 0 && delay <= PCN_MAX_DELAY_STEPS))
        return pcn_addf(why, "parameter delay_steps = %d must be an integer in [0, %d]", delay,
                        PCN_MAX_DELAY_STEPS), 1;
    static const char *const compensation[2] = {"delay_compensation", "velocity_delay_compensation"};
    const int periods[2] = {in->integer[PCN_SLOT_delay_compensation], in->integer[PCN_SLOT_velocity_delay_compensation]};
    for (int k = 0; k < 2; ++k)
        if (!(periods[k] >= 0 && periods[k] <= PC_LAW_MAX_PREDICT))
            return pcn_addf(why, "parameter %s = %d must be an integer in [0, %d]", compensation[k], periods[k],
                            PC_LAW_MAX_PREDICT), 1;
    const double preset_kt[2] = {PCN_DEFAULT_KT1, PCN_DEFAULT_KT2};
    for (int k = 0; k < 2; ++k) {
        kt[k] = v[8 + k] == PRESET_VALUE ? preset_kt[k] : v[8 + k];
        if (!(kt[k] > 0.0))
            return pcn_addf(why, "parameter %s = %r must be > 0 (or -1 for the motor preset's)", names[8 + k],
                            kt[k]), 1;
    }
    for (int k = 0; k < 2; ++k)
        if (kt[k] < TINY)
            return pcn_addf(why, "parameter %s = %r is absurdly small: it must be >= %G (SI units)", names[8 + k],
                            kt[k], TINY), 1;
    return 0;
}

/* fmus.slave.declarations.with_counter_masses on preset p: finite, absurd, >= 0, heavy enough to balance. */
static int check_counter_masses(const pcn_instance *in, int p, pcn_text *why)
{
    static const char *const names[2] = {"counter_mass1", "counter_mass2"};
    const double M[2] = {in->real[PCN_SLOT_counter_mass1], in->real[PCN_SLOT_counter_mass2]};
    for (int j = 0; j < 2; ++j)
        if (!isfinite(M[j])) return pcn_addf(why, "%s = %r is not finite", names[j], M[j]), 1;
    for (int j = 0; j < 2; ++j)
        if (fabs(M[j]) > ABSURD)
            return pcn_addf(why, "parameter %s = %r is absurd: |%s| must be <= %G (SI units)", names[j], M[j],
                            names[j], ABSURD), 1;
    for (int j = 0; j < 2; ++j)
        if (M[j] < 0.0) return pcn_addf(why, "parameter %s = %r kg must be >= 0", names[j], M[j]), 1;
    for (int k = 0; k < 2; ++k) {   /* ChainParams.counter_offsets, FiveBarParams.check_counter_masses */
        const double *c = pcn_preset_model + p * PRESET_MODEL_WORDS + 2 + 9 * k;   /* l1, l2, lg1, lg2, m1, m2 ... */
        const pc_fivebar_chain chain = {.l1 = c[0], .l2 = c[1], .lg1 = c[2], .lg2 = c[3], .m1 = c[4], .m2 = c[5]};
        double offset[2];
        pc_model5r_counter_offsets(&chain, M[0], M[1], offset);
        const double reach = PCN_COUNTER_REACH * (c[0] + c[1]);
        for (int j = 0; j < 2; ++j)
            if (fabs(offset[j]) > reach)
                return pcn_addf(why, "parameter %s = %r kg is too light to balance chain %d: it would sit %g m behind "
                                "its joint, more than %G times the chain's length (%g m)", names[j], M[j], k + 1,
                                fabs(offset[j]), PCN_COUNTER_REACH, reach), 1;
    }
    return 0;
}

/* What the model of these parameters is made for (kind: 0 PD, 1 exact, 2 tabulated; the grid's
 * values only for a table). */
static void model_key(const pcn_instance *in, const pc_law_params *p, double key[MODEL_KEY])
{
    const double *r = in->real;
    const int slots[10] = {PCN_SLOT_gravity_x, PCN_SLOT_gravity_y, PCN_SLOT_counter_mass1, PCN_SLOT_counter_mass2,
                           PCN_SLOT_model_error, PCN_SLOT_grid_step, PCN_SLOT_x_min, PCN_SLOT_x_max,
                           PCN_SLOT_y_min, PCN_SLOT_y_max};
    const int kind = p->model == PC_LAW_MODEL_PD ? 0 : p->model == PC_LAW_MODEL_EXACT ? 1 : 2;
    key[0] = kind;
    key[1] = find(in->string[PCN_SLOT_preset], pcn_preset_names, PCN_PRESET_NAMES_COUNT);
    for (int k = 0; k < 10; ++k) key[2 + k] = kind == 0 || (kind == 1 && k >= 5) ? 0.0 : r[slots[k]];
}

/* The model of a model-based strategy (PositionController with perturbed_params): the preset with
 * the model's gravity and both chains' counter-masses, every mass and inertia scaled by
 * 1 + model_error, packed (pack_params), and with a table its grid (TabulatedModel); the key
 * it was made for.  Nonzero (why written) if the table does not fit, which the checks before exclude. */
static int make_model(const pcn_instance *in, const pc_law_params *p, workspace *w, pcn_text *why)
{
    double key[MODEL_KEY];
    model_key(in, p, key);
    for (int k = 0; k < MODEL_KEY; ++k) w->key[k] = NAN;
    if (key[0] == 0.0) return memcpy(w->key, key, sizeof key), 0;
    const double *m = pcn_preset_model + (long)key[1] * PRESET_MODEL_WORDS, f = 1.0 + key[6];
    pc_fivebar_params *model = &w->model;
    model->l0 = m[0];
    model->m0 = m[1] * f;
    model->gravity[0] = key[2];
    model->gravity[1] = key[3];
    for (int k = 0; k < 2; ++k) {
        const double *c = m + 2 + 9 * k;
        model->chain[k] = (pc_fivebar_chain){.l1 = c[0], .l2 = c[1], .lg1 = c[2], .lg2 = c[3], .m1 = c[4] * f,
                                             .m2 = c[5] * f, .Jz1 = c[6] * f, .Jz2 = c[7] * f, .J_rotor = c[8] * f};
        pc_model5r_pack_chain(&model->chain[k], key[4] * f, key[5] * f);
    }
    if (key[0] == 2.0 && pc_model5r_build_table(model, key + 8, key[7], PCN_BAND, w->table, TABLE_WORDS) < 0)
        return pcn_addf(why, "the table of grid_step = %r m does not fit the native FMU's %ld words", key[7],
                        TABLE_WORDS), 1;
    memcpy(w->key, key, sizeof key);
    return 0;
}

/* Whether the model in the workspace was made for these parameters. */
static int model_current(const pcn_instance *in, const pc_law_params *p, const workspace *w)
{
    double key[MODEL_KEY];
    model_key(in, p, key);
    return memcmp(key, w->key, sizeof key) == 0;
}

/* The slave's set-up in its order (PositionController.setup, then the controller's own
 * checks): the kernel's parameters into p and the starting gains into k. */
static int configure(const pcn_instance *in, pc_law_params *p, double k[2], pcn_text *why)
{
    const double *r = in->real;
    const double *row = strategy_row(in, why);
    if (!row) return 1;
    if (!(r[PCN_SLOT_T] >= MIN_STEP))
        return pcn_addf(why, "parameter T = %r s must be >= %G s", r[PCN_SLOT_T], MIN_STEP), 1;
    const double v[N_NUMERIC] = {
        r[PCN_SLOT_lam], r[PCN_SLOT_m_star], r[PCN_SLOT_phi], r[PCN_SLOT_k1], r[PCN_SLOT_k2], r[PCN_SLOT_gamma1],
        r[PCN_SLOT_gamma2], r[PCN_SLOT_model_error], r[PCN_SLOT_kt1], r[PCN_SLOT_kt2], r[PCN_SLOT_grid_step],
        r[PCN_SLOT_x_min], r[PCN_SLOT_x_max], r[PCN_SLOT_y_min], r[PCN_SLOT_y_max], r[PCN_SLOT_T],
        r[PCN_SLOT_gravity_x], r[PCN_SLOT_gravity_y]};
    double kt[2];
    if (check_numbers(in, v, kt, why)) return 1;
    const int preset = find(in->string[PCN_SLOT_preset], pcn_preset_names, PCN_PRESET_NAMES_COUNT);
    if (preset < 0) {
        pcn_addf(why, "preset: unknown preset '%s'", in->string[PCN_SLOT_preset]);
        return add_names(why, "; valid: ", pcn_preset_names, PCN_PRESET_NAMES_COUNT), 1;
    }
    if (check_counter_masses(in, preset, why)) return 1;
    /* Strategy.with_ of the parameters that are not PRESET_VALUE, then _check_strategy. */
    const double lam = v[0] != PRESET_VALUE ? v[0] : row[S_LAM], m_star = v[1] != PRESET_VALUE ? v[1] : row[S_M_STAR];
    const double phi = v[2] != PRESET_VALUE ? v[2] : row[S_PHI];
    k[0] = v[3] != PRESET_VALUE ? v[3] : row[S_K1];
    k[1] = v[4] != PRESET_VALUE ? v[4] : row[S_K2];
    const int adaptive = v[5] > 0.0 || v[6] > 0.0, model_based = row[S_MODEL_BASED] != 0.0;
    const char *named[2] = {"lam", "phi"};
    const double positive[2] = {lam, phi};
    for (int j = 0; j < 2; ++j)
        if (!(positive[j] > 0.0)) return pcn_addf(why, "%s = %r must be > 0", named[j], positive[j]), 1;
    if (!(m_star >= 0.0)) return pcn_addf(why, "m_star = %r must be >= 0", m_star), 1;
    if (!model_based && m_star <= 0.0)
        return pcn_addf(why, "m_star = %r must be > 0 for the PD strategy %s", m_star,
                        in->string[PCN_SLOT_strategy]), 1;
    for (int j = 0; j < 2; ++j)
        if (!(k[j] >= 0.0)) return pcn_addf(why, "k%d = %r must be >= 0", j + 1, k[j]), 1;
    const char *model = in->string[PCN_SLOT_model];
    const int exact = strcmp(model, "exact") == 0;
    if (!exact && strcmp(model, "tabulated") != 0)
        return pcn_addf(why, "model = '%s' is unknown; valid: exact, tabulated", model), 1;
    if (model_based && !(v[7] > -1.0)) return pcn_addf(why, "model_error = %r must be finite and > -1", v[7]), 1;
    /* controller.law.pack */
    memset(p, 0, sizeof *p);
    const double *g = pcn_preset_geometry + preset * 5;
    p->geometry = (pc_5r_geometry){g[0], g[1], g[2], g[3], g[4]};
    p->band = PCN_BAND;
    p->space = row[S_SPACE];
    p->model = !model_based ? PC_LAW_MODEL_PD : exact ? PC_LAW_MODEL_EXACT : PC_LAW_MODEL_TABULATED;
    p->law = row[S_LAW];
    p->kp = pow(lam, 2.0);   /* lam ** 2, as Python computes it */
    p->kv = 2.0 * lam;
    p->lam = lam;
    p->phi = phi;
    p->adaptive = adaptive ? 1.0 : row[S_ADAPTIVE];
    p->gamma[0] = adaptive ? v[5] : row[S_GAMMA1];
    p->gamma[1] = adaptive ? v[6] : row[S_GAMMA2];
    p->m_star = m_star;
    p->kt[0] = kt[0];
    p->kt[1] = kt[1];
    p->predict[0] = in->integer[PCN_SLOT_delay_compensation];
    p->predict[1] = in->integer[PCN_SLOT_velocity_delay_compensation];
    return 0;
}

static int setup(pcn_instance *in, pcn_text *why)
{
    controller *c = data_of(in);
    double k[2];
    memset(c, 0, sizeof *c);
    if (configure(in, &c->params, k, why)) {
        memset(c, 0, sizeof *c);
        return 1;
    }
    c->state.k[0] = k[0];
    c->state.k[1] = k[1];
    if (make_model(in, &c->params, (workspace *)in->scratch, why)) {
        memset(c, 0, sizeof *c);
        return 1;
    }
    return 0;
}

static int check_step(pcn_instance *in, double t, double h, pcn_text *why)
{
    return pcn_sampling_check(&data_of(in)->counter, in, in->real[PCN_SLOT_T], in->integer[PCN_SLOT_sample_phase], t,
                              h, why);
}

/* The refusal's quantity as controller/position.py's REASONS name it (code, variable, unit). */
static void quantify(int code, const pc_refusal *r, double t, pcn_text *why)
{
    static const char *const OUTPUTS[6] = {"tau1", "tau2", "i_ref1", "i_ref2", "e1", "e2"};
    static const char *const TABLE_OUT[2] = {"x", "y"};
    const char *reason, *variable, *unit = "";
    switch (code) {
    case PC_LAW_NONFINITE: reason = "NONFINITE", variable = INPUTS[r->index]; break;
    case PC_LAW_REF_OUT: reason = "REF_OUT", variable = "(x_d, y_d)", unit = "m"; break;
    case PC_LAW_REF_BAND: reason = "REF_BAND", variable = "margin"; break;
    case PC_LAW_NO_ASSEMBLY: reason = "NO_ASSEMBLY", variable = "(q1, q2)", unit = "m"; break;
    case PC_LAW_MEASURED_SINGULAR: reason = "MEASURED_SINGULAR", variable = "(q1, q2)"; break;
    case PC_LAW_REF_SINGULAR: reason = "REF_SINGULAR", variable = "(x_d, y_d)"; break;
    case PC_LAW_TABLE_OUT: reason = "TABLE_OUT", variable = TABLE_OUT[r->index ? 1 : 0], unit = "m"; break;
    case PC_LAW_TABLE_HOLE: reason = "TABLE_HOLE", variable = "x", unit = "m"; break;
    case PC_LAW_EXACT_OUT: reason = "EXACT_OUT", variable = "(x, y)", unit = "m"; break;
    default: reason = "NONFINITE_OUTPUT", variable = OUTPUTS[r->index]; break;
    }
    pcn_quantify(why, code, reason, variable, r->value, unit, t);
}

/* The refusal of a sample in controller/position.py's words (REASONS). */
static void refusal_text(const pcn_instance *in, const pc_law_scratch *w, int code, const pc_refusal *r, double t,
                         pcn_text *why)
{
    const pc_law_inputs *x = &w->in;
    const double px = w->task.x, py = w->task.y;
    const char *reference = "reference (x_d, y_d) = (%r, %r) m at t = %G s";
    const char *pose = "measured pose (x, y) = (%G, %G) m at t = %G s: ";
    quantify(code, r, t, why);
    switch (code) {
    case PC_LAW_NONFINITE:
        pcn_addf(pcn_timed(why), "input %s = %r at t = %G s is not finite", INPUTS[r->index], r->value, t);
        break;
    case PC_LAW_REF_OUT:
        pcn_addf(pcn_timed(why), reference, x->x_d, x->y_d, t);
        pcn_addf(why, " is outside the workspace");
        break;
    case PC_LAW_REF_BAND:
        pcn_addf(pcn_timed(why), reference, x->x_d, x->y_d, t);
        pcn_addf(why, " is in the near-singular band (margin %g < %G)", r->value, PCN_BAND);
        break;
    case PC_LAW_NO_ASSEMBLY:
        pcn_addf(pcn_timed(why), "measured (q1, q2) = (%r, %r) rad at t = %G s: no assembly for q1=%G, q2=%G rad "
                 "(elbow distance %G m)", x->q1, x->q2, t, x->q1, x->q2, r->value);
        break;
    case PC_LAW_MEASURED_SINGULAR:
        pcn_addf(pcn_timed(why), "measured (q1, q2) = (%r, %r) rad at t = %G s: a parallel singularity (det J_X = %g)",
                 x->q1, x->q2, t, r->value);
        break;
    case PC_LAW_REF_SINGULAR:
        pcn_addf(pcn_timed(why), reference, x->x_d, x->y_d, t);
        pcn_addf(why, ": a chain is stretched or folded there (J_Theta singular)");
        break;
    case PC_LAW_TABLE_OUT:
        pcn_addf(pcn_timed(why), pose, px, py, t);
        pcn_addf(why, "point (x=%G, y=%G) m is outside the tabulated region x in [%G, %G], y in [%G, %G] m", px, py,
                 in->real[PCN_SLOT_x_min], in->real[PCN_SLOT_x_max], in->real[PCN_SLOT_y_min],
                 in->real[PCN_SLOT_y_max]);
        break;
    case PC_LAW_TABLE_HOLE:
        pcn_addf(pcn_timed(why), pose, px, py, t);
        pcn_addf(why, "point (x=%G, y=%G) m needs a grid point left out of the table (outside the workspace or "
                 "near-singular)", px, py);
        break;
    case PC_LAW_EXACT_OUT:
        pcn_addf(pcn_timed(why), pose, px, py, t);
        pcn_addf(why, "point out of reach of a chain (distance %G m)", r->value);
        break;
    default: {   /* PC_LAW_NONFINITE_OUTPUT */
        const double *v = &x->q1, *o = w->out.tau;
        int largest = 0;
        for (int k = 1; k < N_INPUTS; ++k)
            if (fabs(v[k]) > fabs(v[largest])) largest = k;
        pcn_addf(pcn_timed(why), "the law's outputs (tau1, tau2, i_ref1, i_ref2, e1, e2) = (%r, %r, %r, %r, %r, %r) at "
                 "t = %G s are not finite; largest input: %s = %r", o[0], o[1], o[2], o[3], o[4], o[5], t,
                 INPUTS[largest], v[largest]);
    }
    }
}

/* The law at a sample (the slave's sample): the table's exact fallback, the delay, the outputs. */
static int sample(pcn_instance *in, double t, pcn_text *why)
{
    static const int inputs[N_INPUTS] = {PCN_SLOT_q1, PCN_SLOT_q2, PCN_SLOT_dq1, PCN_SLOT_dq2, PCN_SLOT_ddq1,
                                         PCN_SLOT_ddq2, PCN_SLOT_x_d, PCN_SLOT_y_d, PCN_SLOT_dx_d, PCN_SLOT_dy_d,
                                         PCN_SLOT_ddx_d, PCN_SLOT_ddy_d};
    controller *c = data_of(in);
    workspace *w = (workspace *)in->scratch;
    if (!model_current(in, &c->params, w) && make_model(in, &c->params, w, why)) return 1;
    double *r = in->real, *x = &w->w.in.q1;
    for (int k = 0; k < N_INPUTS; ++k) x[k] = r[inputs[k]];
    const int tabulated = c->params.model == PC_LAW_MODEL_TABULATED;
    const pc_law_context context = {&c->params, tabulated ? (const pc_law_table *)w->table : NULL,
                                    (pc_law_terms *)&w->terms, &c->state, &w->w, pc_fivebar_terms_of, &w->model, NULL,
                                    0};
    const double h = r[PCN_SLOT_T];
    pc_refusal refusal;
    int code = pc_law_run(&context, h, &refusal), fell_back = 0;
    if ((code == PC_LAW_TABLE_OUT || code == PC_LAW_TABLE_HOLE) && tabulated && in->boolean[PCN_SLOT_table_fallback]) {
        code = pc_law_exact_pose(&c->params, &w->w, &refusal);   /* the exact model off the table */
        if (code == PC_OK) {
            pc_fivebar_terms_of(&w->model, w->w.q, w->w.dq, (double *)&w->terms);
            code = pc_law_resume(&context, h, &refusal);
            fell_back = code == PC_OK;
        }
    }
    if (code != PC_OK) return refusal_text(in, &w->w, code, &refusal, t, why), 1;
    c->fallbacks += fell_back;
    double commands[4] = {w->w.out.tau[0], w->w.out.tau[1], w->w.out.i_ref[0], w->w.out.i_ref[1]};
    const int n = in->integer[PCN_SLOT_delay_steps];
    if (n > 0) pc_law_delay(c->delayed, n, commands);
    r[PCN_SLOT_tau1] = commands[0];
    r[PCN_SLOT_tau2] = commands[1];
    r[PCN_SLOT_i_ref1] = commands[2];
    r[PCN_SLOT_i_ref2] = commands[3];
    r[PCN_SLOT_e1] = w->w.out.e[0];
    r[PCN_SLOT_e2] = w->w.out.e[1];
    in->integer[PCN_SLOT_model_fallbacks] = (int)c->fallbacks;
    return 0;
}

/* Sample on sub-step sample_phase, hold the outputs on the others. */
static int step(pcn_instance *in, double t, double h, pcn_text *why)
{
    (void)h;
    pcn_sampling *s = &data_of(in)->counter;
    if (PCN_SAMPLES(s, in, t) && sample(in, t, why)) return 1;
    s->substep = pc_sampling_next(s->substep, s->substeps);
    return 0;
}

/* Restored data: all zero (a state taken before set-up), or the parameters this instance's
 * set-up gives, a finite law state and queue (rows past delay_steps zero), a whole count. */
static int check_data(const pcn_instance *in, const double *data, pcn_text *why)
{
    const controller *c = (const controller *)data;
    if (pcn_sampling_check_data(&c->counter, why)) return 1;
    int zero = 1;
    for (long k = 0; k < WORDS(controller) - PCN_SAMPLING_WORDS; ++k) zero &= data[k] == 0.0;
    if (zero) return 0;
    pc_law_params own;
    double k0[2];
    pcn_text ignored;
    pcn_clear(&ignored);
    if (configure(in, &own, k0, &ignored) || memcmp(&own, &c->params, sizeof own) != 0)
        return pcn_addf(why, "the position controller's configuration words differ from this instance's set-up"), 1;
    for (long k = 0; k < WORDS(pc_law_state); ++k)
        if (!isfinite(data[k])) return pcn_addf(why, "the law's state word %d is %r", (int)k, data[k]), 1;
    const int n = in->integer[PCN_SLOT_delay_steps];
    for (int k = 0; k < 4 * PCN_MAX_DELAY_STEPS; ++k)
        if (k < 4 * n ? !isfinite(c->delayed[k]) : c->delayed[k] != 0.0)
            return pcn_addf(why, "word %d of the delay queue (delay_steps = %d) is %r", k, n, c->delayed[k]), 1;
    if (!(c->fallbacks >= 0.0 && c->fallbacks <= 2147483647.0 && c->fallbacks == floor(c->fallbacks)))
        return pcn_addf(why, "the table-fallback count %r is not a whole number", c->fallbacks), 1;
    return 0;
}

const pcn_model pcn_this_model = {
    .identifier = PCN_IDENTIFIER,
    .accepted_steps = PCN_SAMPLING_ACCEPTS,
    .data_words = WORDS(controller),
    .scratch_words = WORDS(workspace) + TABLE_WORDS,
    .setup = setup,
    .check_step = check_step,
    .step = step,
    .check_data = check_data,
};
