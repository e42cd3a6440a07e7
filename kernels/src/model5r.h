/* The 5R model's set-up in C, for the native FMUs (docs/native.md): the counter-masses absorbed
 * into the links (plant.presets.ChainParams.counter_offsets, plant.fast5r.composite_link:
 * pc_fivebar_params of a chain with counter-masses) and the position controller's tabulated
 * model (controller.model.build_table, TabulatedModel.kernel_table: the pc_law_table of a
 * grid), the same formulas in the same order as the Python, so the same doubles.
 *
 * Set-up code: called when a model is built, never in a step; no allocation, no global state
 * (the table is written into the caller's buffer of the size pc_model5r_table_words gives).
 */
#ifndef PC_MODEL5R_H
#define PC_MODEL5R_H

#include "fivebar.h"
#include "kinematics5r.h"
#include "law.h"

/* ChainParams.counter_offsets: (L1, L2) where the counter-masses M1, M2 sit on the links of
 * the chain (l1, lg1, lg2, m1, m2 read from `c`); 0 for a mass of 0. */
void pc_model5r_counter_offsets(const pc_fivebar_chain *c, double M1, double M2, double L[2]);

/* plant.fast5r._pack_chain: the chain with the point masses M1, M2 at their offsets absorbed
 * into its links (composite_link; a mass of 0 leaves its link bit for bit). */
void pc_model5r_pack_chain(pc_fivebar_chain *c, double M1, double M2);

/* controller.model._grid: points along x and y of the grid from extent = (x_min, x_max,
 * y_min, y_max) with `step` (round half to even, as Python's round), and the words of its
 * pc_law_table (header and PC_LAW_TERMS values a point). */
long pc_model5r_table_words(const double extent[4], double step, long *nx, long *ny);

/* controller.model.build_table and law.pack_table: the model `p` on the grid into `table`
 * (`words` doubles, at least pc_model5r_table_words'): each point's row (H, the quadratic
 * coefficients of v_M, g_M: ExactModel.row) where the inverse kinematics reach it with the
 * singularity margin >= band, NaN elsewhere.  Returns the points tabulated, or -1 if `words`
 * is too small (nothing written). */
long pc_model5r_build_table(const pc_fivebar_params *p, const double extent[4], double step, double band,
                            double *table, long words);

#endif
