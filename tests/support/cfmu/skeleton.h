/* The FMI 2.0 co-simulation functions shared by the test FMUs written in C.

   A model file defines, before including this header:
     NR, NI, NB, NS      how many Real, Integer, Boolean, String variables it has
                         (value reference k of a type is index k of its array);
     struct Model        its own state;
     START_R, START_I, START_B, START_S   start values (initialisers of arrays);
     model_exit_init(Instance *)           0, or 1 after setting inst->message;
     model_do_step(Instance *, double t, double h)   likewise;
     model_outputs(Instance *)             outputs that depend directly on inputs.
   No FMU state (canGetAndSetFMUstate = false): those calls return fmi2Error. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"

typedef struct Instance {
    fmi2Real r[NR > 0 ? NR : 1];
    fmi2Integer i[NI > 0 ? NI : 1];
    fmi2Boolean b[NB > 0 ? NB : 1];
    char *s[NS > 0 ? NS : 1];
    fmi2Real time;
    int failed;
    char message[512];
    char *name;
    fmi2CallbackFunctions callbacks;
    struct Model m;
} Instance;

static int model_exit_init(Instance *inst);
static int model_do_step(Instance *inst, fmi2Real t, fmi2Real h);
static void model_outputs(Instance *inst);

static char *copy_string(const char *text) {
    char *copy = malloc(strlen(text) + 1);
    strcpy(copy, text);
    return copy;
}

static fmi2Status refuse(Instance *inst, fmi2Status status) {
    inst->callbacks.logger(inst->callbacks.componentEnvironment, inst->name, status, "logStatusError",
                           "%s", inst->message);
    return status;
}

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Component fmi2Instantiate(fmi2String name, fmi2Type type, fmi2String guid, fmi2String resources,
                              const fmi2CallbackFunctions *callbacks, fmi2Boolean visible, fmi2Boolean logging) {
    static const fmi2Real start_r[] = START_R;
    static const fmi2Integer start_i[] = START_I;
    static const fmi2Boolean start_b[] = START_B;
    static const char *start_s[] = START_S;
    Instance *inst;
    int k;
    if (type != fmi2CoSimulation) return NULL;
    inst = calloc(1, sizeof(Instance));
    inst->callbacks = *callbacks;
    inst->name = copy_string(name);
    for (k = 0; k < NR; k++) inst->r[k] = start_r[k];
    for (k = 0; k < NI; k++) inst->i[k] = start_i[k];
    for (k = 0; k < NB; k++) inst->b[k] = start_b[k];
    for (k = 0; k < NS; k++) inst->s[k] = copy_string(start_s[k]);
    (void)guid; (void)resources; (void)visible; (void)logging;
    return inst;
}

void fmi2FreeInstance(fmi2Component c) {
    Instance *inst = c;
    int k;
    if (!inst) return;
    for (k = 0; k < NS; k++) free(inst->s[k]);
    free(inst->name);
    free(inst);
}

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean on, size_t n, const fmi2String cats[]) {
    (void)c; (void)on; (void)n; (void)cats;
    return fmi2OK;
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean tolDefined, fmi2Real tol, fmi2Real start,
                               fmi2Boolean stopDefined, fmi2Real stop) {
    ((Instance *)c)->time = start;
    (void)tolDefined; (void)tol; (void)stopDefined; (void)stop;
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c) { (void)c; return fmi2OK; }

fmi2Status fmi2ExitInitializationMode(fmi2Component c) {
    Instance *inst = c;
    if (model_exit_init(inst)) {
        inst->failed = 1;
        return refuse(inst, fmi2Error);
    }
    model_outputs(inst);
    return fmi2OK;
}

fmi2Status fmi2Terminate(fmi2Component c) { (void)c; return fmi2OK; }
fmi2Status fmi2Reset(fmi2Component c) { (void)c; return fmi2Error; }

#define BOUNDS(n) for (k = 0; k < nvr; k++) if (vr[k] >= (n)) return fmi2Error;

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Real value[]) {
    Instance *inst = c;
    size_t k;
    BOUNDS(NR)
    model_outputs(inst);
    for (k = 0; k < nvr; k++) value[k] = inst->r[vr[k]];
    return fmi2OK;
}

fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Integer value[]) {
    Instance *inst = c;
    size_t k;
    BOUNDS(NI)
    model_outputs(inst);
    for (k = 0; k < nvr; k++) value[k] = inst->i[vr[k]];
    return fmi2OK;
}

fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Boolean value[]) {
    Instance *inst = c;
    size_t k;
    BOUNDS(NB)
    model_outputs(inst);
    for (k = 0; k < nvr; k++) value[k] = inst->b[vr[k]];
    return fmi2OK;
}

fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2String value[]) {
    Instance *inst = c;
    size_t k;
    BOUNDS(NS)
    for (k = 0; k < nvr; k++) value[k] = inst->s[vr[k]];
    return fmi2OK;
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Real value[]) {
    Instance *inst = c;
    size_t k;
    BOUNDS(NR)
    for (k = 0; k < nvr; k++) inst->r[vr[k]] = value[k];
    return fmi2OK;
}

fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Integer value[]) {
    Instance *inst = c;
    size_t k;
    BOUNDS(NI)
    for (k = 0; k < nvr; k++) inst->i[vr[k]] = value[k];
    return fmi2OK;
}

fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Boolean value[]) {
    Instance *inst = c;
    size_t k;
    BOUNDS(NB)
    for (k = 0; k < nvr; k++) inst->b[vr[k]] = value[k];
    return fmi2OK;
}

fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2String value[]) {
    Instance *inst = c;
    size_t k;
    BOUNDS(NS)
    for (k = 0; k < nvr; k++) {
        free(inst->s[vr[k]]);
        inst->s[vr[k]] = copy_string(value[k]);
    }
    return fmi2OK;
}

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real t, fmi2Real h, fmi2Boolean noSetPrior) {
    Instance *inst = c;
    (void)noSetPrior;
    if (inst->failed) return refuse(inst, fmi2Error);
    if (model_do_step(inst, t, h)) {
        inst->failed = 1;
        return refuse(inst, fmi2Discard);
    }
    inst->time = t + h;
    return fmi2OK;
}

fmi2Status fmi2CancelStep(fmi2Component c) { (void)c; return fmi2Error; }

fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status *value) {
    (void)c; (void)s; (void)value; return fmi2Discard;
}
fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real *value) {
    (void)c; (void)s; (void)value; return fmi2Discard;
}
fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer *value) {
    (void)c; (void)s; (void)value; return fmi2Discard;
}
fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean *value) {
    (void)c; (void)s; (void)value; return fmi2Discard;
}
fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String *value) {
    (void)c; (void)s; (void)value; return fmi2Discard;
}

fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                                       const fmi2Integer order[], const fmi2Real value[]) {
    (void)c; (void)vr; (void)n; (void)order; (void)value; return fmi2Error;
}
fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                                        const fmi2Integer order[], fmi2Real value[]) {
    (void)c; (void)vr; (void)n; (void)order; (void)value; return fmi2Error;
}
fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference u[], size_t nu,
                                        const fmi2ValueReference z[], size_t nz, const fmi2Real du[],
                                        fmi2Real dz[]) {
    (void)c; (void)u; (void)nu; (void)z; (void)nz; (void)du; (void)dz; return fmi2Error;
}

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *s) { (void)c; (void)s; return fmi2Error; }
fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate s) { (void)c; (void)s; return fmi2Error; }
fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *s) { (void)c; (void)s; return fmi2Error; }
fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate s, size_t *n) {
    (void)c; (void)s; (void)n; return fmi2Error;
}
fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate s, fmi2Byte b[], size_t n) {
    (void)c; (void)s; (void)b; (void)n; return fmi2Error;
}
fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte b[], size_t n, fmi2FMUstate *s) {
    (void)c; (void)b; (void)n; (void)s; return fmi2Error;
}
