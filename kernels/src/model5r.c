/* The 5R model's set-up (model5r.h). */
#include "model5r.h"

#define HEADER_WORDS ((long)(sizeof(pc_law_table) / sizeof(double)))

void pc_model5r_counter_offsets(const pc_fivebar_chain *c, double M1, double M2, double L[2])
{
    L[1] = M2 > 0.0 ? -c->m2 * c->lg2 / M2 : 0.0;
    L[0] = M1 > 0.0 ? -(c->m1 * c->lg1 + (M2 + c->m2) * c->l1) / M1 : 0.0;
}

/* (m, lg, Jz) of a link carrying a point `mass` at `offset` (plant.serial.with_point_mass). */
static void composite_link(double *m, double *lg, double *Jz, double mass, double offset)
{
    if (mass == 0.0) return;
    const double total = *m + mass, com = (*m * *lg + mass * offset) / total;
    const double r = *lg - com, s = offset - com;
    *Jz = (*Jz + *m * (r * r)) + mass * (s * s);
    *lg = com;
    *m = total;
}

void pc_model5r_pack_chain(pc_fivebar_chain *c, double M1, double M2)
{
    double L[2];
    pc_model5r_counter_offsets(c, M1, M2, L);
    composite_link(&c->m1, &c->lg1, &c->Jz1, M1, L[0]);
    composite_link(&c->m2, &c->lg2, &c->Jz2, M2, L[1]);
}

long pc_model5r_table_words(const double extent[4], double step, long *nx, long *ny)
{
    *nx = (long)rint((extent[1] - extent[0]) / step) + 1;
    *ny = (long)rint((extent[3] - extent[2]) / step) + 1;
    return HEADER_WORDS + *nx * *ny * PC_LAW_TERMS;
}

/* ExactModel.row at (x, y): H from the last of the three evaluations, v at unit rates. */
static void row(const pc_fivebar_params *p, const pc_5r_geometry *g, double x, double y, double *out)
{
    static const double rates[3][2] = {{1.0, 0.0}, {0.0, 1.0}, {1.0, 1.0}};
    double q[7], dq[7], distance, v[3][2];
    pc_fivebar_inverse terms;
    pc_5r_thesis_state(g, x, y, 0.0, 0.0, q, dq, &distance);
    for (int k = 0; k < 3; ++k) {
        double ignored[7];
        pc_5r_thesis_state(g, x, y, rates[k][0], rates[k][1], ignored, dq, &distance);
        pc_fivebar_inverse_terms(p, q, dq, &terms);
        v[k][0] = terms.v[0];
        v[k][1] = terms.v[1];
    }
    const double values[PC_LAW_TERMS] = {terms.M[0], terms.M[1], terms.M[3], v[0][0], v[0][1], v[1][0], v[1][1],
                                         (v[2][0] - v[0][0]) - v[1][0], (v[2][1] - v[0][1]) - v[1][1],
                                         terms.g[0], terms.g[1]};
    for (int k = 0; k < PC_LAW_TERMS; ++k) out[k] = values[k];
}

long pc_model5r_build_table(const pc_fivebar_params *p, const double extent[4], double step, double band,
                            double *table, long words)
{
    long nx, ny;
    if (pc_model5r_table_words(extent, step, &nx, &ny) > words) return -1;
    const pc_5r_geometry g = {p->l0, p->chain[0].l1, p->chain[0].l2, p->chain[1].l1, p->chain[1].l2};
    pc_law_table *t = (pc_law_table *)table;
    t->x0 = extent[0] + step * 0.0;
    t->y0 = extent[2] + step * 0.0;
    t->inv_step = 1.0 / step;
    t->nx = (double)(nx - 1);
    t->ny = (double)(ny - 1);
    long points = 0;
    for (long iy = 0; iy < ny; ++iy)
        for (long ix = 0; ix < nx; ++ix) {
            const double x = extent[0] + step * (double)ix, y = extent[2] + step * (double)iy;
            double *out = t->values + (iy * nx + ix) * PC_LAW_TERMS, angles[4], distance;
            if (pc_5r_inverse(&g, x, y, angles, &distance) != PC_5R_OK || pc_5r_margin(angles) < band) {
                for (int k = 0; k < PC_LAW_TERMS; ++k) out[k] = NAN;
                continue;
            }
            row(p, &g, x, y, out);
            ++points;
        }
    return points;
}
