/* Messages of the native FMUs, worded and formatted as the pythonfmu FMUs' (docs/native.md).
 *
 * Python formats a float in a message with repr() (the shortest string that reads back to the
 * same double) or with format(x, ".6g") or ".3g"; pcn_repr and pcn_addf give the same characters, so a
 * native FMU's refusal is the pythonfmu twin's, byte for byte.  Locale: the C locale's '.'.
 */
#ifndef PCN_TEXT_H
#define PCN_TEXT_H

#include <stddef.h>

#define PCN_TEXT_SIZE 1024
/* Enough for any double's repr ("-2.2250738585072014e-308": 24) and its terminator. */
#define PCN_REPR_SIZE 32

/* What a model's refusal is about (kernels.Refused's fields), for the record in `refusal`
 * (pcn_record.c); reason NULL: not a model's refusal, the record's fields are null. */
typedef struct {
    char variable[64];
    const char *unit, *reason;
    double value;
    int code;
    int has_time;   /* the refusal's own time (else the step's) */
    double time;
} pcn_quantity;

/* A message being written: appends past the capacity are cut (the text stays terminated).
 * As a refusal's why: `names_time` when it names the step's time (kernels.timed: the core adds
 * none), `quantity` when it is a model's refusal.  pcn_clear clears both. */
typedef struct {
    char text[PCN_TEXT_SIZE];
    size_t length;
    int names_time;
    pcn_quantity quantity;
} pcn_text;

/* Python's repr(float(x)) into out[PCN_REPR_SIZE]; returns out. */
char *pcn_repr(double x, char *out);

void pcn_clear(pcn_text *t);
/* Append printf-formatted text, where two conversions of Python are added:
 *   %r  a double, as Python's repr(float),
 *   %G  a double, as Python's format(x, ".6g"),
 *   %g  a double, as Python's format(x, ".3g"),
 *   %B  an int, as Python's repr(bool) (True / False),
 *   %s, %d, %u, %%  as printf. */
void pcn_addf(pcn_text *t, const char *format, ...);
/* t, marked as naming the step's time (kernels.timed): pcn_addf(pcn_timed(why), "... at t = %G s", ..., t). */
pcn_text *pcn_timed(pcn_text *t);
/* t's quantity: a model's refusal `code` named `reason` (static text) of `variable` = `value`
 * [`unit`] (Python's kernels.Refused fields) at the model's `time`, or the step's when NaN. */
void pcn_quantify(pcn_text *t, int code, const char *reason, const char *variable, double value, const char *unit,
                  double time);

#endif
