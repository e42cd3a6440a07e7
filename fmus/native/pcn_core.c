/* The native FMUs' one co-simulation core, of no FMI version (docs/native.md).
 *
 * It behaves as the pythonfmu FMUs under parcosim's wrapper (fmus/slave/base.py,
 * fmus/export/wrapper/parcosim_fmi2.c): the same call-order rules, refusals (Discard for a
 * refused step, Error for a refused call, never Fatal) and messages; the model's own part is
 * its adapter (pcn_model.h), the FMI functions are a layer's (fmi2_native.c, fmi3_native.c),
 * which names them in the messages (pcn_api).  Links libc and libm only.
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "pcn_native.h"

/* ---- logging ---- */

static int wants(const native *in, const char *category)
{
    if (!in->logging_on) return 0;
    if (in->n_categories == 0) return 1;
    for (size_t i = 0; i < in->n_categories; ++i)
        if (strcmp(in->categories[i], category) == 0) return 1;
    return 0;
}

void pcn_emit(const native *in, pcn_status status, const char *category, const char *message)
{
    if (in->logger == NULL || (status < PCN_ERROR && !wants(in, category))) return;
    in->api->log(in, status, category, message);
}

/* A refused FMI call: "<function>: <why> (t = %.9g s)", PCN_ERROR. */
pcn_status pcn_call_error(const native *in, const char *function, const char *why)
{
    pcn_text t;
    pcn_clear(&t);
    char time[PCN_REPR_SIZE];
    snprintf(time, sizeof time, "%.9g", in->time);
    pcn_addf(&t, "%s: %s (t = %s s)", function, why, time);
    pcn_emit(in, PCN_ERROR, "logStatusError", t.text);
    return PCN_ERROR;
}

void pcn_set_string(char **slot, const char *value)
{
    char *copy = malloc(strlen(value) + 1);
    if (copy == NULL) return;   /* out of memory: the old value stays */
    strcpy(copy, value);
    free(*slot);
    *slot = copy;
}

/* GuardedSlave._refuse: log "<instance>: <text>" (error), to stderr too, and, unless keep_error,
 * keep it in `error` and its record of `kind` at `when` in `refusal` (with why's quantity, if
 * any).  The step's time is added unless why names it (names_time) or the refusal repeats. */
static void refuse(native *in, const char *message, const pcn_text *why, int has_time, double time, int repeat,
                   int keep_error, const char *kind, double when)
{
    pcn_text text;
    pcn_clear(&text);
    if (repeat && has_time) pcn_addf(&text, "%s; step from t = %G s refused", message, time);
    else if (!has_time || repeat || (why && why->names_time)) pcn_addf(&text, "%s", message);
    else pcn_addf(&text, "%s (step from t = %G s)", message, time);
    if (!keep_error) {
        const char *error = repeat ? message : text.text;
        pcn_set_string(&in->pub.string[in->error_slot], error);
        pcn_write_refusal(in, kind, error, when, why);
    }
    pcn_text line;
    pcn_clear(&line);
    pcn_addf(&line, "%s: %s", in->name, text.text);
    pcn_emit(in, PCN_ERROR, "logStatusError", line.text);
    fprintf(stderr, "[parcosim] %s\n", line.text);
}

void pcn_step_size_message(const pcn_instance *in, pcn_text *why, double t, double h, const char *because)
{
    const pcn_model *m = &pcn_this_model;
    why->names_time = 1;
    pcn_addf(why, "step size h = %r s at t = %r s %s; %s accepts %s", h, t, because, m->identifier,
             m->accepted_steps_of ? m->accepted_steps_of(in) : m->accepted_steps);
}

/* ---- instances ---- */

const pcn_variable *pcn_variable_of(unsigned vr)
{
    /* The generator numbers the variables 0, 1, ... in table order: one look (every get and
     * set asks, per value reference; the search was a fifth of a per-component package's
     * CPU in a C host, docs/native.md); any other table is searched. */
    if (vr < (unsigned)pcn_n_variables && pcn_variables[vr].vr == vr) return &pcn_variables[vr];
    for (int k = 0; k < pcn_n_variables; ++k)
        if (pcn_variables[k].vr == vr) return &pcn_variables[k];
    return NULL;
}

static void start_values(native *in)
{
    for (int k = 0; k < pcn_n_variables; ++k) {
        const pcn_variable *v = &pcn_variables[k];
        switch (v->type) {
        case PCN_REAL: in->pub.real[v->slot] = v->start; break;
        case PCN_INTEGER: in->pub.integer[v->slot] = (int)v->start; break;
        case PCN_BOOLEAN: in->pub.boolean[v->slot] = v->start != 0.0; break;
        case PCN_STRING: pcn_set_string(&in->pub.string[v->slot], v->start_string ? v->start_string : ""); break;
        }
    }
    in->initialising = in->initialised = in->terminated = in->ready = 0;
    in->initial_outputs = in->built_for_exit = in->has_last = in->has_accepted = in->step_refused = 0;
    in->pub.start_time = in->next_time = in->last_step = in->time = 0.0;
}

void pcn_free(native *in)
{
    if (in == NULL) return;
    for (int k = 0; in->pub.string && k < pcn_n_slots[PCN_STRING]; ++k) free(in->pub.string[k]);
    for (size_t k = 0; k < in->n_categories; ++k) free(in->categories[k]);
    free(in->categories);
    free(in->pub.real);
    free(in->pub.integer);
    free(in->pub.boolean);
    free(in->pub.string);
    free(in->pub.data);
    free(in->pub.scratch);
    free((char *)in->pub.resources);
    free(in->name);
    free(in->initial_warning);
    free(in);
}

/* calloc of at least one element (a model without variables of a type still gets a pointer). */
static void *zeros(size_t count, size_t size) { return calloc(count ? count : 1, size); }

native *pcn_new(const pcn_api *api, const char *name, char *resources, pcn_function logger, void *env,
                int logging_on)
{
    native *in = calloc(1, sizeof *in);
    if (in == NULL) {
        free(resources);
        return NULL;
    }
    in->model = &pcn_this_model;
    in->api = api;
    in->pub.resources = resources;
    in->name = malloc(strlen(name) + 1);
    in->logger = logger;
    in->env = env;
    in->logging_on = logging_on != 0;
    in->pub.real = zeros((size_t)pcn_n_slots[PCN_REAL], sizeof(double));
    in->pub.integer = zeros((size_t)pcn_n_slots[PCN_INTEGER], sizeof(int));
    in->pub.boolean = zeros((size_t)pcn_n_slots[PCN_BOOLEAN], sizeof(int));
    in->pub.string = zeros((size_t)pcn_n_slots[PCN_STRING], sizeof(char *));
    in->pub.data = zeros((size_t)pcn_this_model.data_words, sizeof(double));
    in->pub.scratch = zeros((size_t)pcn_this_model.scratch_words, sizeof(double));
    in->error_slot = in->refusal_slot = -1;
    for (int k = 0; k < pcn_n_variables; ++k) {
        if (strcmp(pcn_variables[k].name, "error") == 0) in->error_slot = pcn_variables[k].slot;
        if (strcmp(pcn_variables[k].name, "refusal") == 0) in->refusal_slot = pcn_variables[k].slot;
    }
    if (in->name && in->pub.real && in->pub.integer && in->pub.boolean && in->pub.string && in->pub.data &&
        in->pub.scratch && in->error_slot >= 0 && in->refusal_slot >= 0) {
        strcpy(in->name, name);
        start_values(in);
        return in;
    }
    pcn_free(in);
    return NULL;
}

void pcn_refuse_instance(const pcn_api *api, const char *name, pcn_function logger, void *env, const char *why)
{
    native probe = {0};
    probe.api = api;
    probe.name = (char *)name;
    probe.logger = logger;
    probe.env = env;
    pcn_emit(&probe, PCN_ERROR, "logStatusError", why);
}

pcn_status pcn_set_debug_logging(native *in, const char *fn, int on, size_t n, const char *const categories[])
{
    if (n > 0 && categories == NULL) return pcn_call_error(in, fn, "categories (NULL) refused");
    char **copy = n ? calloc(n, sizeof *copy) : NULL;
    if (n && copy == NULL) return PCN_ERROR;
    for (size_t k = 0; k < n; ++k) {
        const char *name = categories[k] ? categories[k] : "";
        copy[k] = malloc(strlen(name) + 1);
        if (copy[k]) strcpy(copy[k], name);
    }
    for (size_t k = 0; k < in->n_categories; ++k) free(in->categories[k]);
    free(in->categories);
    in->categories = copy;
    in->n_categories = n;
    in->logging_on = on != 0;
    return PCN_OK;
}

/* ---- the state machine (GuardedSlave) ---- */

static const char *mode(const native *in, pcn_text *t)
{
    if (in->terminated) pcn_addf(t, "after %s", in->api->terminate);
    else if (in->initialised) pcn_addf(t, "in Step Mode (at t = %r s)", in->next_time);
    else if (in->initialising) pcn_addf(t, "in Initialization Mode");
    else pcn_addf(t, "before %s", in->api->enter_initialization);
    return t->text;
}

/* GuardedSlave._refuse_out_of_order: 0 when the call may come now. */
static int out_of_order(native *in, const char *call, const char *given)
{
    if (!(in->initialising || in->initialised || in->terminated)) return 0;
    pcn_text why, where;
    pcn_clear(&why);
    pcn_clear(&where);
    pcn_addf(&why, "%s%s refused %s: it is allowed only once, between %s and %s; nothing was changed", call, given,
             mode(in, &where), in->api->instantiate, in->api->enter_initialization);
    pcn_call_error(in, call, why.text);
    return 1;
}

pcn_status pcn_setup_experiment(native *in, const char *fn, double startTime, int stopTimeDefined, double stopTime)
{
    pcn_text given, why;
    pcn_clear(&given);
    pcn_clear(&why);
    pcn_addf(&given, " (start_time = %r)", startTime);
    if (out_of_order(in, fn, given.text)) return PCN_ERROR;
    if (!isfinite(startTime)) pcn_addf(&why, "startTime = %r s is not finite; nothing was set", startTime);
    else if (startTime + TIME_RESOLUTION == startTime)
        pcn_addf(&why, "startTime = %r s is too large in magnitude: startTime + %G s == startTime, time could not "
                 "advance; nothing was set", startTime, TIME_RESOLUTION);
    else if (stopTimeDefined && !(isfinite(stopTime) && stopTime >= startTime)) {
        if (!isfinite(stopTime)) pcn_addf(&why, "stopTime = %r s is not finite; nothing was set", stopTime);
        else pcn_addf(&why, "stopTime = %r s is before startTime = %r s; nothing was set", stopTime, startTime);
    }
    if (why.length) return pcn_call_error(in, fn, why.text);
    in->pub.start_time = in->time = startTime;
    in->initial_outputs = in->built_for_exit = 0;
    return PCN_OK;
}

pcn_status pcn_enter_initialization(native *in, const char *fn)
{
    if (out_of_order(in, fn, "")) return PCN_ERROR;
    in->initialising = 1;
    return PCN_OK;
}

pcn_status pcn_exit_initialization(native *in, const char *fn)
{
    if (!in->initialising) {
        pcn_text why, where;
        pcn_clear(&why);
        pcn_clear(&where);
        pcn_addf(&why, "%s refused %s: it ends Initialization Mode (after %s); nothing was changed, the model is "
                 "not rebuilt", fn, mode(in, &where), in->api->enter_initialization);
        return pcn_call_error(in, fn, why.text);
    }
    in->initialising = 0;
    in->has_accepted = 0;
    in->initialised = 1;
    in->next_time = in->pub.start_time;
    in->has_last = 0;
    pcn_text why;
    pcn_clear(&why);
    in->step_refused = 0;
    if (in->built_for_exit || in->model->setup(&in->pub, &why) == 0) {
        in->ready = 1;
        pcn_set_string(&in->pub.string[in->error_slot], "");
        pcn_set_string(&in->pub.string[in->refusal_slot], "");
    } else {
        in->ready = 0;
        pcn_text message;
        pcn_clear(&message);
        pcn_addf(&message, "initialisation refused: %s (t = %G s)", why.text, in->pub.start_time);
        refuse(in, message.text, &why, 0, 0.0, 0, 0, "initialisation", in->pub.start_time);
    }
    return PCN_OK;
}

pcn_status pcn_terminate(native *in)
{
    in->terminated = 1;
    return PCN_OK;
}

pcn_status pcn_reset(native *in)
{
    start_values(in);
    memset(in->pub.data, 0, sizeof(double) * (size_t)in->model->data_words);
    return PCN_OK;
}

/* GuardedSlave.check_step_size and the model's rule. */
static int check_step(native *in, double t, double h, pcn_text *why)
{
    const char *because = NULL;
    char text[64];
    if (!isfinite(h) || h <= 0.0) because = "is not a finite positive number";
    else if (h < MIN_STEP) because = "is below the shortest step 1e-09 s";
    else if (!(t + h <= MAX_TIME)) {
        snprintf(text, sizeof text, "ends after t = %g s", MAX_TIME);
        because = text;
    }
    if (because) {
        pcn_step_size_message(&in->pub, why, t, h, because);
        return 1;
    }
    return in->model->check_step ? in->model->check_step(&in->pub, t, h, why) : 0;
}

/* GuardedSlave._check_communication_point. */
static int check_point(const native *in, double t, pcn_text *why)
{
    double expected = in->next_time, tolerance = 1e-9 * fmax(fabs(expected), 1e-3);
    if (in->has_last && in->last_step) tolerance = fmin(tolerance, 0.5 * in->last_step);
    if (fabs(t - expected) <= tolerance) return 0;
    why->names_time = 1;
    pcn_addf(why, "communication point t = %r s does not follow the last one: the next doStep must start at t = %r "
             "s (the last step's end, or the time of the state set by %s)", t, expected, in->api->set_state);
    return 1;
}

pcn_status pcn_do_step(native *in, double t, double h)
{
    in->time = t;
    pcn_text why;
    pcn_clear(&why);
    if (in->ready && !in->terminated) {
        int refused = t != in->next_time && check_point(in, t, &why);
        if (!refused && (!in->has_accepted || h != in->accepted_step || !(t + h <= MAX_TIME))) {
            refused = check_step(in, t, h, &why);
            if (!refused) {
                in->has_accepted = 1;
                in->accepted_step = h;
            }
        }
        if (!refused) refused = in->model->step(&in->pub, t, h, &why);
        if (!refused) {
            in->next_time = t + h;
            in->last_step = h;
            in->has_last = 1;
            in->time = t + h;
            return PCN_OK;
        }
        refuse(in, why.text, &why, 1, t, 0, 0, "refused", t);
        in->ready = 0;
        in->step_refused = 1;
        return PCN_DISCARD;
    }
    const char *error = in->pub.string[in->error_slot];
    if (in->terminated) {
        pcn_addf(&why, "doStep from t = %r s after %s refused", t, in->api->terminate);
        refuse(in, why.text, NULL, 0, t, 1, 0, "refused", t);
    } else if (!in->initialised) {
        pcn_addf(&why, "doStep from t = %r s before initialisation (%s) refused", t, in->api->exit_initialization);
        refuse(in, why.text, NULL, 0, t, 1, 0, "refused", t);
    } else if (in->step_refused) {
        pcn_addf(&why, "an earlier step was refused (%s); restore an FMU state taken before it (%s) to go on", error,
                 in->api->set_state);
        refuse(in, why.text, NULL, 1, t, 1, 1, "refused", t);
    } else if (error[0]) {   /* the initialisation's refusal, said again (its record kept) */
        refuse(in, error, NULL, 1, t, 1, 1, "initialisation", t);
    } else {
        refuse(in, "initialisation refused", NULL, 1, t, 1, 0, "initialisation", t);
    }
    return PCN_DISCARD;
}
