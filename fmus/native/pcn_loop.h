/* A system's compiled loop as build data (fmus/native/loopimage.py, docs/native.md): the
 * native ClosedLoop's adapter (adapters/pcn_closedloop.c) lays it out in an instance and runs
 * it with pc_loop_run (kernels/src/loop.c).  The generated loop_table.c defines pcn_loop.
 *
 * Two arenas of 8-byte words per instance: the data (every buffer the members' kernels read
 * and write, the stepper's values, each member's x, the loop's time; saved in the FMU state)
 * and the scratch (the members' contexts, which hold addresses: copied from their image and
 * relocated at set-up, never saved). */
#ifndef PCN_LOOP_H
#define PCN_LOOP_H

#include <stdint.h>

#include "loop.h"

enum { PCN_TO_DATA, PCN_TO_SCRATCH, PCN_TO_FUNCTION };

/* A pointer field at byte `at` of the scratch arena: the data or scratch arena's byte
 * `target`, or function number `target`. */
typedef struct {
    long at;
    int kind;
    long target;
} pcn_relocation;

typedef void (*pcn_function)(void);

typedef struct {
    const char *name, *model, *kernel;   /* the instance, its model, its I/O step */
    long context;                        /* byte offset of its context in the scratch arena */
    long x;                              /* word offset of its x in the data arena */
} pcn_member;

typedef struct {
    long data_words, scratch_words;
    const uint64_t *data, *scratch;      /* the arenas' initial words */
    int n_relocations;
    const pcn_relocation *relocations;
    const pcn_function *functions;
    int n_members;
    const pcn_member *members;
    const pc_io_fn *io;
    int n_groups;
    const int *group_substeps, *group_end;
    const int *in_end, *in_x, *in_slot, *out_end, *out_x, *out_slot;
    long values;                         /* word offset of the values (n_values slots) */
    int n_values;
    long time;                           /* word offset of the loop's time */
    int n_outputs;
    const int *output_variable;          /* Real slot of each output ... */
    const int *output_value;             /* ... and the value slot it publishes */
    int n_fixed;
    const long *fixed;                   /* (first word, words) pairs the loop never changes */
    double step;                         /* the system's communication step h [s] */
    long most_steps;                     /* the most steps h in one doStep (the twin's call budget) */
} pcn_loop_table;

extern const pcn_loop_table pcn_loop;

#endif
