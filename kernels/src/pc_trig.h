/* sin and cos of one angle together, inline: the kernels' hot trigonometry (the 5R's chain
 * terms and report, the closed-form kinematics, the circle) calls it dozens of times a step,
 * where glibc's sincos is an out-of-line call of 10-16 ns on the RK4's critical path.
 *
 * 2^-27 <= |x| <= PC_TRIG_FAST: x = k pi/2 + r, k = round(2 x / pi), r by Cody-Waite's three-part
 * pi/2 (33 + 33 + 53 bits; k p1, k p2 exact), |r| <= pi/4; sin r and cos r by their Taylor
 * series (through r^17 and r^16: truncation below 1e-19 at pi/4, alternating series) in
 * Estrin's scheme; then the quadrant k mod 4.  Within 1 ulp of libm's sin and cos there and
 * within 1.5 ulp of the true values (1.18 seen; libm's own within 0.51): tests/kernels/test_kernels_trig.py.
 * Up to 1e4 rad the reduction's two roundings would reach 2 ulps: hence the range.
 * |x| < 2^-27: sin x = x, cos x = 1 (correctly rounded, the sign of -0 kept).  Elsewhere
 * (large, NaN, inf): libm. */
#ifndef PC_TRIG_H
#define PC_TRIG_H

#include <float.h>
#include <math.h>

#if FLT_EVAL_METHOD != 0
#error "pc_trig.h rounds 2 x / pi to a whole number by adding 1.5 * 2^52: it needs double evaluation"
#endif

/* The fast path's range, rad. */
#define PC_TRIG_FAST 1e3

static inline void pc_sincos(double x, double *sinx, double *cosx)
{
    if (!(fabs(x) <= PC_TRIG_FAST) || fabs(x) < 0x1p-27) {   /* libm's range, NaN, inf; sin x = x, cos x = 1 */
        *sinx = fabs(x) < 0x1p-27 ? x : sin(x);
        *cosx = fabs(x) < 0x1p-27 ? 1.0 : cos(x);
        return;
    }
    const double k = (x * 0x1.45f306dc9c883p-1 + 0x1.8p52) - 0x1.8p52;   /* round(2 x / pi) */
    const double r = ((x - k * 0x1.921fb54400000p+0) - k * 0x1.0b4611a600000p-34) - k * 0x1.3198a2e037073p-69;
    const double z = r * r, z2 = z * z, z4 = z2 * z2;
    /* Taylor coefficients 1/n! (Estrin's scheme): sin r = r + r z ps, cos r = 1 - z/2 + z^2 pc. */
    const double s01 = -1.0 / 6.0 + z * 8.333333333333333e-03;
    const double s23 = -1.984126984126984e-04 + z * 2.7557319223985893e-06;
    const double s45 = -2.505210838544172e-08 + z * 1.6059043836821613e-10;
    const double s67 = -7.647163731819816e-13 + z * 2.8114572543455206e-15;
    const double ps = (s01 + z2 * s23) + z4 * (s45 + z2 * s67);
    const double c01 = 0.041666666666666664 + z * -0.001388888888888889;
    const double c23 = 2.48015873015873e-05 + z * -2.755731922398589e-07;
    const double c45 = 2.08767569878681e-09 + z * -1.1470745597729725e-11;
    const double pc = (c01 + z2 * c23) + z4 * (c45 + z2 * 4.779477332387385e-14);
    const double s = r + r * z * ps;
    const double c = 1.0 - (0.5 * z - z2 * pc);
    const long q = (long)k & 3;   /* the quadrant */
    const double sv = (q & 1) ? c : s, cv = (q & 1) ? s : c;
    *sinx = (q & 2) ? -sv : sv;
    *cosx = ((q + 1) & 2) ? -cv : cv;
}

/* sin x alone (pc_sincos; the cos it does not use is not computed once inlined). */
static inline double pc_sin(double x)
{
    double s, c;
    pc_sincos(x, &s, &c);
    return s;
}

#endif
