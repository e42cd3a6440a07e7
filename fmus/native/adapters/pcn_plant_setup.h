/* The 5R plant's set-up and refusals for the native FiveBarPlant and ActuatedFiveBarPlant
 * (docs/native.md): fmus.slave.declarations.build_plant's checks in their order with their messages, the
 * presets (build data: pcn_plant_preset_*), the chain overrides, the counter-masses absorbed
 * into the links (plant.fast5r.composite_link), the link inertias, the integrator settings
 * (RK4 with kernel 'fast' only: dopri5 and the general kernel have no C and are refused by
 * name), the encoders and the start at rest from the inverse kinematics
 * (plant.fivebar.thesis_coordinates); then PlantSimulator's step-size rule and the texts of
 * its refused steps.  Both models declare the plant's variables under the same names
 * (fmus.slave.declarations.declare_plant), so this file compiles against either model's model_config.h.
 */
#ifndef PCN_PLANT_SETUP_H
#define PCN_PLANT_SETUP_H

#include "fivebar.h"
#include "pcn_model.h"

/* What a step reads besides the state: the kernel's parameters and settings (FMU state:
 * configuration words, checked on restore against the instance's parameters). */
typedef struct {
    pc_fivebar_params params;
    pc_fivebar_settings settings;
} pcn_plant_config;

#define PCN_PLANT_CONFIG_WORDS ((long)(sizeof(pcn_plant_config) / sizeof(double)))
/* The plant's state q (7), dq (7). */
#define PCN_PLANT_STATES 14

/* build_plant and PlantSimulator's set-up: the configuration and the start at rest y; nonzero
 * (why written, as the twin's ValueError) when refused. */
int pcn_plant_setup(const pcn_instance *in, pcn_plant_config *c, double y[PCN_PLANT_STATES], pcn_text *why);

/* The plant's outputs (fmus.slave.declarations.PLANT_OUTPUTS) of a state's report into the output slots. */
void pcn_plant_publish(pcn_instance *in, const pc_fivebar_report *report);

/* PlantSimulator.check_step beyond h > 0: Baumgarte's lambda against RK4's stability. */
int pcn_plant_check_step(const pcn_plant_config *c, double t, double dt, pcn_text *why);

/* PlantSimulator.accept's checks (the kernel's judge) on a state integrated and projected by
 * the caller (project = true): the status, refusal filled; report written. */
int pcn_plant_judge(const pcn_plant_config *c, const double *y, pc_fivebar_report *report, pc_refusal *refusal);

/* PlantSimulator._refusal's text of a refused step from t over dt: `status` and `refusal`
 * (the kernel's), `trial` the refused state, `held` the inputs held ("tau1 = ..., ... held"). */
void pcn_plant_refusal(const pcn_plant_config *c, int status, const pc_refusal *refusal, const double *trial,
                       double t, double dt, const char *held, pcn_text *why);

/* Restored model data: the configuration words are this instance's (or all zero: before
 * set-up) and the state's words finite. */
int pcn_plant_check_data(const pcn_instance *in, const double *data, int states, pcn_text *why);

#endif
