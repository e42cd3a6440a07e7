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

int pc_mean_current_coefficients(double R, double L, double h, int method, double *w)
{
    double ag[2];
    int code = pc_electrical_step_coefficients(R, L, h, method, ag);
    if (code != PC_OK) return code;
    if (method == PC_ELECTRICS_QUASI_STATIC || (method == PC_ELECTRICS_EXACT && L == 0.0)) {
        w[0] = 0.0;
        w[1] = 1.0 / R;
    } else if (method == PC_ELECTRICS_EXACT) {
        double x = R * h / L;
        w[0] = -expm1(-x) / x;
        w[1] = (1.0 - w[0]) / R;
    } else {
        w[0] = 0.5 * (1.0 + ag[0]);
        w[1] = 0.5 * ag[1];
    }
    return PC_OK;
}
