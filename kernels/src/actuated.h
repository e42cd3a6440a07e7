/* The actuated 5R with both DC drives inside (plant/actuated.py, ActuatedFiveBarPlant): one step
 * composed once, here: each drive's voltage sample, the LuGre bristles advanced with the joint
 * speeds held, the plant's actuated step (fivebar.h), then the drives and bristles kept. */
#ifndef PC_ACTUATED_H
#define PC_ACTUATED_H

#include "drive.h"
#include "fivebar.h"

/* The compiled loop's buffers of an ActuatedFiveBarPlant (pc_io_fn context); drive n is on
 * joint n + 1.  friction[n]: drive n's LuGre parameters with sigma2 = 0 (b is in the ODE; the
 * z slot unused) or NULL for the tanh friction of B.2; bristles[n]: the drive's own pc_lugre,
 * whose z is the bristle state (NULL with friction[n]). */
typedef struct {
    const pc_fivebar_context *plant;   /* z = state: q, dq, i1, i2; its voltages/held are set here */
    pc_drive *drive[2];
    pc_controller *controller[2];
    const pc_lugre *friction[2];
    pc_lugre *bristles[2];
} pc_actuated_context;

/* One step of h: x = [i_ref1, i_hat1, v_ref1, i_ref2, i_hat2, v_ref2 | the plant's outputs
 * (pc_fivebar_actuated_io, from x[plant->first]), tau1, tau2 minus the bristles' torque, v1, v2, i1,
 * i2].  A refusal (a drive's: its code and index; the plant's otherwise) changes nothing: state,
 * drives, bristles, x; the plant's refused trial state is left in its context's scratch.  The one
 * composition: the in-process ActuatedPlant (plant/actuated.py) and the compiled loop call it. */
int pc_actuated_step(const pc_actuated_context *c, double *x, double h, pc_refusal *refusal);

/* The compiled loop's step (pc_io_fn): pc_actuated_step. */
int pc_actuated_io(void *context, double *x, double t, double h, pc_refusal *refusal);

#endif
