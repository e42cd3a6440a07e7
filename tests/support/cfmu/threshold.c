/* A small FMU with Integer and Boolean variables, for the master's typed connections.

   above = enable and u > threshold   (Boolean output, direct feedthrough: its ModelStructure
                                       entry has no dependencies attribute, so it depends on
                                       every input)
   in doStep(t, h): count += k if above (with the inputs at t); y += h u if enable. */
#define NR 3
#define NI 2
#define NB 2
#define NS 0

enum { U, THRESHOLD, Y };
enum { K, COUNT };
enum { ENABLE, ABOVE };

struct Model { int unused; };

#define START_R {0, 0, 0}
#define START_I {0, 0}
#define START_B {0, 0}
#define START_S {""}

#include "skeleton.h"

static void model_outputs(Instance *inst) {
    inst->b[ABOVE] = inst->b[ENABLE] && inst->r[U] > inst->r[THRESHOLD];
}

static int model_exit_init(Instance *inst) {
    inst->i[COUNT] = 0;
    inst->r[Y] = 0.0;
    return 0;
}

static int model_do_step(Instance *inst, fmi2Real t, fmi2Real h) {
    (void)t;
    model_outputs(inst);
    if (inst->b[ABOVE]) inst->i[COUNT] += inst->i[K];
    if (inst->b[ENABLE]) inst->r[Y] += h * inst->r[U];
    return 0;
}
