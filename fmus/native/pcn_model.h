/* The native FMUs' interface between the one generic co-simulation core (pcn_core.c, under an
 * FMI 2.0 or 3.0 layer) and a model's adapter (adapters/<model>.c) over its kernel (docs/native.md).
 *
 * Each FMU is compiled from the core, its FMI layer (fmi2_native.c or fmi3_native.c), its
 * adapter, the kernels it uses and one generated file, model_table.c: the variable table (from the pythonfmu slave's
 * declarations: names, value references, types, causality, start values), the model's
 * identity (identifier, GUID) and the data its build computed (designs, presets), as
 * constants.  The instance holds every variable's value in one array per type, in table
 * order; an adapter reads them by the slots the generated header names
 * (PCN_<MODEL>_<variable>).
 */
#ifndef PCN_MODEL_H
#define PCN_MODEL_H

#include "pcn_text.h"

typedef enum { PCN_REAL, PCN_INTEGER, PCN_BOOLEAN, PCN_STRING } pcn_type;
typedef enum { PCN_INPUT, PCN_OUTPUT, PCN_PARAMETER } pcn_causality;

/* One variable: its value lives in the instance's array of its type at `slot`. */
typedef struct {
    const char *name;
    unsigned vr;
    pcn_type type;
    pcn_causality causality;
    int tunable;               /* a parameter settable after initialisation */
    int slot;
    double start;              /* Real, Integer, Boolean */
    const char *start_string;  /* String */
} pcn_variable;

typedef struct pcn_instance pcn_instance;

/* A model's adapter.  Each hook that refuses writes the reason into `why` (the pythonfmu
 * slave's ValueError text) and returns nonzero; the generic part adds the FMI wording. */
typedef struct {
    const char *identifier;          /* the model name (the slave class) */
    const char *accepted_steps;      /* GuardedSlave.accepted_steps() */
    /* ... if it depends on the parameters (the drives' mode), or NULL. */
    const char *(*accepted_steps_of)(const pcn_instance *in);
    long data_words;                 /* doubles of model data the FMU state saves */
    long scratch_words;              /* doubles of scratch (not saved) */
    /* Build the model from the parameters (GuardedSlave.setup). */
    int (*setup)(pcn_instance *in, pcn_text *why);
    /* The model's rule for h beyond the generic one (check_step_size), or NULL. */
    int (*check_step)(pcn_instance *in, double t, double h, pcn_text *why);
    /* Advance the model from t by h (GuardedSlave.step); on a refusal nothing changed. */
    int (*step)(pcn_instance *in, double t, double h, pcn_text *why);
    /* Whether saved model data fits this instance (configuration words equal). */
    int (*check_data)(const pcn_instance *in, const double *data, pcn_text *why);
} pcn_model;

/* The generated table (model_table.c). */
extern const pcn_model pcn_this_model;
extern const pcn_variable pcn_variables[];
extern const int pcn_n_variables;
extern const int pcn_n_slots[4];      /* values of each pcn_type */
extern const char pcn_guid[];

/* What an adapter may touch of an instance. */
struct pcn_instance {
    double *real;          /* Real values, by slot */
    int *integer;          /* Integer values, by slot */
    int *boolean;          /* Boolean values (0/1), by slot */
    char **string;         /* String values (malloc'd), by slot */
    double *data;          /* the model data (saved in the FMU state) */
    double *scratch;       /* the model scratch (not saved) */
    const char *resources; /* the resources folder (a path), "" if none was given */
    double start_time;     /* the experiment's startTime (fmi2SetupExperiment, fmi3EnterInitializationMode) */
};

/* The step-size message of GuardedSlave.step_size_message. */
void pcn_step_size_message(const pcn_instance *in, pcn_text *why, double t, double h, const char *because);

#endif
