/* The refusal's record, the String output `refusal`, as the pythonfmu twin writes it
 * (fmus.status.RunError.to_json: json.dumps(record, allow_nan=False) with its defaults,
 * ", " and ": " separators and ensure_ascii): the keys kind, message, instance, time, variable,
 * value, unit, code, reason in that order, None as null, a finite float as its repr, a
 * non-finite one as the string "inf", "-inf" or "nan", a string with json's escapes (\", \\,
 * \n, \r, \t, \b, \f, \u00XX below 0x20, \uXXXX past ASCII, a surrogate pair past U+FFFF).
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "pcn_native.h"

typedef struct {
    char *text;
    size_t length, capacity;
    int failed;
} json;

static void put(json *j, const char *s, size_t n)
{
    if (j->failed) return;
    if (j->length + n + 1 > j->capacity) {
        size_t capacity = 2 * (j->length + n + 1) + 64;
        char *grown = realloc(j->text, capacity);
        if (grown == NULL) {
            j->failed = 1;
            return;
        }
        j->text = grown;
        j->capacity = capacity;
    }
    memcpy(j->text + j->length, s, n);
    j->length += n;
    j->text[j->length] = '\0';
}

static void puts_(json *j, const char *s) { put(j, s, strlen(s)); }

static void put_unit(json *j, uint32_t u)
{
    char escape[16];
    snprintf(escape, sizeof escape, "\\u%04x", (unsigned)u);
    puts_(j, escape);
}

/* One code point of UTF-8 at s (length *n), U+FFFD for a byte that starts none. */
static uint32_t decode(const unsigned char *s, size_t *n)
{
    uint32_t c = s[0];
    size_t more = (c & 0xE0) == 0xC0 ? 1 : (c & 0xF0) == 0xE0 ? 2 : (c & 0xF8) == 0xF0 ? 3 : 0;
    *n = 1;
    if (more == 0) return 0xFFFD;
    c &= more == 1 ? 0x1F : more == 2 ? 0x0F : 0x07;
    for (size_t k = 1; k <= more; ++k) {
        if ((s[k] & 0xC0) != 0x80) return 0xFFFD;
        c = (c << 6) | (s[k] & 0x3Fu);
    }
    *n = more + 1;
    return c;
}

static void put_string(json *j, const char *s)
{
    if (s == NULL) {
        puts_(j, "null");
        return;
    }
    puts_(j, "\"");
    for (const unsigned char *p = (const unsigned char *)s; *p;) {
        const char *named = *p == '"' ? "\\\"" : *p == '\\' ? "\\\\" : *p == '\n' ? "\\n" : *p == '\r' ? "\\r"
                            : *p == '\t' ? "\\t" : *p == '\b' ? "\\b" : *p == '\f' ? "\\f" : NULL;
        size_t n = 1;
        if (named) puts_(j, named);
        else if (*p < 0x20) put_unit(j, *p);
        else if (*p < 0x80) put(j, (const char *)p, 1);
        else {
            uint32_t c = decode(p, &n);
            if (c < 0x10000) put_unit(j, c);
            else {
                put_unit(j, 0xD800 + ((c - 0x10000) >> 10));
                put_unit(j, 0xDC00 + ((c - 0x10000) & 0x3FF));
            }
        }
        p += n;
    }
    puts_(j, "\"");
}

static void put_number(json *j, double x)
{
    char repr[PCN_REPR_SIZE];
    if (isfinite(x)) puts_(j, pcn_repr(x, repr));
    else put_string(j, isnan(x) ? "nan" : x > 0 ? "inf" : "-inf");
}

void pcn_write_refusal(native *in, const char *kind, const char *message, double time, const pcn_text *why)
{
    const pcn_quantity *q = why && why->quantity.reason ? &why->quantity : NULL;
    json j = {0};
    puts_(&j, "{\"kind\": ");
    put_string(&j, kind);
    puts_(&j, ", \"message\": ");
    put_string(&j, message);
    puts_(&j, ", \"instance\": ");
    put_string(&j, in->name);
    puts_(&j, ", \"time\": ");
    put_number(&j, q && q->has_time ? q->time : time);
    puts_(&j, ", \"variable\": ");
    put_string(&j, q ? q->variable : NULL);
    puts_(&j, ", \"value\": ");
    if (q) put_number(&j, q->value);
    else puts_(&j, "null");
    puts_(&j, ", \"unit\": ");
    put_string(&j, q ? q->unit : NULL);
    puts_(&j, ", \"code\": ");
    if (q) {
        char code[16];
        snprintf(code, sizeof code, "%d", q->code);
        puts_(&j, code);
    } else puts_(&j, "null");
    puts_(&j, ", \"reason\": ");
    put_string(&j, q ? q->reason : NULL);
    puts_(&j, "}");
    if (!j.failed) pcn_set_string(&in->pub.string[in->refusal_slot], j.text);
    free(j.text);
}
