/* The DC motor's armature circuit over one step with v and omega held (4.162): one affine map
 * i(t + h) = a i(t) + g (v - ke omega), whose (a, g) depend on the integration method, and
 * the current's mean over the step (the drive's torque_output 'mean').
 * motor/electrics.py checks R, L, h and the method's name, then calls this; the native FMUs
 * call it directly (docs/native.md). */
#ifndef PC_ELECTRICS_H
#define PC_ELECTRICS_H

#include "pc_common.h"

#define PC_ELECTRICS_EXACT 0        /* analytic: a = exp(-R h / L), g = (1 - a) / R (expm1) */
#define PC_ELECTRICS_EULER 1        /* explicit Euler: a = 1 - h R / L, g = h / L */
#define PC_ELECTRICS_QUASI_STATIC 2 /* L di/dt neglected: a = 0, g = 1 / R */

#define PC_ELECTRICS_BAD_METHOD 1   /* an unknown method, or Euler with L = 0 */

/* (a, g) into ag[2] for R > 0, L >= 0, h > 0 (the caller's checks); exact with L = 0 is the
 * quasi-static limit. */
int pc_electrical_step_coefficients(double R, double L, double h, int method, double *ag);

/* (w_i, w_u) into w[2]: the current averaged over the step is w_i i(t) + w_u (v - ke omega),
 * for the same method and held inputs (exact: the mean of the exponential, w_i = (1 - a)/x,
 * x = R h / L, w_u = (1 - w_i)/R; euler: the current is linear over the step; quasi-static,
 * or exact with L = 0: u/R throughout).  The same arguments and checks as above. */
int pc_mean_current_coefficients(double R, double L, double h, int method, double *w);

#endif
