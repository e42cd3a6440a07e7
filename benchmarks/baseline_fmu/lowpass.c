/* A minimal FMI 2.0 co-simulation FMU in C: a first-order low-pass y' = (u - y) / tau.
 *
 * The baseline of benchmarks/cold_start.py: what any importer pays to extract, load,
 * initialise and step a small compiled FMU, against which parcosim's FMUs are measured.
 * Each doStep advances the exact solution for u held over the step:
 * y <- u + (y - u) exp(-h / tau).
 * Variables (value references): 0 u (input), 1 y (output), 2 tau (parameter, > 0).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"

#define GUID "{7f1d7a50-3c4e-4b3a-9a55-0c0ffee5ba5e}"
enum { VR_U, VR_Y, VR_TAU, VR_COUNT };

typedef struct {
    double values[VR_COUNT];
    double time;
    fmi2CallbackFunctions callbacks;
    char name[128];   /* a copy: FMI 2.0 does not keep the importer's string alive */
} LowPass;

/* The start values of modelDescription.xml. */
static void set_start_values(LowPass *m)
{
    m->values[VR_U] = 1.0;
    m->values[VR_Y] = 0.0;
    m->values[VR_TAU] = 0.01;
    m->time = 0.0;
}

static void report(LowPass *m, fmi2Status status, const char *message)
{
    if (m->callbacks.logger)
        m->callbacks.logger(m->callbacks.componentEnvironment, m->name, status, "error", message);
}

static int valid(LowPass *m, const fmi2ValueReference vr[], size_t nvr)
{
    for (size_t i = 0; i < nvr; i++)
        if (vr[i] >= VR_COUNT) {
            report(m, fmi2Error, "unknown value reference");
            return 0;
        }
    return 1;
}

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean on, size_t n, const fmi2String cats[])
{
    (void)c; (void)on; (void)n; (void)cats;
    return fmi2OK;
}

fmi2Component fmi2Instantiate(fmi2String name, fmi2Type type, fmi2String guid, fmi2String resources,
                              const fmi2CallbackFunctions *callbacks, fmi2Boolean visible, fmi2Boolean logging)
{
    (void)resources; (void)visible; (void)logging;
    if (type != fmi2CoSimulation || !guid || strcmp(guid, GUID) != 0)
        return NULL;
    LowPass *m = calloc(1, sizeof *m);
    if (!m)
        return NULL;
    m->callbacks = *callbacks;
    snprintf(m->name, sizeof m->name, "%s", name ? name : "");
    set_start_values(m);
    return m;
}

void fmi2FreeInstance(fmi2Component c) { free(c); }

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean tol_defined, fmi2Real tol, fmi2Real start,
                               fmi2Boolean stop_defined, fmi2Real stop)
{
    (void)tol_defined; (void)tol; (void)stop_defined; (void)stop;
    ((LowPass *)c)->time = start;
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c) { (void)c; return fmi2OK; }

fmi2Status fmi2ExitInitializationMode(fmi2Component c)
{
    LowPass *m = c;
    if (!(m->values[VR_TAU] > 0.0)) {
        report(m, fmi2Error, "parameter tau must be > 0");
        return fmi2Error;
    }
    return fmi2OK;
}

fmi2Status fmi2Terminate(fmi2Component c) { (void)c; return fmi2OK; }

fmi2Status fmi2Reset(fmi2Component c)
{
    set_start_values(c);
    return fmi2OK;
}

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Real value[])
{
    LowPass *m = c;
    if (!valid(m, vr, nvr))
        return fmi2Error;
    for (size_t i = 0; i < nvr; i++)
        value[i] = m->values[vr[i]];
    return fmi2OK;
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Real value[])
{
    LowPass *m = c;
    if (!valid(m, vr, nvr))
        return fmi2Error;
    for (size_t i = 0; i < nvr; i++)
        if (!isfinite(value[i])) {   /* refused whole: nothing is written */
            report(m, fmi2Error, "a value that is not finite");
            return fmi2Error;
        }
    for (size_t i = 0; i < nvr; i++)
        m->values[vr[i]] = value[i];
    return fmi2OK;
}

/* No integer, boolean or string variables: any reference is an error, none is fine. */
#define NO_VARIABLES(kind, type, constness)                                                           \
    fmi2Status fmi2##kind(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, constness type v[]) \
    {                                                                                                 \
        (void)vr; (void)v;                                                                            \
        if (nvr == 0)                                                                                 \
            return fmi2OK;                                                                            \
        report(c, fmi2Error, "no such variable");                                                     \
        return fmi2Error;                                                                             \
    }
NO_VARIABLES(GetInteger, fmi2Integer, )
NO_VARIABLES(GetBoolean, fmi2Boolean, )
NO_VARIABLES(GetString, fmi2String, )
NO_VARIABLES(SetInteger, fmi2Integer, const)
NO_VARIABLES(SetBoolean, fmi2Boolean, const)
NO_VARIABLES(SetString, fmi2String, const)

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real t, fmi2Real h, fmi2Boolean no_prior)
{
    (void)no_prior;
    LowPass *m = c;
    if (!(h >= 0.0) || !isfinite(h)) {
        report(m, fmi2Error, "step size must be finite and >= 0");
        return fmi2Error;
    }
    double u = m->values[VR_U];
    m->values[VR_Y] = u + (m->values[VR_Y] - u) * exp(-h / m->values[VR_TAU]);
    m->time = t + h;
    return fmi2OK;
}

/* What this FMU does not support (its model description says so). */
static fmi2Status unsupported(fmi2Component c)
{
    report(c, fmi2Error, "not supported by this FMU");
    return fmi2Error;
}

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *s) { (void)s; return unsupported(c); }
fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate s) { (void)s; return unsupported(c); }
fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *s) { (void)s; return unsupported(c); }
fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate s, size_t *n) { (void)s; (void)n; return unsupported(c); }
fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate s, fmi2Byte b[], size_t n)
{
    (void)s; (void)b; (void)n;
    return unsupported(c);
}
fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte b[], size_t n, fmi2FMUstate *s)
{
    (void)b; (void)n; (void)s;
    return unsupported(c);
}
fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference u[], size_t nu,
                                        const fmi2ValueReference z[], size_t nz, const fmi2Real du[], fmi2Real dz[])
{
    (void)u; (void)nu; (void)z; (void)nz; (void)du; (void)dz;
    return unsupported(c);
}
fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                       const fmi2Integer order[], const fmi2Real value[])
{
    (void)vr; (void)nvr; (void)order; (void)value;
    return unsupported(c);
}
fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                        const fmi2Integer order[], fmi2Real value[])
{
    (void)vr; (void)nvr; (void)order; (void)value;
    return unsupported(c);
}
fmi2Status fmi2CancelStep(fmi2Component c) { return unsupported(c); }
fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind k, fmi2Status *v) { (void)k; (void)v; return unsupported(c); }
fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind k, fmi2Real *v) { (void)k; (void)v; return unsupported(c); }
fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind k, fmi2Integer *v) { (void)k; (void)v; return unsupported(c); }
fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind k, fmi2Boolean *v) { (void)k; (void)v; return unsupported(c); }
fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind k, fmi2String *v) { (void)k; (void)v; return unsupported(c); }
