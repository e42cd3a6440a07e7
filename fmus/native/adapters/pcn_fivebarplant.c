/* Native FiveBarPlant (fmus/slaves/parcosim_fivebarplant.py) over pc_fivebar_step.
 *
 * The set-up is fmus.slave.declarations.build_plant's (pcn_plant_setup.c): the presets travel as build
 * data, every parameter works as in the pythonfmu FMU except the settings that have no C
 * (method 'dopri5', kernel 'general'), refused by name at initialisation.  A step is
 * PlantSimulator.step's with RK4 and the C kernel: without projection one pc_fivebar_step (the
 * kernel judges the new state); with `project`, pc_fivebar_advance, pc_fivebar_project and the
 * same judge, as the twin composes them.  Model data (FMU state): pcn_plant_config, then the
 * state q, dq.
 */
#include <math.h>
#include <string.h>

#include "model_config.h"
#include "pcn_model.h"
#include "pcn_plant_setup.h"

#define PROJECTIONS 3   /* PlantSimulator.project's Newton iterations */

typedef struct {
    pcn_plant_config config;
    double y[PCN_PLANT_STATES];
} plant;

/* Scratch: the kernel's step (trial state and RK4's work). */
#define SCRATCH_WORDS PC_FIVEBAR_SCRATCH(PCN_PLANT_STATES)

static int setup(pcn_instance *in, pcn_text *why)
{
    plant *p = (plant *)in->data;
    plant fresh;
    if (pcn_plant_setup(in, &fresh.config, fresh.y, why)) return 1;
    *p = fresh;
    pc_fivebar_report report;
    pc_fivebar_report_of(&p->config.params, &p->config.settings, p->y, &report);
    pcn_plant_publish(in, &report);
    return 0;
}

/* PlantSimulator._check_torques: the first torque that is not finite, named. */
static int check_torques(double tau1, double tau2, double t, pcn_text *why)
{
    if (isfinite(tau1) && isfinite(tau2)) return 0;
    const int first = !isfinite(tau1);
    const char *name = first ? "tau1" : "tau2";
    const double value = first ? tau1 : tau2;
    pcn_addf(pcn_timed(why), "input %s = %r at t = %G s is not finite", name, value, t);
    pcn_quantify(why, PC_FIVEBAR_NONFINITE_INPUT, "nonfinite_input", name, value, "N m", t);
    return 1;
}

/* The state integrated over dt with the projection after it (project = true): into `trial`. */
static int projected_step(const plant *p, double tau1, double tau2, double dt, double *work, double *trial,
                          pc_fivebar_report *report, pc_refusal *refusal)
{
    const pc_fivebar_held held = {&p->config.params, NULL, NULL, tau1, -tau2, p->config.settings.lambda, 0};
    memcpy(trial, p->y, sizeof p->y);
    pc_fivebar_advance(&held, trial, dt, (int)p->config.settings.substeps, work);
    int finite = 1;
    for (int k = 0; k < PCN_PLANT_STATES; ++k) finite &= isfinite(trial[k]);
    if (finite) pc_fivebar_project(&p->config.params, trial, PROJECTIONS);
    return pcn_plant_judge(&p->config, trial, report, refusal);
}

static int step(pcn_instance *in, double t, double h, pcn_text *why)
{
    plant *p = (plant *)in->data;
    const double tau1 = in->real[PCN_SLOT_tau1], tau2 = in->real[PCN_SLOT_tau2];
    if (check_torques(tau1, tau2, t, why) || pcn_plant_check_step(&p->config, t, h, why)) return 1;
    double *trial = in->scratch;
    pc_fivebar_report report;
    pc_refusal refusal;
    int status;
    if (in->boolean[PCN_SLOT_project])
        status = projected_step(p, tau1, tau2, h, in->scratch + PCN_PLANT_STATES, trial, &report, &refusal);
    else
        status = pc_fivebar_step(&p->config.params, &p->config.settings, NULL, 0, p->y, NULL, tau1, -tau2, h,
                                 in->scratch, &report, &refusal);
    if (status != PC_OK) {
        pcn_text held;
        pcn_clear(&held);
        pcn_addf(&held, "tau1 = %r, tau2 = %r N m held", tau1, tau2);
        pcn_plant_refusal(&p->config, status, &refusal, trial, t, h, held.text, why);
        return 1;
    }
    memcpy(p->y, trial, sizeof p->y);
    pcn_plant_publish(in, &report);
    return 0;
}

static int check_data(const pcn_instance *in, const double *data, pcn_text *why)
{
    return pcn_plant_check_data(in, data, PCN_PLANT_STATES, why);
}

const pcn_model pcn_this_model = {
    .identifier = PCN_IDENTIFIER,
    .accepted_steps = "any step size h with 1e-09 s <= h and t + h <= 1e+09 s",
    .data_words = sizeof(plant) / sizeof(double),
    .scratch_words = SCRATCH_WORDS,
    .setup = setup,
    .step = step,
    .check_data = check_data,
};
