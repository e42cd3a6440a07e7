/* The armature circuit's step coefficients (electrics.h). */
#include "electrics.h"

int pc_electrical_step_coefficients(double R, double L, double h, int method, double *ag)
{
    if (method == PC_ELECTRICS_QUASI_STATIC || (method == PC_ELECTRICS_EXACT && L == 0.0)) {
        ag[0] = 0.0;
        ag[1] = 1.0 / R;
        return PC_OK;
    }
    if (method == PC_ELECTRICS_EXACT) {
        double x = R * h / L;
        ag[0] = exp(-x);
        ag[1] = -expm1(-x) / R;
        return PC_OK;
    }
    if (method != PC_ELECTRICS_EULER || L == 0.0) return PC_ELECTRICS_BAD_METHOD;
    ag[0] = 1.0 - h * R / L;
    ag[1] = h / L;
    return PC_OK;
}
