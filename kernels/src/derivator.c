/* The derivator's sample (thesis 7.2.3); layout and conventions in derivator.h. */
#include "derivator.h"

#include <string.h>

const pc_field pc_derivator_fields[] = {
    PC_FIELD(pc_derivator, states),
    PC_FIELD(pc_derivator, channels),
    PC_FIELD(pc_derivator, started),
    PC_FIELD(pc_derivator, velocity_sections),
    {"data", (int)(offsetof(pc_derivator, data) / sizeof(double)), 0},
    {0, 0, 0},
};

/* Words of one section's coefficients: b0 b1 b2 a1 a2. */
#define SECTION_WORDS 5

long pc_derivator_words(long states, long channels)
{
    return (long)(offsetof(pc_derivator, data) / sizeof(double)) + 1 + (states / 2 - 1) * SECTION_WORDS +
           (states + 1) * channels;
}

/* A size word: a whole number in [least, most]. */
static int whole(double value, long least, long most)
{
    return value >= (double)least && value <= (double)most && value == (double)(long)value;
}

/* The sizes n, m and the velocity sections of a buffer of `words` doubles, checked against its
 * length. */
static int layout(const pc_derivator *d, long words, long *n, long *m, long *velocity, pc_refusal *r)
{
    if (!d || words < (long)(offsetof(pc_derivator, data) / sizeof(double)))
        return pc_refuse(r, PC_DERIVATOR_BAD_LAYOUT, 2, (double)words);
    if (!whole(d->states, 2, PC_DERIVATOR_MAX_STATES) || (long)d->states % 2 != 0)
        return pc_refuse(r, PC_DERIVATOR_BAD_LAYOUT, 0, d->states);
    if (!whole(d->channels, 1, PC_DERIVATOR_MAX_CHANNELS))
        return pc_refuse(r, PC_DERIVATOR_BAD_LAYOUT, 1, d->channels);
    *n = (long)d->states;
    *m = (long)d->channels;
    if (!whole(d->velocity_sections, 0, *n / 2 - 1))
        return pc_refuse(r, PC_DERIVATOR_BAD_LAYOUT, 4, d->velocity_sections);
    *velocity = (long)d->velocity_sections;
    if (pc_derivator_words(*n, *m) != words)
        return pc_refuse(r, PC_DERIVATOR_BAD_LAYOUT, 2, (double)words);
    return PC_OK;
}

/* The sizes of the context's buffer, checked against its length and the scratch's. */
static int sizes(const pc_derivator_context *c, long *n, long *m, long *velocity, pc_refusal *r)
{
    int code = layout(c->derivator, c->words, n, m, velocity, r);
    if (code != PC_OK) return code;
    if (!c->scratch || c->scratch_words < *n * *m)
        return pc_refuse(r, PC_DERIVATOR_BAD_LAYOUT, 3, (double)c->scratch_words);
    return PC_OK;
}

long pc_derivator_scratch_words(const pc_derivator *d, long words)
{
    long n, m, velocity;
    return layout(d, words, &n, &m, &velocity, NULL) == PC_OK ? n * m : 0;
}

/* The state rows of a buffer of n states. */
static double *state_of(pc_derivator *d, long n)
{
    return d->data + 1 + (n / 2 - 1) * SECTION_WORDS;
}

int pc_derivator_reset(const pc_derivator_context *c, const double *q0, pc_refusal *r)
{
    long n, m, velocity;
    int code = sizes(c, &n, &m, &velocity, r);
    if (code != PC_OK) return code;
    for (long ch = 0; ch < m; ++ch)
        if (!isfinite(q0[ch])) return pc_refuse(r, PC_DERIVATOR_BAD_INPUT, (int)ch, q0[ch]);
    pc_derivator *d = c->derivator;
    double *state = state_of(d, n);
    for (long ch = 0; ch < m; ++ch) {
        state[ch] = q0[ch];   /* the first difference's last input; every other word 0 at rest */
        for (long j = 1; j < n; ++j) state[j * m + ch] = 0.0;
        state[n * m + ch] = q0[ch];
    }
    d->started = 1.0;
    return PC_OK;
}

/* A channel pair's two numbers: one SSE2 register with GCC and clang (each lane the scalar's
 * operations in the scalar's order, so the same bits), two doubles elsewhere. */
#if defined(__GNUC__)
typedef double pair __attribute__((vector_size(16)));
#define PAIR(a, b) ((pair){(a), (b)})
#define LANE(p, i) ((p)[i])
static inline pair pair_sub(pair a, pair b) { return a - b; }
static inline pair pair_scale(double w, pair a) { return w * a; }
static inline pair pair_add(pair a, pair b) { return a + b; }
#else
typedef struct {
    double v[2];
} pair;
static pair pair_of(double a, double b)
{
    pair p = {{a, b}};
    return p;
}
#define PAIR(a, b) pair_of((a), (b))
#define LANE(p, i) ((p).v[i])
static pair pair_sub(pair a, pair b) { return PAIR(a.v[0] - b.v[0], a.v[1] - b.v[1]); }
static pair pair_scale(double w, pair a) { return PAIR(w * a.v[0], w * a.v[1]); }
static pair pair_add(pair a, pair b) { return PAIR(a.v[0] + b.v[0], a.v[1] + b.v[1]); }
#endif

/* A backward difference of input u, x[0] its last input: its output; next[0] = u. */
static inline pair difference(double rate, pair u, const pair *x, pair *next)
{
    next[0] = u;
    return pair_scale(rate, pair_sub(u, x[0]));
}

/* `count` sections (coefficients in `section`, states from x[0]) driven by u: the last one's
 * output; their next states from next[0]. */
static inline pair sections(const double *section, long count, pair u, const pair *x, pair *next)
{
    for (long k = 0; k < count; ++k, section += SECTION_WORDS, x += 2, next += 2) {
        const pair y = pair_add(pair_scale(section[0], u), x[0]);
        next[0] = pair_sub(pair_add(pair_scale(section[1], u), x[1]), pair_scale(section[3], y));
        next[1] = pair_sub(pair_scale(section[2], u), pair_scale(section[4], y));
        u = y;
    }
    return u;
}

/* Words j < n of channels ch and other from rows of m: words[j] = (rows[j m + ch], rows[j m + other]). */
static void get(const double *rows, long n, long m, long ch, long other, pair *words)
{
    if (other == ch + 1)   /* side by side */
        for (long j = 0; j < n; ++j) memcpy(&words[j], rows + j * m + ch, sizeof(pair));
    else
        for (long j = 0; j < n; ++j) words[j] = PAIR(rows[j * m + ch], rows[j * m + other]);
}

/* get's inverse: rows[j m + ch], rows[j m + other] = words[j]. */
static void put(double *rows, long n, long m, long ch, long other, const pair *words)
{
    if (other == ch + 1)
        for (long j = 0; j < n; ++j) memcpy(rows + j * m + ch, &words[j], sizeof(pair));
    else
        for (long j = 0; j < n; ++j) {
            rows[j * m + ch] = LANE(words[j], 0);
            rows[j * m + other] = LANE(words[j], 1);
        }
}

int pc_derivator_step(const pc_derivator_context *c, const double *q, double limit, double *out, pc_refusal *r)
{
    long n, m, velocity;
    int code = sizes(c, &n, &m, &velocity, r);
    if (code != PC_OK) return code;
    for (long ch = 0; ch < m; ++ch)
        if (!(isfinite(q[ch]) && fabs(q[ch]) <= limit)) return pc_refuse(r, PC_DERIVATOR_BAD_INPUT, (int)ch, q[ch]);
    pc_derivator *d = c->derivator;
    const double rate = d->data[0], *section = d->data + 1;
    const long acceleration = n / 2 - 1 - velocity, second = 1 + 2 * velocity;   /* the second difference's word */
    double *state = state_of(d, n);
    const int started = d->started != 0.0;
    pair x[PC_DERIVATOR_MAX_STATES], next[PC_DERIVATOR_MAX_STATES];   /* a channel pair's words side by side */
    for (long ch = 0; ch < m; ch += 2) {   /* an odd last channel pairs with itself */
        const long other = ch + 1 < m ? ch + 1 : ch;
        const pair u = PAIR(q[ch], q[other]);
        if (started)
            get(state, n, m, ch, other, x);
        else                               /* at rest at q */
            for (long j = 0; j < n; ++j) x[j] = j == 0 ? u : PAIR(0.0, 0.0);
        const pair dq = sections(section, velocity, difference(rate, u, x, next), x + 1, next + 1);
        const pair ddq = sections(section + velocity * SECTION_WORDS, acceleration,
                                  difference(rate, dq, x + second, next + second), x + second + 1, next + second + 1);
        out[ch] = LANE(dq, 0);
        out[other] = LANE(dq, 1);
        out[m + ch] = LANE(ddq, 0);
        out[m + other] = LANE(ddq, 1);
        if (m > 2) put(c->scratch, n, m, ch, other, next);   /* one pair: `next` waits in place */
    }
    for (long k = 0; k < 2 * m; ++k)
        if (!isfinite(out[k])) return pc_refuse(r, PC_DERIVATOR_NONFINITE_OUTPUT, (int)k, out[k]);
    if (m > 2)
        for (long k = 0; k < n * m; ++k) state[k] = c->scratch[k];
    else
        put(state, n, m, 0, m - 1, next);
    for (long ch = 0; ch < m; ++ch) state[n * m + ch] = q[ch];
    d->started = 1.0;
    return PC_OK;
}

int pc_derivator_io(void *context, double *x, double t, double h, pc_refusal *r)
{
    (void)t;
    (void)h;
    const pc_derivator_context *c = context;
    if (c->derivator && c->derivator->channels != 2.0)
        return pc_refuse(r, PC_DERIVATOR_BAD_LAYOUT, 1, c->derivator->channels);
    double out[4];
    int code = pc_derivator_step(c, x, c->limit, out, r);
    if (code != PC_OK) return code;
    x[2] = out[0];
    x[3] = out[1];
    x[4] = out[2];
    x[5] = out[3];
    return PC_OK;
}
