/* The current controller's design (design.h), in double-double arithmetic (a value is hi + lo,
 * |lo| <= ulp(hi) / 2: 106 bits) rounded once at the end.  In double, scaling and squaring exp
 * rounds each squaring relative to the norm and doubles what came before: a stiff motor's slow
 * mode (e^-7 squared 12 times from e^(-7 / 2^12)) came out 2e-9 relative off, 5e5 eps times its
 * condition number (tests/kernels/test_kernels_design.py, STIFF). */
#include "design.h"

#define TAYLOR_TERMS 26   /* the scaled block's 1-norm is <= 1/2: the remainder is below 1e-36 */
#define MAX_SQUARINGS 1100

typedef struct {
    double hi, lo;
} dd;

/* Error-free transformations (Dekker, Knuth; exact under -ffp-contract=off, fma correctly rounded). */
static dd quick_sum(double a, double b)   /* |a| >= |b| or a == 0 */
{
    const double s = a + b;
    return (dd){s, b - (s - a)};
}

static dd two_sum(double a, double b)
{
    const double s = a + b, v = s - a;
    return (dd){s, (a - (s - v)) + (b - v)};
}

static dd add(dd x, dd y)
{
    dd s = two_sum(x.hi, y.hi);
    const dd t = two_sum(x.lo, y.lo);
    s = quick_sum(s.hi, s.lo + t.hi);
    return quick_sum(s.hi, s.lo + t.lo);
}

static dd neg(dd x) { return (dd){-x.hi, -x.lo}; }

static dd mul(dd x, dd y)
{
    const double p = x.hi * y.hi;
    return quick_sum(p, fma(x.hi, y.hi, -p) + (x.hi * y.lo + x.lo * y.hi));
}

static dd div_dd(dd x, dd y)
{
    const double q1 = x.hi / y.hi;
    const dd r = add(x, neg(mul(y, (dd){q1, 0.0})));
    const double q2 = r.hi / y.hi;
    const dd r2 = add(r, neg(mul(y, (dd){q2, 0.0})));
    return add(quick_sum(q1, q2), (dd){r2.hi / y.hi, 0.0});
}

static dd of(double a) { return (dd){a, 0.0}; }

static dd scaled(dd x, int p) { return (dd){ldexp(x.hi, p), ldexp(x.lo, p)}; }

static void mul3(const dd a[9], const dd b[9], dd out[9])
{
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            out[3 * i + j] = add(add(mul(a[3 * i], b[j]), mul(a[3 * i + 1], b[3 + j])), mul(a[3 * i + 2], b[6 + j]));
}

/* w = exp(m) - I for a 3x3 m whose last row is 0 (an input column beside a 2x2 block): m 2^-s with
 * the block's 1-norm <= 1/2, the Taylor series of exp(x) - I by Horner, then s doublings
 * (I + w)^2 - I = 2 w + w^2.  Carrying exp - I keeps what squaring exp would round off against 1
 * (a slow mode's e^mu - 1, the input's integral): a doubling rounds relative to w, not to I. */
static void expm1_3(const dd m[9], dd w[9])
{
    double norm = 0.0;
    for (int j = 0; j < 2; ++j) {
        const double column = fabs(m[j].hi) + fabs(m[3 + j].hi);
        norm = column > norm ? column : norm;
    }
    int s = 0;
    while (ldexp(norm, -s) > 0.5 && s < MAX_SQUARINGS) ++s;
    dd x[9], e[9], t[9];
    for (int k = 0; k < 9; ++k) {
        x[k] = scaled(m[k], -s);
        e[k] = of(k % 4 == 0 ? 1.0 : 0.0);
    }
    for (int n = TAYLOR_TERMS; n >= 2; --n) {   /* e = I + x e / n */
        mul3(x, e, t);
        for (int k = 0; k < 9; ++k) e[k] = add(of(k % 4 == 0 ? 1.0 : 0.0), div_dd(t[k], of(n)));
    }
    mul3(x, e, w);
    for (int k = 0; k < s; ++k) {
        mul3(w, w, t);
        for (int j = 0; j < 9; ++j) w[j] = add(scaled(w[j], 1), t[j]);
    }
}

/* e^x: 2^k e^r, r = x - k ln 2 (|r| <= 0.35), e^r - 1 from its Taylor series at r 2^-10 and ten doublings. */
static dd exp_dd(dd x)
{
    static const dd ln2 = {0x1.62e42fefa39efp-1, 0x1.abc9e3b39803fp-56};
    if (!(fabs(x.hi) < 746.0)) return of(x.hi < 0.0 ? 0.0 : x.hi * INFINITY);   /* underflow, overflow, NaN */
    const double k = nearbyint(x.hi / ln2.hi);
    const dd r = scaled(add(x, neg(mul(of(k), ln2))), -10);
    dd w = of(1.0);
    for (int n = 12; n >= 2; --n) w = add(of(1.0), div_dd(mul(r, w), of(n)));
    w = mul(r, w);
    for (int j = 0; j < 10; ++j) w = add(scaled(w, 1), mul(w, w));
    return scaled(add(of(1.0), w), (int)k);
}

/* The ZOH model in double-double: num[0] z + num[1] over z^2 + den[1] z + den[2]. */
static void zoh(const double motor[PC_DESIGN_MOTOR], double T, dd num[2], dd den[3])
{
    const dd R = of(motor[PC_DESIGN_R]), L = of(motor[PC_DESIGN_L]), kt = of(motor[PC_DESIGN_KT]);
    const dd ke = of(motor[PC_DESIGN_KE]), b = of(motor[PC_DESIGN_B]), J = of(motor[PC_DESIGN_J]), t = of(T);
    /* [[A, B], [0, 0]] T: states (i, w), input u, output i */
    const dd a11 = neg(div_dd(mul(R, t), L)), a12 = neg(div_dd(mul(ke, t), L));
    const dd a21 = div_dd(mul(kt, t), J), a22 = neg(div_dd(mul(b, t), J));
    /* the speed scaled by 2^p (D^-1 M D, D = diag(1, 2^p, 1): exact) so that |m12| ~ |m21|: the
     * squarings set by the dynamics, not by the units; num and den are invariant under D. */
    int p = 0;
    if (a12.hi != 0.0 && a21.hi != 0.0 && isfinite(a12.hi) && isfinite(a21.hi)) p = (ilogb(a21.hi) - ilogb(a12.hi)) / 2;
    const dd zero = of(0.0);
    const dd m[9] = {a11, scaled(a12, p), div_dd(t, L), scaled(a21, -p), a22, zero, zero, zero, zero};
    dd w[9];
    expm1_3(m, w);
    /* Ad again as e^c exp(M - c I), c the rightmost eigenvalue's real part (any c is exact; this one
     * leaves exp(M - c I) of order 1): entries far below 1 (a decayed mode) keep their own digits. */
    const double sigma = 0.5 * (m[0].hi + m[4].hi), h = 0.5 * (m[0].hi - m[4].hi);
    const double disc = h * h + m[1].hi * m[3].hi;
    const double c = sigma + (disc > 0.0 ? sqrt(disc) : 0.0);
    dd shifted[9], v[9];
    for (int k = 0; k < 9; ++k) shifted[k] = k == 2 || k == 5 ? zero : m[k];
    shifted[0] = add(m[0], of(-c));
    shifted[4] = add(m[4], of(-c));
    expm1_3(shifted, v);
    const dd ec = exp_dd(of(c));
    const dd e11 = mul(ec, add(of(1.0), v[0])), e12 = mul(ec, v[1]), e22 = mul(ec, add(of(1.0), v[4]));
    /* C adj(zI - Ad) Bd and det(zI - Ad), Bd = w's last column, det(Ad) = exp(tr(A) T) */
    num[0] = w[2];
    num[1] = add(mul(e12, w[5]), neg(mul(e22, w[2])));
    den[0] = of(1.0);
    den[1] = neg(add(e11, e22));
    den[2] = exp_dd(add(a11, a22));
}

void pc_current_zoh(const double motor[PC_DESIGN_MOTOR], double T, double num[2], double den[3])
{
    dd n[2], d[3];
    zoh(motor, T, n, d);
    for (int k = 0; k < 2; ++k) num[k] = n[k].hi;
    for (int k = 0; k < 3; ++k) den[k] = d[k].hi;
}

int pc_current_design(const double motor[PC_DESIGN_MOTOR], double T, const double poles[3], double coefficients[4],
                      double *detail)
{
    double ignored;
    if (!detail) detail = &ignored;
    *detail = 0.0;
    if (motor[PC_DESIGN_L] == 0.0) return PC_DESIGN_NO_L;
    if (motor[PC_DESIGN_B] == 0.0) return PC_DESIGN_ZERO_AT_ONE;
    dd num[2], den[3];
    zoh(motor, T, num, den);
    const dd n1 = num[0], n0 = num[1], d1 = den[1], d0 = den[2];
    if (n1.hi == 0.0 || !isfinite(n1.hi)) return *detail = n1.hi, PC_DESIGN_NOT_ZOH;
    /* With delta on the plant's zero z0 = -n0 / n1, P = (z - z0) [(z - 1) D + n1 (alpha z^2 + beta z + gamma)]
     * (N = n1 (z - z0)), so the bracket is the three poles' polynomial: alpha, beta, gamma one division each. */
    dd want[4] = {of(1.0), of(0.0), of(0.0), of(0.0)};
    for (int k = 0; k < 3; ++k)
        for (int j = k + 1; j >= 1; --j) want[j] = add(want[j], neg(mul(of(poles[k]), want[j - 1])));
    const dd known[4] = {of(1.0), add(d1, of(-1.0)), add(d0, neg(d1)), neg(d0)};   /* (z - 1) D */
    for (int j = 0; j < 3; ++j) coefficients[j] = div_dd(add(want[j + 1], neg(known[j + 1])), n1).hi;
    coefficients[3] = neg(div_dd(n0, n1)).hi;
    for (int j = 0; j < 4; ++j)
        if (!isfinite(coefficients[j])) return *detail = coefficients[j], PC_DESIGN_NONFINITE;
    return PC_OK;
}
