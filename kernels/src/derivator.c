/* The derivator's sample (thesis 7.2.3); layout and conventions in derivator.h. */
#include "derivator.h"

const pc_field pc_derivator_fields[] = {
    PC_FIELD(pc_derivator, states),
    PC_FIELD(pc_derivator, channels),
    PC_FIELD(pc_derivator, started),
    {"data", (int)(offsetof(pc_derivator, data) / sizeof(double)), 0},
    {0, 0, 0},
};

long pc_derivator_words(long states, long channels)
{
    return (long)(offsetof(pc_derivator, data) / sizeof(double)) + (2 + states) * (states + 1) + states +
           (states + 1) * channels;
}

/* A size word: a whole number in [1, most]. */
static int whole(double value, long most)
{
    return value >= 1.0 && value <= (double)most && value == (double)(long)value;
}

/* The sizes n, m of a buffer of `words` doubles, checked against its length. */
static int layout(const pc_derivator *d, long words, long *n, long *m, pc_refusal *r)
{
    if (!d || words < (long)(offsetof(pc_derivator, data) / sizeof(double)))
        return pc_refuse(r, PC_DERIVATOR_BAD_LAYOUT, 2, (double)words);
    if (!whole(d->states, PC_DERIVATOR_MAX_STATES))
        return pc_refuse(r, PC_DERIVATOR_BAD_LAYOUT, 0, d->states);
    if (!whole(d->channels, PC_DERIVATOR_MAX_CHANNELS))
        return pc_refuse(r, PC_DERIVATOR_BAD_LAYOUT, 1, d->channels);
    *n = (long)d->states;
    *m = (long)d->channels;
    if (pc_derivator_words(*n, *m) != words)
        return pc_refuse(r, PC_DERIVATOR_BAD_LAYOUT, 2, (double)words);
    return PC_OK;
}

/* The sizes of the context's buffer, checked against its length and the scratch's. */
static int sizes(const pc_derivator_context *c, long *n, long *m, pc_refusal *r)
{
    int code = layout(c->derivator, c->words, n, m, r);
    if (code != PC_OK) return code;
    if (!c->scratch || c->scratch_words < *n * *m)
        return pc_refuse(r, PC_DERIVATOR_BAD_LAYOUT, 3, (double)c->scratch_words);
    return PC_OK;
}

long pc_derivator_scratch_words(const pc_derivator *d, long words)
{
    long n, m;
    return layout(d, words, &n, &m, NULL) == PC_OK ? n * m : 0;
}

int pc_derivator_reset(const pc_derivator_context *c, const double *q0, pc_refusal *r)
{
    long n, m;
    int code = sizes(c, &n, &m, r);
    if (code != PC_OK) return code;
    for (long ch = 0; ch < m; ++ch)
        if (!isfinite(q0[ch])) return pc_refuse(r, PC_DERIVATOR_BAD_INPUT, (int)ch, q0[ch]);
    pc_derivator *d = c->derivator;
    const double *rest = d->data + (2 + n) * (n + 1);
    double *state = d->data + (2 + n) * (n + 1) + n;
    for (long ch = 0; ch < m; ++ch) {
        for (long j = 0; j < n; ++j) state[j * m + ch] = rest[j] * q0[ch];
        state[n * m + ch] = q0[ch];
    }
    d->started = 1.0;
    return PC_OK;
}

/* Rows of the step matrix per pass of rows_times: their sums run side by side (independent additions). */
#define PASS_ROWS 7

/* A channel pair's two numbers: one SSE2 register with GCC and clang (each lane the scalar's
 * operations in the scalar's order, so the same bits), two doubles elsewhere. */
#if defined(__GNUC__)
typedef double pair __attribute__((vector_size(16)));
#define PAIR(a, b) ((pair){(a), (b)})
#define LANE(p, i) ((p)[i])
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
#endif

/* sum + w * x, lane by lane. */
static inline pair pair_madd(pair sum, double w, pair x)
{
#if defined(__GNUC__)
    return sum + w * x;
#else
    return PAIR(sum.v[0] + w * x.v[0], sum.v[1] + w * x.v[1]);
#endif
}

/* Rows [row, row + count) (count <= PASS_ROWS) of the step matrix times [x_ch; q_ch] of the channel
 * pair (ch, other), x[j] entry j of their states: each sum in index order (numpy's BLAS may differ
 * in the last bit).  Row 0 goes to out[ch] (velocity), row 1 to out[m + ch] (acceleration), row
 * 2 + j to next[j m + ch] (the next state).  A short pass repeats its last row. */
static void rows_times(const double *matrix, long n, long m, long row, long count, const pair *x, long ch,
                       long other, const double *q, double *out, double *next)
{
    const double *w[PASS_ROWS];
    pair sum[PASS_ROWS];
    for (long r = 0; r < PASS_ROWS; ++r) {
        w[r] = matrix + (row + (r < count ? r : count - 1)) * (n + 1);
        sum[r] = PAIR(0.0, 0.0);
    }
    for (long j = 0; j < n; ++j)
        for (long r = 0; r < PASS_ROWS; ++r) sum[r] = pair_madd(sum[r], w[r][j], x[j]);
    for (long r = 0; r < count; ++r) {
        double *dest = row + r < 2 ? out + (row + r) * m : next + (row + r - 2) * m;
        dest[ch] = LANE(sum[r], 0) + w[r][n] * q[ch];
        dest[other] = LANE(sum[r], 1) + w[r][n] * q[other];
    }
}

int pc_derivator_step(const pc_derivator_context *c, const double *q, double limit, double *out, pc_refusal *r)
{
    long n, m;
    int code = sizes(c, &n, &m, r);
    if (code != PC_OK) return code;
    for (long ch = 0; ch < m; ++ch)
        if (!(isfinite(q[ch]) && fabs(q[ch]) <= limit)) return pc_refuse(r, PC_DERIVATOR_BAD_INPUT, (int)ch, q[ch]);
    pc_derivator *d = c->derivator;
    const double *matrix = d->data, *rest = d->data + (2 + n) * (n + 1);
    double *state = d->data + (2 + n) * (n + 1) + n;
    const int started = d->started != 0.0;
    pair x[PC_DERIVATOR_MAX_STATES];   /* a channel pair's states side by side */
    for (long ch = 0; ch < m; ch += 2) {   /* an odd last channel pairs with itself */
        const long other = ch + 1 < m ? ch + 1 : ch;
        for (long j = 0; j < n; ++j)       /* not started: the rest state at q */
            x[j] = started ? PAIR(state[j * m + ch], state[j * m + other]) : PAIR(rest[j] * q[ch], rest[j] * q[other]);
        for (long row = 0; row < 2 + n; row += PASS_ROWS) {   /* estimates (rows C, D), next state (A, B) */
            const long count = 2 + n - row < PASS_ROWS ? 2 + n - row : PASS_ROWS;
            rows_times(matrix, n, m, row, count, x, ch, other, q, out, c->scratch);
        }
    }
    for (long k = 0; k < 2 * m; ++k)
        if (!isfinite(out[k])) return pc_refuse(r, PC_DERIVATOR_NONFINITE_OUTPUT, (int)k, out[k]);
    for (long k = 0; k < n * m; ++k) state[k] = c->scratch[k];
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
