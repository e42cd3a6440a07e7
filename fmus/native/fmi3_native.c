/* The native FMUs' FMI 3.0 co-simulation layer (docs/native.md, "FMI 3.0"): the same core as
 * FMI 2.0's (pcn_core.c, pcn_values.c, pcn_state.c: rules, refusals, messages, the FMU state
 * with its checked header) under FMI 3.0's functions.  What is FMI 3.0's own is here: the
 * instantiation token and a plain resource path, the logger without a format, Enter-
 * InitializationMode with the experiment's times, fmi3DoStep's outputs, Int32 and Boolean
 * arrays of their own types, nValues, the types this FMU has no variable of; the functions
 * of what it does not provide are refused in fmi3_refused.c.
 */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "fmi3Functions.h"
#include "model_config.h"
#include "pcn_native.h"

#define PCN_STR_(x) #x
#define PCN_STR(x) PCN_STR_(x)

/* The core's value references and Integers are unsigned and int. */
_Static_assert(sizeof(fmi3ValueReference) == sizeof(unsigned) && sizeof(fmi3Int32) == sizeof(int),
               "fmi3ValueReference and fmi3Int32 are unsigned int and int");

static void log_fmi3(const native *in, pcn_status status, const char *category, const char *message)
{
    ((fmi3LogMessageCallback)in->logger)(in->env, (fmi3Status)status, category, message);
}

static const pcn_api FMI3 = {"fmi3InstantiateCoSimulation", "fmi3EnterInitializationMode",
                             "fmi3ExitInitializationMode", "fmi3Terminate", "fmi3SetFMUState",
                             {"Float64", "Int32", "Boolean", "String"}, log_fmi3};

/* ---- instances ---- */

static fmi3Instance no_instance(const char *fn, fmi3String name, fmi3InstanceEnvironment env,
                                fmi3LogMessageCallback logger, const char *why)
{
    pcn_text text;
    pcn_clear(&text);
    pcn_addf(&text, "%s: %s", fn, why);
    if (logger) pcn_refuse_instance(&FMI3, name ? name : "", (pcn_function)logger, env, text.text);
    return NULL;
}

fmi3Instance fmi3InstantiateCoSimulation(fmi3String instanceName, fmi3String instantiationToken,
                                         fmi3String resourcePath, fmi3Boolean visible, fmi3Boolean loggingOn,
                                         fmi3Boolean eventModeUsed, fmi3Boolean earlyReturnAllowed,
                                         const fmi3ValueReference requiredIntermediateVariables[],
                                         size_t nRequiredIntermediateVariables,
                                         fmi3InstanceEnvironment instanceEnvironment, fmi3LogMessageCallback logMessage,
                                         fmi3IntermediateUpdateCallback intermediateUpdate)
{
    (void)visible, (void)earlyReturnAllowed, (void)requiredIntermediateVariables, (void)intermediateUpdate;
    const char *fn = "fmi3InstantiateCoSimulation";
    pcn_text why;
    pcn_clear(&why);
    if (instantiationToken == NULL || strcmp(instantiationToken, pcn_guid) != 0)
        pcn_addf(&why, "instantiation token %s is not this FMU's: %s has %s",
                 instantiationToken ? instantiationToken : "(NULL)", pcn_this_model.identifier, pcn_guid);
    else if (eventModeUsed)
        pcn_addf(&why, "eventModeUsed refused: %s has no Event Mode (hasEventMode=\"false\")",
                 pcn_this_model.identifier);
    else if (nRequiredIntermediateVariables > 0)
        pcn_addf(&why, "%d required intermediate variables refused: %s provides no intermediate update",
                 (int)nRequiredIntermediateVariables, pcn_this_model.identifier);
    if (why.length) return no_instance(fn, instanceName, instanceEnvironment, logMessage, why.text);
    const char *path = resourcePath ? resourcePath : "";
    char *resources = malloc(strlen(path) + 1);
    if (resources) strcpy(resources, path);
    native *in = resources ? pcn_new(&FMI3, instanceName ? instanceName : "", resources, (pcn_function)logMessage,
                                     instanceEnvironment, loggingOn)
                           : NULL;
    return in ? in : no_instance(fn, instanceName, instanceEnvironment, logMessage, "out of memory");
}

fmi3Instance fmi3InstantiateModelExchange(fmi3String instanceName, fmi3String instantiationToken,
                                          fmi3String resourcePath, fmi3Boolean visible, fmi3Boolean loggingOn,
                                          fmi3InstanceEnvironment instanceEnvironment,
                                          fmi3LogMessageCallback logMessage)
{
    (void)instantiationToken, (void)resourcePath, (void)visible, (void)loggingOn;
    return no_instance("fmi3InstantiateModelExchange", instanceName, instanceEnvironment, logMessage,
                       "this is a co-simulation FMU only");
}

fmi3Instance fmi3InstantiateScheduledExecution(fmi3String instanceName, fmi3String instantiationToken,
                                               fmi3String resourcePath, fmi3Boolean visible, fmi3Boolean loggingOn,
                                               fmi3InstanceEnvironment instanceEnvironment,
                                               fmi3LogMessageCallback logMessage, fmi3ClockUpdateCallback clockUpdate,
                                               fmi3LockPreemptionCallback lockPreemption,
                                               fmi3UnlockPreemptionCallback unlockPreemption)
{
    (void)instantiationToken, (void)resourcePath, (void)visible, (void)loggingOn, (void)clockUpdate;
    (void)lockPreemption, (void)unlockPreemption;
    return no_instance("fmi3InstantiateScheduledExecution", instanceName, instanceEnvironment, logMessage,
                       "this is a co-simulation FMU only");
}

void fmi3FreeInstance(fmi3Instance instance) { pcn_free(instance); }

const char *fmi3GetVersion(void) { return fmi3Version; }

fmi3Status fmi3SetDebugLogging(fmi3Instance instance, fmi3Boolean loggingOn, size_t nCategories,
                               const fmi3String categories[])
{
    return instance ? (fmi3Status)pcn_set_debug_logging(instance, "fmi3SetDebugLogging", loggingOn, nCategories,
                                                        categories)
                    : fmi3Error;
}

/* FMI 2.0's fmi2SetupExperiment and fmi2EnterInitializationMode in one call. */
fmi3Status fmi3EnterInitializationMode(fmi3Instance instance, fmi3Boolean toleranceDefined, fmi3Float64 tolerance,
                                       fmi3Float64 startTime, fmi3Boolean stopTimeDefined, fmi3Float64 stopTime)
{
    (void)toleranceDefined, (void)tolerance;
    const char *fn = "fmi3EnterInitializationMode";
    if (instance == NULL) return fmi3Error;
    pcn_status status = pcn_setup_experiment(instance, fn, startTime, stopTimeDefined, stopTime);
    return (fmi3Status)(status == PCN_OK ? pcn_enter_initialization(instance, fn) : status);
}

fmi3Status fmi3ExitInitializationMode(fmi3Instance instance)
{
    return instance ? (fmi3Status)pcn_exit_initialization(instance, "fmi3ExitInitializationMode") : fmi3Error;
}

fmi3Status fmi3Terminate(fmi3Instance instance) { return instance ? (fmi3Status)pcn_terminate(instance) : fmi3Error; }
fmi3Status fmi3Reset(fmi3Instance instance) { return instance ? (fmi3Status)pcn_reset(instance) : fmi3Error; }

fmi3Status fmi3DoStep(fmi3Instance instance, fmi3Float64 currentCommunicationPoint,
                      fmi3Float64 communicationStepSize, fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                      fmi3Boolean *eventHandlingNeeded, fmi3Boolean *terminateSimulation, fmi3Boolean *earlyReturn,
                      fmi3Float64 *lastSuccessfulTime)
{
    (void)noSetFMUStatePriorToCurrentPoint;
    if (instance == NULL) return fmi3Error;
    native *in = instance;
    if (eventHandlingNeeded == NULL || terminateSimulation == NULL || earlyReturn == NULL || lastSuccessfulTime == NULL)
        return (fmi3Status)pcn_call_error(in, "fmi3DoStep", "an output pointer (eventHandlingNeeded, "
                                          "terminateSimulation, earlyReturn, lastSuccessfulTime) is NULL");
    pcn_status status = pcn_do_step(in, currentCommunicationPoint, communicationStepSize);
    *eventHandlingNeeded = fmi3False;
    *terminateSimulation = fmi3False;
    *earlyReturn = fmi3False;   /* a step is taken whole or refused whole */
    *lastSuccessfulTime = status == PCN_OK ? in->next_time : currentCommunicationPoint;
    return (fmi3Status)status;
}

/* ---- values ---- */

/* nValues is nValueReferences: every variable is a scalar. */
static int scalar_count(native *in, const char *fn, size_t nvr, size_t nValues)
{
    if (nValues == nvr) return 1;
    pcn_text why;
    pcn_clear(&why);
    pcn_addf(&why, "nValues = %d for %d value references refused: every variable of this FMU is a scalar",
             (int)nValues, (int)nvr);
    pcn_call_error(in, fn, why.text);
    return 0;
}

static fmi3Status get(fmi3Instance instance, const char *fn, const fmi3ValueReference vr[], size_t nvr, void *values,
                      size_t nValues, pcn_type type)
{
    if (instance == NULL) return fmi3Error;
    if (!scalar_count(instance, fn, nvr, nValues)) return fmi3Error;
    return (fmi3Status)pcn_get(instance, fn, (const unsigned *)vr, nvr, values, type);
}

static fmi3Status set(fmi3Instance instance, const char *fn, const fmi3ValueReference vr[], size_t nvr,
                      const void *values, size_t nValues, pcn_type type)
{
    if (instance == NULL) return fmi3Error;
    if (!scalar_count(instance, fn, nvr, nValues)) return fmi3Error;
    return (fmi3Status)pcn_set(instance, fn, (const unsigned *)vr, nvr, values, type);
}

/* FMI 3.0's independent variable "time" (value reference PCN_TIME_VR, model_config.h): the
 * communication point (the start time before initialisation); never set. */
static double time_of(const native *in) { return in->initialised ? in->next_time : in->pub.start_time; }

fmi3Status fmi3GetFloat64(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, fmi3Float64 values[],
                          size_t nValues)
{
    const char *fn = "fmi3GetFloat64";
    int has_time = 0;
    for (size_t k = 0; vr && values && k < nvr; ++k) has_time |= vr[k] == PCN_TIME_VR;
    if (!has_time || instance == NULL) return get(instance, fn, vr, nvr, values, nValues, PCN_REAL);
    if (!scalar_count(instance, fn, nvr, nValues)) return fmi3Error;
    for (size_t k = 0; k < nvr; ++k) {   /* one by one: the core's checks, the same first refusal */
        if (vr[k] == PCN_TIME_VR) values[k] = time_of(instance);
        else if (pcn_get(instance, fn, (const unsigned *)&vr[k], 1, &values[k], PCN_REAL) != PCN_OK) return fmi3Error;
    }
    return fmi3OK;
}
fmi3Status fmi3GetInt32(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, fmi3Int32 values[],
                        size_t nValues)
{
    return get(instance, "fmi3GetInt32", vr, nvr, values, nValues, PCN_INTEGER);
}
fmi3Status fmi3GetString(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, fmi3String values[],
                         size_t nValues)
{
    return get(instance, "fmi3GetString", vr, nvr, (void *)values, nValues, PCN_STRING);
}
fmi3Status fmi3SetFloat64(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                          const fmi3Float64 values[], size_t nValues)
{
    for (size_t k = 0; instance && vr && k < nvr; ++k)
        if (vr[k] == PCN_TIME_VR)
            return (fmi3Status)pcn_call_error(instance, "fmi3SetFloat64",
                                              "value reference " PCN_STR(PCN_TIME_VR) " ('time') is the independent "
                                              "variable: it is never set; nothing was set");
    return set(instance, "fmi3SetFloat64", vr, nvr, values, nValues, PCN_REAL);
}
fmi3Status fmi3SetInt32(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, const fmi3Int32 values[],
                        size_t nValues)
{
    return set(instance, "fmi3SetInt32", vr, nvr, values, nValues, PCN_INTEGER);
}
fmi3Status fmi3SetString(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                         const fmi3String values[], size_t nValues)
{
    return set(instance, "fmi3SetString", vr, nvr, (const void *)values, nValues, PCN_STRING);
}

/* fmi3Boolean is a bool of one byte, the core's Booleans int 0/1: copied through an int array
 * (read as bytes: any nonzero byte is true). */
fmi3Status fmi3GetBoolean(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, fmi3Boolean values[],
                          size_t nValues)
{
    int *ints = calloc(nvr ? nvr : 1, sizeof *ints);
    if (ints == NULL)
        return instance ? (fmi3Status)pcn_call_error(instance, "fmi3GetBoolean", "out of memory") : fmi3Error;
    fmi3Status status = get(instance, "fmi3GetBoolean", vr, nvr, values ? (void *)ints : NULL, nValues, PCN_BOOLEAN);
    for (size_t k = 0; status == fmi3OK && k < nvr; ++k) values[k] = ints[k] != 0;
    free(ints);
    return status;
}
fmi3Status fmi3SetBoolean(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                          const fmi3Boolean values[], size_t nValues)
{
    int *ints = calloc(nvr ? nvr : 1, sizeof *ints);
    if (ints == NULL)
        return instance ? (fmi3Status)pcn_call_error(instance, "fmi3SetBoolean", "out of memory") : fmi3Error;
    const unsigned char *bytes = (const unsigned char *)values;
    for (size_t k = 0; bytes && k < nvr; ++k) ints[k] = bytes[k] != 0;
    fmi3Status status = set(instance, "fmi3SetBoolean", vr, nvr, values ? (const void *)ints : NULL, nValues,
                            PCN_BOOLEAN);
    free(ints);
    return status;
}

/* A type this FMU has no variable of: nothing to get or set, any value reference refused. */
static fmi3Status none_of(fmi3Instance instance, const char *fn, const char *type, const fmi3ValueReference vr[],
                          size_t nvr)
{
    if (instance == NULL) return fmi3Error;
    if (nvr == 0) return fmi3OK;
    native *in = instance;
    pcn_text why;
    pcn_clear(&why);
    const pcn_variable *v = vr ? pcn_variable_of(vr[0]) : NULL;
    if (vr == NULL) pcn_addf(&why, "the value reference array (NULL) with %d values refused", (int)nvr);
    else if (v == NULL) pcn_addf(&why, "value reference %u is not a variable of this FMU", (unsigned)vr[0]);
    else pcn_addf(&why, "value reference %u ('%s') is a %s variable, not a %s", (unsigned)vr[0], v->name,
                  in->api->type_name[v->type], type);
    return (fmi3Status)pcn_call_error(in, fn, why.text);
}

#define NONE_OF(TYPE, CTYPE)                                                                                         \
    fmi3Status fmi3Get##TYPE(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, CTYPE values[],       \
                             size_t nValues)                                                                         \
    {                                                                                                                \
        (void)values, (void)nValues;                                                                                 \
        return none_of(instance, "fmi3Get" #TYPE, #TYPE, vr, nvr);                                                   \
    }                                                                                                                \
    fmi3Status fmi3Set##TYPE(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, const CTYPE values[], \
                             size_t nValues)                                                                         \
    {                                                                                                                \
        (void)values, (void)nValues;                                                                                 \
        return none_of(instance, "fmi3Set" #TYPE, #TYPE, vr, nvr);                                                   \
    }
NONE_OF(Float32, fmi3Float32)
NONE_OF(Int8, fmi3Int8)
NONE_OF(UInt8, fmi3UInt8)
NONE_OF(Int16, fmi3Int16)
NONE_OF(UInt16, fmi3UInt16)
NONE_OF(UInt32, fmi3UInt32)
NONE_OF(Int64, fmi3Int64)
NONE_OF(UInt64, fmi3UInt64)

fmi3Status fmi3GetBinary(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, size_t valueSizes[],
                         fmi3Binary values[], size_t nValues)
{
    (void)valueSizes, (void)values, (void)nValues;
    return none_of(instance, "fmi3GetBinary", "Binary", vr, nvr);
}
fmi3Status fmi3SetBinary(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, const size_t valueSizes[],
                         const fmi3Binary values[], size_t nValues)
{
    (void)valueSizes, (void)values, (void)nValues;
    return none_of(instance, "fmi3SetBinary", "Binary", vr, nvr);
}
fmi3Status fmi3GetClock(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, fmi3Clock values[])
{
    (void)values;
    return none_of(instance, "fmi3GetClock", "Clock", vr, nvr);
}
fmi3Status fmi3SetClock(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, const fmi3Clock values[])
{
    (void)values;
    return none_of(instance, "fmi3SetClock", "Clock", vr, nvr);
}

/* ---- the FMU state (pcn_state.c) ---- */

fmi3Status fmi3GetFMUState(fmi3Instance instance, fmi3FMUState *FMUState)
{
    return instance ? (fmi3Status)pcn_get_state(instance, "fmi3GetFMUState", FMUState) : fmi3Error;
}
fmi3Status fmi3SetFMUState(fmi3Instance instance, fmi3FMUState FMUState)
{
    return instance ? (fmi3Status)pcn_set_state(instance, "fmi3SetFMUState", FMUState) : fmi3Error;
}
fmi3Status fmi3FreeFMUState(fmi3Instance instance, fmi3FMUState *FMUState)
{
    return instance ? (fmi3Status)pcn_free_state(instance, "fmi3FreeFMUState", FMUState) : fmi3Error;
}
fmi3Status fmi3SerializedFMUStateSize(fmi3Instance instance, fmi3FMUState FMUState, size_t *size)
{
    return instance ? (fmi3Status)pcn_state_size(instance, "fmi3SerializedFMUStateSize", FMUState, size) : fmi3Error;
}
fmi3Status fmi3SerializeFMUState(fmi3Instance instance, fmi3FMUState FMUState, fmi3Byte serializedState[],
                                 size_t size)
{
    return instance ? (fmi3Status)pcn_serialize(instance, "fmi3SerializeFMUState", FMUState, serializedState, size)
                    : fmi3Error;
}
fmi3Status fmi3DeserializeFMUState(fmi3Instance instance, const fmi3Byte serializedState[], size_t size,
                                   fmi3FMUState *FMUState)
{
    return instance ? (fmi3Status)pcn_deserialize(instance, "fmi3DeserializeFMUState", serializedState, size,
                                                  FMUState)
                    : fmi3Error;
}
