/* Python's float repr and ".6g" for the native FMUs' messages (pcn_text.h). */
#include "pcn_text.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The decimal digits and exponent of "%.*e" of x (x finite, non-zero, positive). */
static void scientific(double x, int digits, char *mantissa, int *exponent)
{
    char buf[64];
    snprintf(buf, sizeof buf, "%.*e", digits - 1, x);
    char *e = strchr(buf, 'e');
    *exponent = atoi(e + 1);
    size_t k = 0;
    for (char *p = buf; p < e; ++p)
        if (*p != '.') mantissa[k++] = *p;
    mantissa[k] = '\0';
}

/* The double that "0.<digits> x 10^(exponent+1)" reads as. */
static double read_back(const char *digits, int exponent)
{
    char buf[96];
    snprintf(buf, sizeof buf, "%c.%.24se%d", digits[0], digits + 1, exponent);
    return strtod(buf, NULL);
}

/* Add one unit in the last place of a digit string (may carry into a new leading digit). */
static void bump(char *digits, int *exponent, int up)
{
    size_t n = strlen(digits);
    for (size_t k = n; k-- > 0;) {
        if (up ? digits[k] < '9' : digits[k] > '0') {
            digits[k] = (char)(digits[k] + (up ? 1 : -1));
            return;
        }
        digits[k] = up ? '0' : '9';
    }
    if (up) {   /* 99..9 + 1: one more place */
        memmove(digits + 1, digits, n + 1);
        digits[0] = '1';
        digits[n] = '\0';
        *exponent += 1;
    }
}

/* The shortest digits (no trailing zero) that read back to x, and the decimal exponent of the
 * first digit: Python's repr (David Gay's shortest mode; among strings of that length, the
 * nearest to x). */
static void shortest(double x, char *digits, int *exponent)
{
    for (int n = 1; n <= 17; ++n) {
        scientific(x, n, digits, exponent);
        if (read_back(digits, *exponent) == x) break;
        /* the nearest n digits miss x's interval but a neighbour may hit it (at a power of two
         * the interval is lopsided) */
        char other[64];
        int e2 = *exponent;
        strcpy(other, digits);
        bump(other, &e2, x > read_back(digits, *exponent));
        if (strlen(other) == (size_t)n && other[0] != '0' && read_back(other, e2) == x) {
            strcpy(digits, other);
            *exponent = e2;
            break;
        }
    }
    size_t k = strlen(digits);
    while (k > 1 && digits[k - 1] == '0') digits[--k] = '\0';
}

char *pcn_repr(double x, char *out)
{
    if (isnan(x)) return strcpy(out, "nan");
    if (isinf(x)) return strcpy(out, x > 0 ? "inf" : "-inf");
    if (x == 0.0) return strcpy(out, signbit(x) ? "-0.0" : "0.0");
    char digits[64], *o = out;
    int exponent;
    if (x < 0) *o++ = '-';
    shortest(fabs(x), digits, &exponent);
    int n = (int)strlen(digits), point = exponent + 1;   /* digits before the point */
    if (point > -4 && point <= 16) {                       /* Python's repr: fixed notation */
        if (point <= 0) {
            o += sprintf(o, "0.%.*s%s", -point, "0000", digits);
        } else if (point >= n) {
            o += sprintf(o, "%s%.*s.0", digits, point - n, "0000000000000000");
        } else {
            o += sprintf(o, "%.*s.%s", point, digits, digits + point);
        }
    } else {
        o += sprintf(o, "%c%s%s", digits[0], n > 1 ? "." : "", digits + 1);
        sprintf(o, "e%c%02d", exponent < 0 ? '-' : '+', abs(exponent));
    }
    return out;
}

void pcn_clear(pcn_text *t)
{
    t->text[0] = '\0';
    t->length = 0;
    t->names_time = 0;
    t->quantity = (pcn_quantity){0};
}

pcn_text *pcn_timed(pcn_text *t)
{
    t->names_time = 1;
    return t;
}

void pcn_quantify(pcn_text *t, int code, const char *reason, const char *variable, double value, const char *unit,
                  double time)
{
    pcn_quantity *q = &t->quantity;
    snprintf(q->variable, sizeof q->variable, "%s", variable);
    q->unit = unit;
    q->reason = reason;
    q->value = value;
    q->code = code;
    q->has_time = !isnan(time);
    q->time = time;
}

static void append(pcn_text *t, const char *s)
{
    size_t room = PCN_TEXT_SIZE - 1 - t->length, n = strlen(s);
    if (n > room) n = room;
    memcpy(t->text + t->length, s, n);
    t->length += n;
    t->text[t->length] = '\0';
}

/* Python's format(x, ".<digits>g"): C's %.*g, but "nan" without C's sign of a NaN. */
static void general(double x, int digits, char *out)
{
    if (isnan(x)) strcpy(out, "nan");
    else snprintf(out, PCN_REPR_SIZE, "%.*g", digits, x);
}

void pcn_addf(pcn_text *t, const char *format, ...)
{
    va_list ap;
    char piece[PCN_TEXT_SIZE];
    va_start(ap, format);
    for (const char *p = format; *p; ++p) {
        if (*p != '%') {
            const char *end = strchr(p, '%');
            size_t n = end ? (size_t)(end - p) : strlen(p);
            snprintf(piece, sizeof piece, "%.*s", (int)n, p);
            append(t, piece);
            p += n - 1;
            continue;
        }
        switch (*++p) {
        case 'r': pcn_repr(va_arg(ap, double), piece); break;
        case 'G': general(va_arg(ap, double), 6, piece); break;
        case 'g': general(va_arg(ap, double), 3, piece); break;
        case 'B': strcpy(piece, va_arg(ap, int) ? "True" : "False"); break;
        case 's': snprintf(piece, sizeof piece, "%s", va_arg(ap, const char *)); break;
        case 'd': snprintf(piece, sizeof piece, "%d", va_arg(ap, int)); break;
        case 'u': snprintf(piece, sizeof piece, "%u", va_arg(ap, unsigned)); break;
        case '%': strcpy(piece, "%"); break;
        default: strcpy(piece, "?"); --p; break;   /* a format of this project's own: never */
        }
        append(t, piece);
        if (!*p) break;
    }
    va_end(ap);
}
