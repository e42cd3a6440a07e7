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

/* Entry j of channel ch's state: the state, or not started the rest state at q_ch. */
static inline double entry(const double *rest, const double *state, long m, long j, long ch, const double *q,
                           int started)
{
    return started ? state[j * m + ch] : rest[j] * q[ch];
}

/* Rows `row` and `row2` of the step matrix times [state_ch; q_ch] for every channel into out[m]
 * and out2[m], each sum in index order (numpy's BLAS may differ in the last bit).  Two rows and
 * two channels at a time: the four sums are independent, so they run side by side instead of
 * each waiting on its own additions.  An odd last row or channel pairs with itself. */
static void rows_times(const double *matrix, const double *rest, const double *state, long n, long m, long row,
                       long row2, const double *q, int started, double *out, double *out2)
{
    const double *w = matrix + row * (n + 1), *w2 = matrix + row2 * (n + 1);
    for (long ch = 0; ch < m; ch += 2) {
        const long other = ch + 1 < m ? ch + 1 : ch;
        double sum0 = 0.0, sum1 = 0.0, sum2 = 0.0, sum3 = 0.0;
        for (long j = 0; j < n; ++j) {
            const double x0 = entry(rest, state, m, j, ch, q, started);
            const double x1 = entry(rest, state, m, j, other, q, started);
            sum0 += w[j] * x0;
            sum1 += w[j] * x1;
            sum2 += w2[j] * x0;
            sum3 += w2[j] * x1;
        }
        out[ch] = sum0 + w[n] * q[ch];
        out[other] = sum1 + w[n] * q[other];
        out2[ch] = sum2 + w2[n] * q[ch];
        out2[other] = sum3 + w2[n] * q[other];
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
    rows_times(matrix, rest, state, n, m, 0, 1, q, started, out, out + m);   /* the estimates: rows C, D */
    for (long k = 0; k < 2 * m; ++k)
        if (!isfinite(out[k])) return pc_refuse(r, PC_DERIVATOR_NONFINITE_OUTPUT, (int)k, out[k]);
    for (long j = 0; j < n; j += 2) {             /* the next state: rows A and B, kept apart first */
        const long j2 = j + 1 < n ? j + 1 : j;
        rows_times(matrix, rest, state, n, m, 2 + j, 2 + j2, q, started, c->scratch + j * m, c->scratch + j2 * m);
    }
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
