/* The generic part's instance and its calls, shared by the FMI layers (fmi2_native.c,
 * fmi3_native.c) and pcn_core.c, pcn_values.c, pcn_state.c (not an adapter's).
 *
 * The core knows no FMI version: a layer turns its FMI calls into these, passing the name
 * of the function called (for messages), and gives the instance its names (pcn_api) and its
 * logger.  Statuses are FMI 2.0's and 3.0's codes, which agree (OK 0 ... Error 3).
 */
#ifndef PCN_NATIVE_H
#define PCN_NATIVE_H

#include <stddef.h>

#include "pcn_model.h"

/* fmus/slave/base.py: MIN_STEP, MAX_TIME, TIME_RESOLUTION. */
#define MIN_STEP 1e-9
#define MAX_TIME 1e9
#define TIME_RESOLUTION 1e-6

typedef enum { PCN_OK = 0, PCN_WARNING = 1, PCN_DISCARD = 2, PCN_ERROR = 3 } pcn_status;

/* A logger of some FMI version, called through its own type by that version's layer. */
typedef void (*pcn_function)(void);

typedef struct native native;

/* What differs between the FMI versions in the core: the functions its messages name, the
 * variable types' names, and how a message reaches the importer's logger. */
typedef struct {
    const char *instantiate, *enter_initialization, *exit_initialization, *terminate, *set_state;
    const char *type_name[4];   /* by pcn_type */
    void (*log)(const native *in, pcn_status status, const char *category, const char *message);
} pcn_api;

struct native {
    pcn_instance pub;          /* first: an adapter's pointer is the instance's */
    const pcn_model *model;
    const pcn_api *api;
    char *name;
    pcn_function logger;       /* the importer's, of the api's FMI version */
    void *env;
    int logging_on;
    char **categories;
    size_t n_categories;
    /* GuardedSlave's flags and times (saved in the FMU state) */
    int initialising, initialised, terminated, ready, initial_outputs, built_for_exit, has_last;
    int step_refused;       /* a step was refused (not the initialisation): later steps say so */
    double next_time, last_step;   /* and pub.start_time */
    double time;            /* the wrapper's time for messages */
    /* derived, not saved */
    int has_accepted;
    double accepted_step;
    int error_slot;         /* the String output "error" */
    int refusal_slot;       /* the String output "refusal" (the record, pcn_record.c) */
    char *initial_warning;
};

/* ---- pcn_core.c ---- */

/* A refused FMI call: logs "<function>: <why> (t = %.9g s)"; returns PCN_ERROR. */
pcn_status pcn_call_error(const native *in, const char *function, const char *why);
/* Forward one message to the logger (errors always, the rest if logging is on for its category). */
void pcn_emit(const native *in, pcn_status status, const char *category, const char *message);
/* The variable of a value reference, NULL if none. */
const pcn_variable *pcn_variable_of(unsigned vr);
/* The string slot's value replaced by a copy of `value`. */
void pcn_set_string(char **slot, const char *value);
/* A new instance with its start values (`resources`, malloc'd, is taken over), or NULL
 * (out of memory: `resources` freed).  The FMI layer checked its arguments before. */
native *pcn_new(const pcn_api *api, const char *name, char *resources, pcn_function logger, void *env,
                int logging_on);
/* An instantiation refused: `why` to the logger as the instance `name` would log it. */
void pcn_refuse_instance(const pcn_api *api, const char *name, pcn_function logger, void *env, const char *why);
void pcn_free(native *in);
pcn_status pcn_set_debug_logging(native *in, const char *fn, int on, size_t n, const char *const categories[]);
pcn_status pcn_setup_experiment(native *in, const char *fn, double start, int stop_defined, double stop);
pcn_status pcn_enter_initialization(native *in, const char *fn);
pcn_status pcn_exit_initialization(native *in, const char *fn);
pcn_status pcn_terminate(native *in);
pcn_status pcn_reset(native *in);
/* One communication step from t by h: PCN_OK, or PCN_DISCARD with the refusal logged. */
pcn_status pcn_do_step(native *in, double t, double h);

/* ---- pcn_record.c ---- */

/* `refusal` := the record of a refusal of `kind` ("refused", "initialisation") with the message
 * `message` (as `error` has it), at `time` unless `why`'s quantity has its own; its fields of
 * the model's quantity if `why` (or NULL) names one. */
void pcn_write_refusal(native *in, const char *kind, const char *message, double time, const pcn_text *why);

/* ---- pcn_values.c: values by type (double, int, int 0/1, const char *) ---- */

pcn_status pcn_get(native *in, const char *fn, const unsigned vr[], size_t nvr, void *values, pcn_type type);
pcn_status pcn_set(native *in, const char *fn, const unsigned vr[], size_t nvr, const void *values, pcn_type type);

/* ---- pcn_state.c: the FMU state as bytes with a checked header ---- */

pcn_status pcn_get_state(native *in, const char *fn, void **state);
pcn_status pcn_set_state(native *in, const char *fn, void *state);
pcn_status pcn_free_state(native *in, const char *fn, void **state);
pcn_status pcn_state_size(native *in, const char *fn, void *state, size_t *size);
pcn_status pcn_serialize(native *in, const char *fn, void *state, unsigned char bytes[], size_t size);
pcn_status pcn_deserialize(native *in, const char *fn, const unsigned char bytes[], size_t size, void **state);

#endif
