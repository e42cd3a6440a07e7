/* The native FMUs' FMU state: data with a checked header (docs/native.md, "FMU state").
 *
 * Bytes (host byte order; a state is read back on the platform that wrote it):
 *   magic "PCNSTATE" (8), format version u32, whole length u64 (checksum included),
 *   identifier str16, GUID str16, counts u32 x 4 (Real, Integer, Boolean, String slots),
 *   model data words u64, flags u8 x 8, times f64 x 4 (start, next, last step, time),
 *   Reals f64, Integers i32, Booleans u8, Strings str32, model data f64,
 *   checksum u64 (FNV-1a of every byte before it).
 * A state is refused (Error, the instance unchanged) unless every field fits this FMU: its
 * identifier and GUID, the counts, parameters equal to this instance's (the configuration),
 * flags 0/1, strings UTF-8 without NUL, and the adapter's check of the model data (configuration
 * words equal, sizes).
 */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "pcn_native.h"

#define MAGIC "PCNSTATE"
#define VERSION 3u   /* 2: the flag step_refused (8 flags); 3: the standard FNV-1a offset basis */
#define FLAGS 8

typedef struct {
    const native *owner;   /* the instance that issued it: no other may use it */
    size_t size;
    unsigned char bytes[];
} pcn_state;

typedef struct {
    unsigned char *bytes;
    size_t size, capacity;
    int failed;
} writer;

static void put(writer *w, const void *data, size_t n)
{
    if (w->failed) return;
    if (w->size + n > w->capacity) {
        size_t capacity = 2 * (w->size + n) + 256;
        unsigned char *grown = realloc(w->bytes, capacity);
        if (grown == NULL) {
            w->failed = 1;
            return;
        }
        w->bytes = grown;
        w->capacity = capacity;
    }
    memcpy(w->bytes + w->size, data, n);
    w->size += n;
}

static void put_u8(writer *w, unsigned v) { unsigned char b = (unsigned char)v; put(w, &b, 1); }
static void put_u16(writer *w, unsigned v) { uint16_t x = (uint16_t)v; put(w, &x, 2); }
static void put_u32(writer *w, uint32_t v) { put(w, &v, 4); }
static void put_u64(writer *w, uint64_t v) { put(w, &v, 8); }
static void put_f64(writer *w, double v) { put(w, &v, 8); }
static void put_str16(writer *w, const char *s) { put_u16(w, (unsigned)strlen(s)); put(w, s, strlen(s)); }

static uint64_t fnv1a(const unsigned char *bytes, size_t n)
{
    uint64_t h = 14695981039346656037ull;   /* FNV-1a 64 offset basis, 0xcbf29ce484222325 */
    for (size_t k = 0; k < n; ++k) h = (h ^ bytes[k]) * 1099511628211ull;
    return h;
}

static int flag(const native *in, int k)
{
    const int flags[FLAGS] = {in->initialising, in->initialised, in->terminated, in->ready,
                              in->initial_outputs, in->built_for_exit, in->has_last, in->step_refused};
    return flags[k];
}

static void write_state(writer *w, const native *in)
{
    put(w, MAGIC, 8);
    put_u32(w, VERSION);
    put_u64(w, 0);   /* the length, filled in below */
    put_str16(w, in->model->identifier);
    put_str16(w, pcn_guid);
    for (int t = 0; t < 4; ++t) put_u32(w, (uint32_t)pcn_n_slots[t]);
    put_u64(w, (uint64_t)in->model->data_words);
    for (int k = 0; k < FLAGS; ++k) put_u8(w, (unsigned)flag(in, k));
    put_f64(w, in->pub.start_time);
    put_f64(w, in->next_time);
    put_f64(w, in->last_step);
    put_f64(w, in->time);
    for (int k = 0; k < pcn_n_slots[PCN_REAL]; ++k) put_f64(w, in->pub.real[k]);
    for (int k = 0; k < pcn_n_slots[PCN_INTEGER]; ++k) put(w, &(int32_t){in->pub.integer[k]}, 4);
    for (int k = 0; k < pcn_n_slots[PCN_BOOLEAN]; ++k) put_u8(w, (unsigned)in->pub.boolean[k]);
    for (int k = 0; k < pcn_n_slots[PCN_STRING]; ++k) {
        put_u32(w, (uint32_t)strlen(in->pub.string[k]));
        put(w, in->pub.string[k], strlen(in->pub.string[k]));
    }
    put(w, in->pub.data, sizeof(double) * (size_t)in->model->data_words);
    if (w->failed) return;
    uint64_t length = w->size + 8;
    memcpy(w->bytes + 12, &length, 8);
    put_u64(w, fnv1a(w->bytes, w->size));
}

static pcn_state *snapshot(const native *in)
{
    writer w = {0};
    write_state(&w, in);
    pcn_state *s = w.failed ? NULL : malloc(sizeof *s + w.size);
    if (s != NULL) {
        s->owner = in;
        s->size = w.size;
        memcpy(s->bytes, w.bytes, w.size);
    }
    free(w.bytes);
    return s;
}

/* ---- reading: every field checked before anything changes ---- */

typedef struct {
    const unsigned char *bytes;
    size_t size, at;
} reader;

static int take(reader *r, void *out, size_t n)
{
    if (r->size - r->at < n) return 0;
    memcpy(out, r->bytes + r->at, n);
    r->at += n;
    return 1;
}

/* Whether n bytes are UTF-8 (FMI's strings) as Python decodes it: no overlong form, no
 * surrogate, nothing past U+10FFFF: a string restored from a state is echoed in messages. */
static int is_utf8(const unsigned char *s, size_t n)
{
    for (size_t k = 0; k < n;) {
        uint32_t c = s[k], least;
        size_t more;
        if (c < 0x80) {
            ++k;
            continue;
        }
        if ((c & 0xE0) == 0xC0) more = 1, least = 0x80, c &= 0x1F;
        else if ((c & 0xF0) == 0xE0) more = 2, least = 0x800, c &= 0x0F;
        else if ((c & 0xF8) == 0xF0) more = 3, least = 0x10000, c &= 0x07;
        else return 0;
        if (n - k <= more) return 0;
        for (size_t j = 1; j <= more; ++j) {
            if ((s[k + j] & 0xC0) != 0x80) return 0;
            c = (c << 6) | (s[k + j] & 0x3Fu);
        }
        if (c < least || c > 0x10FFFF || (c >= 0xD800 && c <= 0xDFFF)) return 0;
        k += more + 1;
    }
    return 1;
}

/* A str16/str32 field (UTF-8 without NUL) copied into out (malloc'd). */
static int take_string(reader *r, size_t width, char **out)
{
    uint32_t n = 0;
    uint16_t n16 = 0;
    if (width == 2 ? !take(r, &n16, 2) : !take(r, &n, 4)) return 0;
    if (width == 2) n = n16;
    if (r->size - r->at < n || memchr(r->bytes + r->at, '\0', n) || !is_utf8(r->bytes + r->at, n)) return 0;
    *out = malloc((size_t)n + 1);
    if (*out == NULL) return 0;
    memcpy(*out, r->bytes + r->at, n);
    (*out)[n] = '\0';
    r->at += n;
    return 1;
}

/* What a state holds, read into fresh arrays. */
typedef struct {
    int flags[FLAGS];
    double times[4];
    double *real;
    int *integer, *boolean;
    char **string;
    double *data;
} contents;

static void free_contents(contents *c)
{
    for (int k = 0; c->string && k < pcn_n_slots[PCN_STRING]; ++k) free(c->string[k]);
    free(c->string);
    free(c->real);
    free(c->integer);
    free(c->boolean);
    free(c->data);
}

/* The header's checks; 0 with `why` written when the bytes are not a state of this FMU. */
static int read_header(reader *r, const native *in, pcn_text *why)
{
    char magic[8];
    uint32_t version = 0, counts[4];
    uint64_t length = 0, words = 0, sum = 0;
    char *identifier = NULL, *guid = NULL;
    int ok = 0;
    if (r->size < 8 + 4 + 8 + 8 || !take(r, magic, 8) || memcmp(magic, MAGIC, 8) != 0)
        pcn_addf(why, "not a serialised parcosim native FMU state (no %s header)", MAGIC);
    else if (!take(r, &version, 4) || version != VERSION)
        pcn_addf(why, "state format version %u, this FMU reads version %u", (unsigned)version, VERSION);
    else if (!take(r, &length, 8) || length != r->size)
        pcn_addf(why, "the state says it is %u bytes long, %u were given", (unsigned)length, (unsigned)r->size);
    else if (memcpy(&sum, r->bytes + r->size - 8, 8), sum != fnv1a(r->bytes, r->size - 8))
        pcn_addf(why, "the state's checksum does not match its bytes (damaged)");
    else if (!take_string(r, 2, &identifier) || strcmp(identifier, in->model->identifier) != 0)
        pcn_addf(why, "the state is of model %s, this FMU is %s", identifier ? identifier : "(unreadable)",
                 in->model->identifier);
    else if (!take_string(r, 2, &guid) || strcmp(guid, pcn_guid) != 0)
        pcn_addf(why, "the state is of the FMU with GUID %s, this FMU's GUID is %s", guid ? guid : "(unreadable)",
                 pcn_guid);
    else if (!take(r, counts, sizeof counts) || !take(r, &words, 8) ||
             counts[0] != (uint32_t)pcn_n_slots[0] || counts[1] != (uint32_t)pcn_n_slots[1] ||
             counts[2] != (uint32_t)pcn_n_slots[2] || counts[3] != (uint32_t)pcn_n_slots[3] ||
             words != (uint64_t)in->model->data_words)
        pcn_addf(why, "the state's variable counts or model data size differ from this FMU's");
    else
        ok = 1;
    free(identifier);
    free(guid);
    return ok;
}

static int read_contents(reader *r, contents *c, pcn_text *why)
{
    unsigned char b;
    for (int k = 0; k < FLAGS; ++k) {
        if (!take(r, &b, 1) || b > 1) return pcn_addf(why, "the state's flag %d is not 0 or 1", k), 0;
        c->flags[k] = b;
    }
    int ok = take(r, c->times, sizeof c->times);
    c->real = calloc((size_t)pcn_n_slots[PCN_REAL] + 1, sizeof(double));
    c->integer = calloc((size_t)pcn_n_slots[PCN_INTEGER] + 1, sizeof(int));
    c->boolean = calloc((size_t)pcn_n_slots[PCN_BOOLEAN] + 1, sizeof(int));
    c->string = calloc((size_t)pcn_n_slots[PCN_STRING] + 1, sizeof(char *));
    c->data = calloc((size_t)pcn_this_model.data_words + 1, sizeof(double));
    ok = ok && c->real && c->integer && c->boolean && c->string && c->data;
    for (int k = 0; ok && k < pcn_n_slots[PCN_REAL]; ++k) ok = take(r, &c->real[k], 8);
    for (int k = 0; ok && k < pcn_n_slots[PCN_INTEGER]; ++k) {
        int32_t v = 0;
        ok = take(r, &v, 4);
        c->integer[k] = v;
    }
    for (int k = 0; ok && k < pcn_n_slots[PCN_BOOLEAN]; ++k) {
        ok = take(r, &b, 1) && b <= 1;
        c->boolean[k] = b;
    }
    for (int k = 0; ok && k < pcn_n_slots[PCN_STRING]; ++k) ok = take_string(r, 4, &c->string[k]);
    ok = ok && take(r, c->data, sizeof(double) * (size_t)pcn_this_model.data_words) && r->at + 8 == r->size;
    if (!ok) pcn_addf(why, "the state's values do not fit this FMU's variables and model data");
    return ok;
}

/* The parameters of the state equal this instance's (they are its configuration). */
static int same_parameters(const native *in, const contents *c, pcn_text *why)
{
    for (int k = 0; k < pcn_n_variables; ++k) {
        const pcn_variable *v = &pcn_variables[k];
        if (v->causality != PCN_PARAMETER || v->tunable) continue;
        int same = v->type == PCN_REAL      ? memcmp(&c->real[v->slot], &in->pub.real[v->slot], 8) == 0
                   : v->type == PCN_INTEGER ? c->integer[v->slot] == in->pub.integer[v->slot]
                   : v->type == PCN_BOOLEAN ? c->boolean[v->slot] == in->pub.boolean[v->slot]
                                            : strcmp(c->string[v->slot], in->pub.string[v->slot]) == 0;
        if (!same) {
            pcn_addf(why, "the state's parameter %s differs from this instance's: it is configuration, set it "
                     "before initialisation instead", v->name);
            return 0;
        }
    }
    return 1;
}

static void apply(native *in, contents *c)
{
    int *flags[FLAGS] = {&in->initialising, &in->initialised, &in->terminated, &in->ready,
                         &in->initial_outputs, &in->built_for_exit, &in->has_last, &in->step_refused};
    for (int k = 0; k < FLAGS; ++k) *flags[k] = c->flags[k];
    in->pub.start_time = c->times[0];
    in->next_time = c->times[1];
    in->last_step = c->times[2];
    in->time = c->times[3];
    in->has_accepted = 0;   /* the step-size rule is checked again at the next step */
    memcpy(in->pub.real, c->real, sizeof(double) * (size_t)pcn_n_slots[PCN_REAL]);
    memcpy(in->pub.integer, c->integer, sizeof(int) * (size_t)pcn_n_slots[PCN_INTEGER]);
    memcpy(in->pub.boolean, c->boolean, sizeof(int) * (size_t)pcn_n_slots[PCN_BOOLEAN]);
    for (int k = 0; k < pcn_n_slots[PCN_STRING]; ++k) {
        free(in->pub.string[k]);
        in->pub.string[k] = c->string[k];
        c->string[k] = NULL;
    }
    memcpy(in->pub.data, c->data, sizeof(double) * (size_t)in->model->data_words);
}

/* Restore the state's bytes into `in`, or refuse (PCN_ERROR naming why) and change nothing. */
static pcn_status restore(native *in, const char *fn, const unsigned char *bytes, size_t size)
{
    reader r = {bytes, size, 0};
    contents c = {0};
    pcn_text why;
    pcn_clear(&why);
    int ok = read_header(&r, in, &why) && read_contents(&r, &c, &why) && same_parameters(in, &c, &why) &&
             (in->model->check_data == NULL || in->model->check_data(&in->pub, c.data, &why) == 0);
    if (ok) apply(in, &c);
    free_contents(&c);
    if (ok) return PCN_OK;
    pcn_text message;
    pcn_clear(&message);
    pcn_addf(&message, "%s refused: %s; nothing was changed", size ? "the state" : "an empty state", why.text);
    return pcn_call_error(in, fn, message.text);
}

static const pcn_state *own_state(const native *in, const char *fn, const void *state)
{
    const pcn_state *s = state;
    if (s != NULL && s->owner == in) return s;
    pcn_call_error(in, fn, s == NULL ? "the FMU state is NULL" : "the FMU state was not issued by this instance");
    return NULL;
}

pcn_status pcn_get_state(native *in, const char *fn, void **state)
{
    if (state == NULL) return pcn_call_error(in, fn, "the FMU state pointer is NULL");
    pcn_state *s = snapshot(in);
    if (s == NULL) return pcn_call_error(in, fn, "out of memory");
    pcn_state *old = *state;
    if (old != NULL && old->owner == in) free(old);   /* the state given is overwritten */
    *state = s;
    return PCN_OK;
}

pcn_status pcn_set_state(native *in, const char *fn, void *state)
{
    const pcn_state *s = own_state(in, fn, state);
    return s ? restore(in, fn, s->bytes, s->size) : PCN_ERROR;
}

pcn_status pcn_free_state(native *in, const char *fn, void **state)
{
    if (state == NULL || *state == NULL) return PCN_OK;
    if (own_state(in, fn, *state) == NULL) return PCN_ERROR;
    free(*state);
    *state = NULL;
    return PCN_OK;
}

pcn_status pcn_state_size(native *in, const char *fn, void *state, size_t *size)
{
    const pcn_state *s = own_state(in, fn, state);
    if (s == NULL) return PCN_ERROR;
    if (size == NULL) return pcn_call_error(in, fn, "the size pointer is NULL");
    *size = s->size;
    return PCN_OK;
}

pcn_status pcn_serialize(native *in, const char *fn, void *state, unsigned char bytes[], size_t size)
{
    const pcn_state *s = own_state(in, fn, state);
    if (s == NULL) return PCN_ERROR;
    if (bytes == NULL || size < s->size)
        return pcn_call_error(in, fn, "the byte array is NULL or shorter than the state");
    memcpy(bytes, s->bytes, s->size);
    return PCN_OK;
}

pcn_status pcn_deserialize(native *in, const char *fn, const unsigned char bytes[], size_t size, void **state)
{
    if (state == NULL || (bytes == NULL && size > 0))
        return pcn_call_error(in, fn, "the bytes or the state pointer is NULL");
    /* Checked against this instance by restoring it into a scratch copy of the bytes' claims:
     * a state is kept only if it would be accepted by the layer's SetFMUState now. */
    pcn_state *s = malloc(sizeof *s + size);
    if (s == NULL) return pcn_call_error(in, fn, "out of memory");
    s->owner = in;
    s->size = size;
    if (size) memcpy(s->bytes, bytes, size);
    reader r = {s->bytes, size, 0};
    contents probe = {0};
    pcn_text why;
    pcn_clear(&why);
    int ok = read_header(&r, in, &why) && read_contents(&r, &probe, &why) &&
             (in->model->check_data == NULL || in->model->check_data(&in->pub, probe.data, &why) == 0);
    free_contents(&probe);
    if (!ok) {
        free(s);
        pcn_text message;
        pcn_clear(&message);
        pcn_addf(&message, "the state refused: %s; nothing was changed", why.text);
        return pcn_call_error(in, fn, message.text);
    }
    *state = s;
    return PCN_OK;
}
