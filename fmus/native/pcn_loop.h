/* A system's compiled loop as build data (fmus/native/loopimage.py, docs/native.md): the
 * native ClosedLoop's adapter (adapters/pcn_closedloop.c) lays it out in an instance and runs
 * it with pc_loop_run (kernels/src/loop.c).  The generated loop_table.c defines pcn_loop and
 * pcn_loop_fill (loop_contexts.h).
 *
 * Two arenas per instance: the data (8-byte words: every buffer the members' kernels read and
 * write, the stepper's values, each member's x, the loop's step count; saved in the FMU state;
 * its initial words are bit patterns, the same doubles on any IEEE target) and the scratch
 * (the members' contexts, which hold addresses: the struct pcn_loop_contexts, laid out by the
 * compiler and filled by pcn_loop_fill at set-up from C initialisers, never saved). */
#ifndef PCN_LOOP_H
#define PCN_LOOP_H

#include <stdint.h>

#include "loop.h"

typedef struct {
    const char *name, *model, *kernel;   /* the instance, its model, its I/O step */
    long context;                        /* byte offset of its context in pcn_loop_contexts */
    long x;                              /* word offset of its x in the data arena */
} pcn_member;

typedef struct {
    long data_words;
    const uint64_t *data;                /* the data arena's initial words */
    int n_members;
    const pcn_member *members;
    const pc_io_fn *io;
    int n_groups;
    const int *group_substeps, *group_end;
    const int *in_end, *in_x, *in_slot, *out_end, *out_x, *out_slot;
    long values;                         /* word offset of the values (n_values slots) */
    int n_values;
    long steps;                          /* word offset of the steps taken k (a whole double): time k h */
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
