/* The current controller's design (design.h). */
#include "design.h"

#define TAYLOR_TERMS 20   /* the scaled matrix's norm is <= 1/2: the remainder is below 1e-26 */
#define MAX_SQUARINGS 1100

static void mul3(const double a[9], const double b[9], double out[9])
{
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            out[3 * i + j] = a[3 * i] * b[j] + a[3 * i + 1] * b[3 + j] + a[3 * i + 2] * b[6 + j];
}

/* e = exp(m) for a 3x3 m: m 2^-s of 1-norm <= 1/2, its Taylor series by Horner, squared s times. */
static void expm3(const double m[9], double e[9])
{
    double norm = 0.0;
    for (int j = 0; j < 3; ++j) {
        const double column = fabs(m[j]) + fabs(m[3 + j]) + fabs(m[6 + j]);
        norm = column > norm ? column : norm;
    }
    int s = 0;
    double scale = 1.0;
    while (norm * scale > 0.5 && s < MAX_SQUARINGS) {
        scale *= 0.5;
        ++s;
    }
    double x[9], t[9];
    for (int k = 0; k < 9; ++k) {
        x[k] = m[k] * scale;
        e[k] = k % 4 == 0 ? 1.0 : 0.0;
    }
    for (int n = TAYLOR_TERMS; n >= 1; --n) {   /* e = I + x e / n */
        mul3(x, e, t);
        for (int k = 0; k < 9; ++k) e[k] = (k % 4 == 0 ? 1.0 : 0.0) + t[k] / n;
    }
    for (int k = 0; k < s; ++k) {
        mul3(e, e, t);
        for (int j = 0; j < 9; ++j) e[j] = t[j];
    }
}

void pc_current_zoh(const double motor[PC_DESIGN_MOTOR], double T, double num[2], double den[3])
{
    const double R = motor[PC_DESIGN_R], L = motor[PC_DESIGN_L], kt = motor[PC_DESIGN_KT], ke = motor[PC_DESIGN_KE];
    const double b = motor[PC_DESIGN_B], J = motor[PC_DESIGN_J];
    /* [[A, B], [0, 0]] T: states (i, w), input u, output i */
    const double a11 = -R / L, a12 = -ke / L, a21 = kt / J, a22 = -b / J;
    const double m[9] = {a11 * T, a12 * T, T / L, a21 * T, a22 * T, 0.0, 0.0, 0.0, 0.0};
    double e[9];
    expm3(m, e);
    /* C adj(zI - Ad) Bd and det(zI - Ad), det(Ad) = exp(tr(A) T) exactly */
    num[0] = e[2];
    num[1] = e[1] * e[5] - e[4] * e[2];
    den[0] = 1.0;
    den[1] = -(e[0] + e[4]);
    den[2] = exp((a11 + a22) * T);
}

int pc_current_design(const double motor[PC_DESIGN_MOTOR], double T, const double poles[3], double coefficients[4],
                      double *detail)
{
    double ignored;
    if (!detail) detail = &ignored;
    *detail = 0.0;
    if (motor[PC_DESIGN_L] == 0.0) return PC_DESIGN_NO_L;
    if (motor[PC_DESIGN_B] == 0.0) return PC_DESIGN_ZERO_AT_ONE;
    double num[2], den[3];
    pc_current_zoh(motor, T, num, den);
    const double n1 = num[0], n0 = num[1], d1 = den[1], d0 = den[2];
    if (n1 == 0.0 || !isfinite(n1)) return *detail = n1, PC_DESIGN_NOT_ZOH;
    /* With delta on the plant's zero z0 = -n0 / n1, P = (z - z0) [(z - 1) D + n1 (alpha z^2 + beta z + gamma)]
     * (N = n1 (z - z0)), so the bracket is the three poles' polynomial: alpha, beta, gamma one division each. */
    double want[4] = {1.0, 0.0, 0.0, 0.0};
    for (int k = 0; k < 3; ++k)
        for (int j = k + 1; j >= 1; --j) want[j] += -poles[k] * want[j - 1];
    const double known[4] = {1.0, d1 - 1.0, d0 - d1, -d0};   /* (z - 1) D */
    for (int j = 0; j < 3; ++j) coefficients[j] = (want[j + 1] - known[j + 1]) / n1;
    coefficients[3] = -n0 / n1;
    for (int j = 0; j < 4; ++j)
        if (!isfinite(coefficients[j])) return *detail = coefficients[j], PC_DESIGN_NONFINITE;
    return PC_OK;
}
