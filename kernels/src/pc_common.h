/* Conventions shared by every parcosim kernel (docs/kernels.md).
 *
 * A model's header declares three structs of plain doubles with named fields:
 *   <model>_params  read-only after set-up (sizes, gains, designs, tables),
 *   <model>_state   what a step advances and FMU state saves,
 *   <model>_scratch caller-owned working storage (never saved),
 * and its step, `int <model>_step(const params *, state *, scratch *, inputs..., outputs...,
 * pc_refusal *)`.  A step allocates nothing, does no I/O and touches no global or static
 * mutable data; the caller (Python through ctypes, an FMU) owns every byte.
 *
 * The return is PC_OK or a model's refusal code; on a refusal the step has changed nothing
 * in the state and `refusal` names the offending quantity (an index into the model's
 * documented list of quantities, and its value).  The Python layer turns that record into
 * one message (kernels.refusal).
 */
#ifndef PC_COMMON_H
#define PC_COMMON_H

#include <math.h>
#include <stddef.h>

#define PC_OK 0

/* What a refused call reports: the model's code, which quantity (index in the model's list,
 * e.g. the input or the channel), and its value. */
typedef struct {
    int code;
    int index;
    double value;
} pc_refusal;

static inline int pc_refuse(pc_refusal *r, int code, int index, double value)
{
    if (r) {
        r->code = code;
        r->index = index;
        r->value = value;
    }
    return code;
}

/* floor(x) inline (at -O2/-O3 without SSE4.1, floor is a libm call): below 2^52 by truncation,
 * one down when that rounded up, the sign of x kept (floor(-0) = -0, floor(0.5) = +0), so the
 * same bits as floor; libm's from 2^52 on and for NaN and inf. */
static inline double pc_floor(double x)
{
    if (!(fabs(x) < 0x1p52)) return floor(x);
    const double t = (double)(long long)x;
    return copysign(t > x ? t - 1.0 : t, x);
}

/* A field list for the Python layer: name and offset in doubles of each field of a struct
 * made of doubles only, so that numpy's float64 buffers and the C structs share one layout. */
typedef struct {
    const char *name;
    int offset;   /* in doubles */
    int count;    /* doubles */
} pc_field;

#define PC_FIELD(type, field) \
    { #field, (int)(offsetof(type, field) / sizeof(double)), (int)(sizeof(((type *)0)->field) / sizeof(double)) }

/* The uniform I/O step of the compiled loop (kernels/src/loop.c): `context` points to the
 * model's buffers, `x` holds the model's inputs then outputs (its adapter names them). */
typedef int (*pc_io_fn)(void *context, double *x, double t, double h, pc_refusal *refusal);

#endif
