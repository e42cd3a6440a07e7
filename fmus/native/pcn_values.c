/* The native FMUs' variable access: get/set of every type by value reference, with the
 * checks and messages of parcosim's wrapper and GuardedSlave (fmus/slave/base.py), for the FMI
 * layers' Get/Set functions (docs/native.md). */
#include <string.h>

#include "pcn_native.h"

static const char *const CAUSALITY_NAME[] = {"input", "output", "parameter"};

/* ---- values ---- */

/* The wrapper's check: each vr a variable of this type; else logs the first, nonzero.  The
 * message is written only for a refusal: an accepted call (every get and set of a step)
 * fills no text. */
static int check_vrs(native *in, const char *fn, const unsigned vr[], size_t nvr, const void *values,
                     pcn_type type)
{
    const pcn_variable *v = NULL;
    size_t k = 0;
    if (nvr > 0 && vr != NULL && values != NULL)
        for (; k < nvr; ++k) {
            v = pcn_variable_of(vr[k]);
            if (v == NULL || v->type != type) break;
        }
    if (k == nvr) return 0;
    pcn_text why;
    pcn_clear(&why);
    if (vr == NULL || values == NULL)
        pcn_addf(&why, "%s (NULL) with %d values refused", vr == NULL ? "the value reference array" : "the value array",
                 (int)nvr);
    else if (v == NULL) pcn_addf(&why, "value reference %u is not a variable of this FMU", vr[k]);
    else
        pcn_addf(&why, "value reference %u ('%s') is a %s variable, not a %s", vr[k], v->name,
                 in->api->type_name[v->type], in->api->type_name[type]);
    pcn_call_error(in, fn, why.text);
    return 1;
}

/* A get of an output before initialisation builds the model first (GuardedSlave._calculate_outputs_for). */
static void calculate_outputs(native *in, const unsigned vr[], size_t nvr)
{
    if (in->initialised || in->initial_outputs) return;
    int wanted = 0;
    for (size_t k = 0; k < nvr; ++k) {
        const pcn_variable *v = pcn_variable_of(vr[k]);
        wanted |= v->causality == PCN_OUTPUT && strcmp(v->name, "error") != 0 && strcmp(v->name, "refusal") != 0;
    }
    if (!wanted) return;
    pcn_text why;
    pcn_clear(&why);
    if (in->model->setup(&in->pub, &why) == 0) {
        in->initial_outputs = in->built_for_exit = 1;
        return;
    }
    pcn_text message;
    pcn_clear(&message);
    pcn_addf(&message, "%s: the outputs read in Initialization Mode keep their start values: %s; "
             "%s will refuse the initialisation", in->name, why.text, in->api->exit_initialization);
    if (in->initial_warning && strcmp(in->initial_warning, message.text) == 0) return;
    pcn_set_string(&in->initial_warning, message.text);
    pcn_emit(in, PCN_WARNING, "logStatusWarning", message.text);
}

/* The old or new value of a variable in a message, as Python's repr. */
static void value_text(pcn_text *t, pcn_type type, const void *values, size_t k)
{
    switch (type) {
    case PCN_REAL: pcn_addf(t, "%r", ((const double *)values)[k]); break;
    case PCN_INTEGER: pcn_addf(t, "%d", (int)((const int *)values)[k]); break;
    case PCN_BOOLEAN: pcn_addf(t, "%B", (int)((const int *)values)[k]); break;
    case PCN_STRING: pcn_addf(t, "'%s'", ((const char *const *)values)[k]); break;
    }
}

static void current_text(pcn_text *t, const native *in, const pcn_variable *v)
{
    switch (v->type) {
    case PCN_REAL: pcn_addf(t, "%r", in->pub.real[v->slot]); break;
    case PCN_INTEGER: pcn_addf(t, "%d", in->pub.integer[v->slot]); break;
    case PCN_BOOLEAN: pcn_addf(t, "%B", in->pub.boolean[v->slot]); break;
    case PCN_STRING: pcn_addf(t, "'%s'", in->pub.string[v->slot]); break;
    }
}

/* GuardedSlave._refuse_set: nonzero (logged) unless every variable may be set now. */
static int refuse_set(native *in, const char *fn, const unsigned vr[], size_t nvr, const void *values,
                      pcn_type type)
{
    for (size_t k = 0; k < nvr; ++k) {
        const pcn_variable *v = pcn_variable_of(vr[k]);
        if (v->causality == PCN_INPUT || (v->causality == PCN_PARAMETER && (!in->initialised || v->tunable))) continue;
        pcn_text why, now;
        pcn_clear(&why);
        pcn_clear(&now);
        if (in->initialised) pcn_addf(&now, "at t = %r s", in->next_time);
        else pcn_addf(&now, "before initialisation");
        if (v->causality == PCN_PARAMETER) {
            pcn_addf(&why, "%s: parameter %s = ", fn, v->name);
            value_text(&why, type, values, k);
            pcn_addf(&why, " refused after initialisation (%s): a fixed parameter keeps its value ", now.text);
        } else {
            pcn_addf(&why, "%s: %s is an output (%s), value ", fn, v->name, CAUSALITY_NAME[v->causality]);
            value_text(&why, type, values, k);
            pcn_addf(&why, " refused (%s): it keeps ", now.text);
        }
        current_text(&why, in, v);
        pcn_addf(&why, "; nothing was set");
        pcn_call_error(in, fn, why.text);
        return 1;
    }
    return 0;
}

pcn_status pcn_get(native *in, const char *fn, const unsigned vr[], size_t nvr, void *values, pcn_type type)
{
    if (check_vrs(in, fn, vr, nvr, values, type)) return PCN_ERROR;
    calculate_outputs(in, vr, nvr);
    for (size_t k = 0; k < nvr; ++k) {
        int slot = pcn_variable_of(vr[k])->slot;
        switch (type) {
        case PCN_REAL: ((double *)values)[k] = in->pub.real[slot]; break;
        case PCN_INTEGER: ((int *)values)[k] = in->pub.integer[slot]; break;
        case PCN_BOOLEAN: ((int *)values)[k] = in->pub.boolean[slot]; break;
        case PCN_STRING: ((const char **)values)[k] = in->pub.string[slot]; break;
        }
    }
    return PCN_OK;
}

pcn_status pcn_set(native *in, const char *fn, const unsigned vr[], size_t nvr, const void *values, pcn_type type)
{
    if (check_vrs(in, fn, vr, nvr, values, type) || refuse_set(in, fn, vr, nvr, values, type)) return PCN_ERROR;
    if (type == PCN_STRING)
        for (size_t k = 0; k < nvr; ++k)
            if (((const char *const *)values)[k] == NULL) {
                pcn_text why;
                pcn_clear(&why);
                pcn_addf(&why, "%s (value reference %u): NULL refused; nothing was set", pcn_variable_of(vr[k])->name,
                         vr[k]);
                return pcn_call_error(in, fn, why.text);
            }
    int parameter = 0;
    for (size_t k = 0; k < nvr; ++k) {
        const pcn_variable *v = pcn_variable_of(vr[k]);
        parameter |= v->causality == PCN_PARAMETER;
        switch (type) {
        case PCN_REAL: in->pub.real[v->slot] = ((const double *)values)[k]; break;
        case PCN_INTEGER: in->pub.integer[v->slot] = ((const int *)values)[k]; break;
        case PCN_BOOLEAN: in->pub.boolean[v->slot] = ((const int *)values)[k] != 0; break;
        case PCN_STRING: pcn_set_string(&in->pub.string[v->slot], ((const char *const *)values)[k]); break;
        }
    }
    if (!in->initialised) {   /* GuardedSlave._parameters_set */
        in->built_for_exit = 0;
        if (parameter) in->initial_outputs = 0;
    }
    return PCN_OK;
}
