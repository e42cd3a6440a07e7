#include "actuated.h"

/* The world speeds of the actuated joints in z (plant.fivebar.world_rates): theta11's is z[10],
 * theta21's -z[12]. */
static double joint_speed(const double *z, int n)
{
    return n == 0 ? z[10] : -z[12];
}

int pc_actuated_step(const pc_actuated_context *c, double *x, double h, pc_refusal *refusal)
{
    pc_drive_sample samples[2];
    double voltages[2], held[2] = {0.0, 0.0}, bristle[2][3];
    for (int n = 0; n < 2; ++n) {   /* x[3n]: i_ref, x[3n + 1]: i_hat, x[3n + 2]: v_ref */
        const int code = pc_drive_peek_voltage(c->drive[n], c->controller[n], x[3 * n], x[3 * n + 2],
                                               x[3 * n + 1], h, &samples[n], refusal);
        if (code != PC_OK) return code;
        voltages[n] = samples[n].v;
    }
    const double *z = c->plant->state;
    for (int n = 0; n < 2; ++n) {   /* ActuatedPlant.held_friction: minus the mean bristle torque */
        if (c->friction[n]) pc_lugre_advance(c->friction[n], c->bristles[n]->z, joint_speed(z, n), h, bristle[n]);
    }
    /* The world torques (-F1, -F2) on (q1, q2) as thesis efforts (fivebar.thesis_torques): (-F1, F2). */
    if (c->friction[0]) held[0] = -bristle[0][2];
    if (c->friction[1]) held[1] = bristle[1][2];
    pc_fivebar_context plant = *c->plant;
    plant.voltages = voltages;
    plant.held = held;
    const int status = pc_fivebar_actuated_io(&plant, x, 0.0, h, refusal);
    if (status != PC_OK) return status;
    const int first = plant.first;
    for (int n = 0; n < 2; ++n) {
        pc_drive_commit(c->drive[n], c->controller[n], &samples[n], z[14 + n]);
        x[first + 13 + n] = voltages[n];
        x[first + 15 + n] = z[14 + n];
        if (!c->friction[n]) continue;
        /* ActuatedPlant.shaft_torques: minus the bristles' torque at the step's end (its speed) */
        c->bristles[n]->z = bristle[n][0];
        x[first + 11 + n] -= pc_lugre_force(c->friction[n], bristle[n][0], joint_speed(z, n));
    }
    return PC_OK;
}

int pc_actuated_io(void *context, double *x, double t, double h, pc_refusal *refusal)
{
    (void)t;
    return pc_actuated_step(context, x, h, refusal);
}
