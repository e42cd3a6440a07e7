/* The native FMUs' FMI 2.0 co-simulation layer (docs/native.md): each fmi2 function is a call
 * of the core (pcn_core.c, pcn_values.c, pcn_state.c) naming itself; this file holds what is
 * FMI 2.0's own: fmi2Instantiate's arguments (fmuType, GUID, a file: URI), the logger's printf
 * format, the types' names in messages and the functions this FMU does not provide.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"
#include "pcn_native.h"

/* The logger takes a printf format: every '%' doubled (the wrapper's rule). */
static void log_fmi2(const native *in, pcn_status status, const char *category, const char *message)
{
    size_t n = 0;
    for (const char *p = message; *p; ++p) n += *p == '%' ? 2 : 1;
    char *format = malloc(n + 1), *o = format;
    if (format == NULL) return;
    for (const char *p = message; *p; ++p) {
        *o++ = *p;
        if (*p == '%') *o++ = '%';
    }
    *o = '\0';
    ((fmi2CallbackLogger)in->logger)(in->env, in->name, (fmi2Status)status, category, format);
    free(format);
}

static const pcn_api FMI2 = {"fmi2Instantiate", "fmi2EnterInitializationMode", "fmi2ExitInitializationMode",
                             "fmi2Terminate", "fmi2SetFMUstate", {"Real", "Integer", "Boolean", "String"}, log_fmi2};

/* The path of a file: URI (file:///p, file:/p, file://localhost/p), %XX decoded; NULL if
 * another scheme. */
static char *resource_path(const char *uri)
{
    if (uri == NULL) return calloc(1, 1);
    const char *p = NULL;
    if (strncmp(uri, "file://localhost/", 17) == 0) p = uri + 16;
    else if (strncmp(uri, "file:///", 8) == 0) p = uri + 7;
    else if (strncmp(uri, "file:/", 6) == 0) p = uri + 5;
    else return NULL;
    char *out = malloc(strlen(p) + 1), *o = out;
    if (out == NULL) return NULL;
    for (; *p; ++p) {
        unsigned code;
        if (p[0] == '%' && p[1] && p[2] && sscanf(p + 1, "%2x", &code) == 1) {
            *o++ = (char)code;
            p += 2;
        } else {
            *o++ = *p;
        }
    }
    *o = '\0';
    return out;
}

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation, const fmi2CallbackFunctions *functions,
                              fmi2Boolean visible, fmi2Boolean loggingOn)
{
    (void)visible;
    const char *name = instanceName ? instanceName : "";
    pcn_function logger = functions ? (pcn_function)functions->logger : NULL;
    void *env = functions ? functions->componentEnvironment : NULL;
    pcn_text why;
    pcn_clear(&why);
    if (fmuType != fmi2CoSimulation)
        pcn_addf(&why, "fmi2Instantiate: %s is a co-simulation FMU only (fmuType %d refused)",
                 pcn_this_model.identifier, (int)fmuType);
    else if (fmuGUID == NULL || strcmp(fmuGUID, pcn_guid) != 0)
        pcn_addf(&why, "fmi2Instantiate: GUID %s is not this FMU's: %s has GUID %s", fmuGUID ? fmuGUID : "(NULL)",
                 pcn_this_model.identifier, pcn_guid);
    char *resources = why.length ? NULL : resource_path(fmuResourceLocation);
    if (why.length == 0 && resources == NULL)
        pcn_addf(&why, "fmi2Instantiate: the resource location %s is not a file: URI", fmuResourceLocation);
    native *in = why.length ? NULL : pcn_new(&FMI2, name, resources, logger, env, loggingOn);
    if (in != NULL) return in;
    if (why.length == 0) pcn_addf(&why, "fmi2Instantiate: out of memory");
    if (logger) pcn_refuse_instance(&FMI2, name, logger, env, why.text);
    return NULL;
}

void fmi2FreeInstance(fmi2Component c) { pcn_free(c); }

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories,
                               const fmi2String categories[])
{
    return c ? (fmi2Status)pcn_set_debug_logging(c, "fmi2SetDebugLogging", loggingOn, nCategories, categories)
             : fmi2Error;
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined, fmi2Real tolerance,
                               fmi2Real startTime, fmi2Boolean stopTimeDefined, fmi2Real stopTime)
{
    (void)toleranceDefined, (void)tolerance;
    return c ? (fmi2Status)pcn_setup_experiment(c, "fmi2SetupExperiment", startTime, stopTimeDefined, stopTime)
             : fmi2Error;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c)
{
    return c ? (fmi2Status)pcn_enter_initialization(c, "fmi2EnterInitializationMode") : fmi2Error;
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c)
{
    return c ? (fmi2Status)pcn_exit_initialization(c, "fmi2ExitInitializationMode") : fmi2Error;
}

fmi2Status fmi2Terminate(fmi2Component c) { return c ? (fmi2Status)pcn_terminate(c) : fmi2Error; }
fmi2Status fmi2Reset(fmi2Component c) { return c ? (fmi2Status)pcn_reset(c) : fmi2Error; }

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real t, fmi2Real h, fmi2Boolean noSetFMUStatePriorToCurrentPoint)
{
    (void)noSetFMUStatePriorToCurrentPoint;
    return c ? (fmi2Status)pcn_do_step(c, t, h) : fmi2Error;
}

fmi2Status fmi2CancelStep(fmi2Component c)
{
    return c ? (fmi2Status)pcn_call_error(c, "fmi2CancelStep", "not supported: doStep never returns fmi2Pending")
             : fmi2Error;
}

/* ---- values: fmi2Integer and fmi2Boolean are int, the core's ---- */

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Real value[])
{
    return c ? (fmi2Status)pcn_get(c, "fmi2GetReal", vr, nvr, value, PCN_REAL) : fmi2Error;
}
fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Integer value[])
{
    return c ? (fmi2Status)pcn_get(c, "fmi2GetInteger", vr, nvr, value, PCN_INTEGER) : fmi2Error;
}
fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Boolean value[])
{
    return c ? (fmi2Status)pcn_get(c, "fmi2GetBoolean", vr, nvr, value, PCN_BOOLEAN) : fmi2Error;
}
fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2String value[])
{
    return c ? (fmi2Status)pcn_get(c, "fmi2GetString", vr, nvr, (void *)value, PCN_STRING) : fmi2Error;
}
fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Real value[])
{
    return c ? (fmi2Status)pcn_set(c, "fmi2SetReal", vr, nvr, value, PCN_REAL) : fmi2Error;
}
fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Integer value[])
{
    return c ? (fmi2Status)pcn_set(c, "fmi2SetInteger", vr, nvr, value, PCN_INTEGER) : fmi2Error;
}
fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Boolean value[])
{
    return c ? (fmi2Status)pcn_set(c, "fmi2SetBoolean", vr, nvr, value, PCN_BOOLEAN) : fmi2Error;
}
fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2String value[])
{
    return c ? (fmi2Status)pcn_set(c, "fmi2SetString", vr, nvr, (const void *)value, PCN_STRING) : fmi2Error;
}

/* ---- the FMU state (pcn_state.c) ---- */

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *state)
{
    return c ? (fmi2Status)pcn_get_state(c, "fmi2GetFMUstate", state) : fmi2Error;
}
fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate state)
{
    return c ? (fmi2Status)pcn_set_state(c, "fmi2SetFMUstate", state) : fmi2Error;
}
fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *state)
{
    return c ? (fmi2Status)pcn_free_state(c, "fmi2FreeFMUstate", state) : fmi2Error;
}
fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate state, size_t *size)
{
    return c ? (fmi2Status)pcn_state_size(c, "fmi2SerializedFMUstateSize", state, size) : fmi2Error;
}
fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate state, fmi2Byte bytes[], size_t size)
{
    return c ? (fmi2Status)pcn_serialize(c, "fmi2SerializeFMUstate", state, (unsigned char *)bytes, size)
             : fmi2Error;
}
fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte bytes[], size_t size, fmi2FMUstate *state)
{
    return c ? (fmi2Status)pcn_deserialize(c, "fmi2DeSerializeFMUstate", (const unsigned char *)bytes, size, state)
             : fmi2Error;
}

/* ---- co-simulation functions this FMU does not provide ---- */

static fmi2Status unsupported(fmi2Component c, const char *fn)
{
    return c ? (fmi2Status)pcn_call_error(c, fn, "not supported by this FMU") : fmi2Error;
}

fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference vUnknown_ref[], size_t nUnknown,
                                        const fmi2ValueReference vKnown_ref[], size_t nKnown,
                                        const fmi2Real dvKnown[], fmi2Real dvUnknown[])
{
    (void)vUnknown_ref, (void)nUnknown, (void)vKnown_ref, (void)nKnown, (void)dvKnown, (void)dvUnknown;
    return unsupported(c, "fmi2GetDirectionalDerivative");
}
fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                       const fmi2Integer order[], const fmi2Real value[])
{
    (void)vr, (void)nvr, (void)order, (void)value;
    return unsupported(c, "fmi2SetRealInputDerivatives");
}
fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                        const fmi2Integer order[], fmi2Real value[])
{
    (void)vr, (void)nvr, (void)order, (void)value;
    return unsupported(c, "fmi2GetRealOutputDerivatives");
}
static fmi2Status no_status(fmi2Component c, const char *fn)
{
    return c ? (fmi2Status)pcn_call_error(c, fn, "no asynchronous doStep: there is no status to ask for") : fmi2Error;
}
fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status *value)
{
    (void)s, (void)value;
    return no_status(c, "fmi2GetStatus");
}
fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real *value)
{
    (void)s, (void)value;
    return no_status(c, "fmi2GetRealStatus");
}
fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer *value)
{
    (void)s, (void)value;
    return no_status(c, "fmi2GetIntegerStatus");
}
fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean *value)
{
    (void)s, (void)value;
    return no_status(c, "fmi2GetBooleanStatus");
}
fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String *value)
{
    (void)s, (void)value;
    return no_status(c, "fmi2GetStringStatus");
}
