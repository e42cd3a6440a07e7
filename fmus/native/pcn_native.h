/* The generic part's instance, shared by fmi2_native.c and pcn_state.c (not an adapter's). */
#ifndef PCN_NATIVE_H
#define PCN_NATIVE_H

#include "fmi2Functions.h"
#include "pcn_model.h"

/* fmus/slave/base.py: MIN_STEP, MAX_TIME, TIME_RESOLUTION. */
#define MIN_STEP 1e-9
#define MAX_TIME 1e9
#define TIME_RESOLUTION 1e-6

typedef struct {
    pcn_instance pub;          /* first: an adapter's pointer is the instance's */
    const pcn_model *model;
    char *name;
    fmi2CallbackLogger logger;
    fmi2ComponentEnvironment env;
    int logging_on;
    char **categories;
    size_t n_categories;
    /* GuardedSlave's flags and times (saved in the FMU state) */
    int initialising, initialised, terminated, ready, initial_outputs, built_for_exit, has_last;
    double next_time, last_step;   /* and pub.start_time */
    double time;            /* the wrapper's time for messages */
    /* derived, not saved */
    int has_accepted;
    double accepted_step;
    int error_slot;         /* the String output "error" */
    char *initial_warning;
} native;

/* A refused FMI call: logs "<function>: <why> (t = %.9g s)"; returns fmi2Error. */
fmi2Status pcn_call_error(const native *in, const char *function, const char *why);
/* Forward one message to the logger (errors always, the rest if logging is on for its category). */
void pcn_emit(const native *in, fmi2Status status, const char *category, const char *message);
/* The variable of a value reference, NULL if none. */
const pcn_variable *pcn_variable_of(unsigned vr);
/* The string slot's value replaced by a copy of `value`. */
void pcn_set_string(char **slot, const char *value);

#endif
