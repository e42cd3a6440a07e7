/* The current controller's design (app. C) in C, for the native FMUs' set-up (docs/native.md):
 * the zero-order-hold model of the motor current (B.10, C.3) and the pole placement of K(z)
 * (C.5-C.12).  motor/current_controller.py makes the same design with python-control, which
 * the pythonfmu FMUs keep using; tests/kernels/test_kernels_design.py holds this one against
 * python-control's c2d and that design as the oracle.
 *
 * Set-up code: called once when a drive is built, never in a step; no allocation, no global
 * state (fixed 2x2, 3x3 and 4x4 arrays on the stack).
 */
#ifndef PC_DESIGN_H
#define PC_DESIGN_H

#include "pc_common.h"

/* The motor values a design reads (motor.current_controller.design_key's order). */
enum { PC_DESIGN_R, PC_DESIGN_L, PC_DESIGN_KT, PC_DESIGN_KE, PC_DESIGN_B, PC_DESIGN_J, PC_DESIGN_MOTOR };

/* Refusals of pc_current_design. */
#define PC_DESIGN_NO_L 1        /* L = 0: G_I is not strictly proper */
#define PC_DESIGN_NOT_ZOH 2     /* the discrete numerator's leading coefficient is 0 or not finite */
#define PC_DESIGN_NONFINITE 3   /* a coefficient is not finite (overflow) */
#define PC_DESIGN_ZERO_AT_ONE 4 /* b = 0: the plant's zero is z = 1, the controller's own pole, and (C.12) is
                                 * singular: K(z) is not unique (numpy's solve returns one of them) */

/* G_I(z) = (num[0] z + num[1]) / (z^2 + den[1] z + den[2]), den[0] = 1: the exact ZOH
 * discretisation at T of I/U for the armature (L di/dt = u - R i - ke w) driving the rotor
 * (J dw/dt = kt i - b w), through the exponential of the 3x3 augmented matrix [[A, B], [0, 0]] T
 * (scaling and squaring of exp - I's Taylor series, the speed's scale balanced) for Bd, and of
 * A T - c I (c the rightmost eigenvalue's real part) times e^c for Ad, in double-double: each
 * value is the 106-bit one rounded once (within an ulp of the exact model over the tests' range,
 * R T / L up to 2e4).  Caller's checks: R, kt, ke, b >= 0, L, J, T > 0. */
void pc_current_zoh(const double motor[PC_DESIGN_MOTOR], double T, double num[2], double den[3]);

/* K(z) = (alpha z^2 + beta z + gamma) / ((z - 1)(z - delta)) placing the closed loop's four
 * poles on `poles` (three) and on the plant's zero z0 (C.8-C.12): coefficients[4] = alpha, beta,
 * gamma, delta.  The placed polynomial has the factor (z - z0), so delta = z0 and alpha, beta,
 * gamma follow from (z - 1) D(z) + n1 (alpha z^2 + beta z + gamma) = (z - p1)(z - p2)(z - p3)
 * coefficient by coefficient, in double-double from the 106-bit model: each coefficient within an
 * ulp of the exact design, where the 4x4 solve of
 * motor/current_controller.py loses up to 1e-10 relative (its matrix is near singular: delta is
 * close to the controller's pole at 1).  PC_OK or a refusal code above; `detail` (may be NULL)
 * the value it names (num[0], or the coefficient). */
int pc_current_design(const double motor[PC_DESIGN_MOTOR], double T, const double poles[3], double coefficients[4],
                      double *detail);

#endif
