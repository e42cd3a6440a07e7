/* The DC drive's step (drive.h): the current controller K(z) (app. C), the exact electrics
 * (4.162 over a step with v and omega held), the shaft torque (B.2, pc_motor.h, or kt i minus
 * the LuGre friction), the PWM's quantum, the current noise, and LuGre (1)-(4). */
#include "drive.h"

#include "pc_motor.h"
#include "pc_sampling.h"

#define PC_PI 3.14159265358979323846
/* Below this r h, phi2 by its series (the closed form loses all digits to cancellation). */
#define LUGRE_SERIES_BELOW 1e-3

const pc_field pc_controller_fields[] = {
    PC_FIELD(pc_controller, alpha), PC_FIELD(pc_controller, beta), PC_FIELD(pc_controller, gamma),
    PC_FIELD(pc_controller, delta), PC_FIELD(pc_controller, v_max), PC_FIELD(pc_controller, u1),
    PC_FIELD(pc_controller, u2), PC_FIELD(pc_controller, e1), PC_FIELD(pc_controller, e2), {0, 0, 0}};

const pc_field pc_drive_fields[] = {
    PC_FIELD(pc_drive, current_mode), PC_FIELD(pc_drive, mean_torque), PC_FIELD(pc_drive, ke),
    PC_FIELD(pc_drive, kt), PC_FIELD(pc_drive, b), PC_FIELD(pc_drive, mu), PC_FIELD(pc_drive, omega_eps),
    PC_FIELD(pc_drive, v_max), PC_FIELD(pc_drive, T), PC_FIELD(pc_drive, sample_phase), PC_FIELD(pc_drive, h), PC_FIELD(pc_drive, a),
    PC_FIELD(pc_drive, g), PC_FIELD(pc_drive, w_i), PC_FIELD(pc_drive, w_u), PC_FIELD(pc_drive, substeps),
    PC_FIELD(pc_drive, i), PC_FIELD(pc_drive, v), PC_FIELD(pc_drive, phase), PC_FIELD(pc_drive, pwm_quantum),
    PC_FIELD(pc_drive, i_offset), PC_FIELD(pc_drive, i_noise), PC_FIELD(pc_drive, noise_seed),
    PC_FIELD(pc_drive, noise_instance), PC_FIELD(pc_drive, sample), {0, 0, 0}};

const pc_field pc_lugre_fields[] = {
    PC_FIELD(pc_lugre, Fc), PC_FIELD(pc_lugre, Fs), PC_FIELD(pc_lugre, omega_s), PC_FIELD(pc_lugre, sigma0),
    PC_FIELD(pc_lugre, sigma1), PC_FIELD(pc_lugre, sigma2), PC_FIELD(pc_lugre, z), {0, 0, 0}};

/* --- K(z) as the anti-windup difference equation (app. C, Astrom-Wittenmark) ----------------- */

static double saturate(double v, double v_max)
{
    return fmin(fmax(v, -v_max), v_max);
}

/* v_k = sat((1 + delta) u1 - delta u2 + alpha e + beta e1 + gamma e2): the voltage for error e. */
static double controller_output(const pc_controller *c, double e)
{
    double v = (1.0 + c->delta) * c->u1 - c->delta * c->u2 + c->alpha * e + c->beta * c->e1 + c->gamma * c->e2;
    return saturate(v, c->v_max);
}

static void controller_commit(pc_controller *c, double v, double e)
{
    c->u2 = c->u1;
    c->u1 = v;
    c->e2 = c->e1;
    c->e1 = e;
}

double pc_controller_update(pc_controller *c, double i_ref, double i_meas)
{
    double e = i_ref - i_meas;
    double v = controller_output(c, e);
    controller_commit(c, v, e);
    return v;
}

double pc_drive_shaft_torque(double kt, double b, double mu, double omega_eps, double i, double omega)
{
    return pc_shaft_torque(kt, b, mu, omega_eps, i, omega);
}

double pc_drive_armature_rate(double R, double L, double ke, double v, double i, double omega)
{
    return pc_armature_rate(R, L, ke, v, i, omega);
}

/* --- the stateless noise ------------------------------------------------------------------- */

uint64_t pc_splitmix64(uint64_t x)
{
    uint64_t z = x + UINT64_C(0x9E3779B97F4A7C15);
    z = (z ^ (z >> 30)) * UINT64_C(0xBF58476D1CE4E5B9);
    z = (z ^ (z >> 27)) * UINT64_C(0x94D049BB133111EB);
    return z ^ (z >> 31);
}

/* A uint64's top 53 bits as a double in (0, 1]. */
static double unit(uint64_t x)
{
    return ((double)(x >> 11) + 1.0) * (1.0 / 9007199254740992.0);
}

static uint64_t noise_key(uint64_t seed, uint64_t instance, uint64_t step)
{
    return pc_splitmix64(pc_splitmix64(pc_splitmix64(seed) ^ instance) ^ step);
}

double pc_drive_uniform(uint64_t seed, uint64_t instance, uint64_t step)
{
    return unit(noise_key(seed, instance, step));
}

/* Box-Muller of two 53-bit uniforms: no state, so a rerun or a restored FMU draws the same noise. */
double pc_drive_gaussian(uint64_t seed, uint64_t instance, uint64_t step)
{
    uint64_t key = noise_key(seed, instance, step);
    double u1 = unit(key), u2 = unit(pc_splitmix64(key));
    return sqrt(-2.0 * log(u1)) * cos(2.0 * PC_PI * u2);
}

/* --- LuGre (1)-(4) ----------------------------------------------------------------------------- */

double pc_lugre_stribeck(const pc_lugre *f, double omega)   /* (3) */
{
    double s = omega / f->omega_s;
    return f->Fc + (f->Fs - f->Fc) * exp(-s * s);
}

static double bristle_rate(const pc_lugre *f, double z, double omega, double g)   /* (1), G(omega) = g */
{
    return omega - f->sigma0 * fabs(omega) * z / g;
}

static double lugre_force(const pc_lugre *f, double z, double omega, double g)   /* (4), G(omega) = g */
{
    return f->sigma0 * z + f->sigma1 * bristle_rate(f, z, omega, g) + f->sigma2 * omega;
}

double pc_lugre_bristle_rate(const pc_lugre *f, double z, double omega)
{
    return bristle_rate(f, z, omega, pc_lugre_stribeck(f, omega));
}

double pc_lugre_force(const pc_lugre *f, double z, double omega)
{
    return lugre_force(f, z, omega, pc_lugre_stribeck(f, omega));
}

/* The deflection (1) tends to at constant omega: sign(omega) G(omega) / sigma0 (0 at rest). */
double pc_lugre_steady_deflection(const pc_lugre *f, double omega)
{
    if (omega == 0.0) return 0.0;
    return copysign(pc_lugre_stribeck(f, omega), omega) / f->sigma0;
}

/* phi1(x) = (1 - e^-x) / x, phi2(x) = (x - 1 + e^-x) / x^2, x >= 0. */
void pc_lugre_phi(double x, double phi[2])
{
    if (x < LUGRE_SERIES_BELOW) {
        phi[0] = 1.0 - x * (0.5 - x * (1.0 / 6.0 - x / 24.0));
        phi[1] = 0.5 - x * (1.0 / 6.0 - x * (1.0 / 24.0 - x / 120.0));
        return;
    }
    double e = expm1(-x);   /* e^-x - 1 */
    phi[0] = -e / x;
    phi[1] = (x + e) / (x * x);
}

/* (1) is linear in z with omega held (rate r = sigma0 |omega| / G): z(h) = z0 e^-rh + omega h phi1(rh),
 * mean z = z0 phi1(rh) + omega h phi2(rh); out = {z(h), F(h) (4), mean F over the step}. */
void pc_lugre_advance(const pc_lugre *f, double z0, double omega, double h, double out[3])
{
    double g = pc_lugre_stribeck(f, omega);
    double x = f->sigma0 * fabs(omega) / g * h;
    double phi[2];
    pc_lugre_phi(x, phi);
    double z = z0 * exp(-x) + omega * h * phi[0];
    double mean_z = z0 * phi[0] + omega * h * phi[1];
    out[0] = z;
    out[1] = lugre_force(f, z, omega, g);
    out[2] = f->sigma0 * mean_z + f->sigma1 * (z - z0) / h + f->sigma2 * omega;
}

/* A mass on LuGre friction from rest (the paper's example, scenarios/friction_demo): the speed
 * held over each step, the bristles solved exactly, the mass integrated with the step's mean
 * friction.  Force: kind 0 a t, 1 a sin(b t), 2 a spring of stiffness a whose end moves at b.
 * rows: n x {x, v, z} after each step.  f's own z is not used (the mass starts at rest). */
void pc_lugre_push(const pc_lugre *f, int kind, double a, double b, double mass, double h, int n, double *rows)
{
    double x = 0.0, v = 0.0, z = 0.0, bristles[3];
    for (int k = 0; k < n; ++k) {
        double t = (k + 0.5) * h, force;
        if (kind == 0) force = a * t;
        else if (kind == 1) force = a * sin(b * t);
        else force = a * (b * t - (x + 0.5 * h * v));
        pc_lugre_advance(f, z, v, h, bristles);
        double acc = (force - bristles[2]) / mass;
        x += h * v + 0.5 * h * h * acc;
        v += h * acc;
        z = bristles[0];
        rows[3 * k] = x;
        rows[3 * k + 1] = v;
        rows[3 * k + 2] = z;
    }
}

/* --- the voltage of a step: controller sample, held voltage, PWM --------------------------------- */

/* A whole number held in a double as uint64 (0 outside [0, 2^64), where C's cast is undefined:
 * Python validates the seeds, but a buffer is also what a restored FMU state wrote). */
static uint64_t whole(double x)
{
    return (x >= 0.0 && x < 18446744073709551616.0) ? (uint64_t)x : 0;
}

/* The current the loop reads at this sample: i_hat plus the offset and the noise (if any). */
static double measured_current(const pc_drive *d, double i_hat)
{
    if (d->i_offset == 0.0 && d->i_noise == 0.0) return i_hat;
    double noise = d->i_noise * pc_drive_gaussian(whole(d->noise_seed), whole(d->noise_instance), whole(d->sample));
    return i_hat + d->i_offset + noise;
}

/* v as the PWM applies it: the nearest multiple of the quantum (ties away from 0). */
static double applied(const pc_drive *d, double v)
{
    double q = d->pwm_quantum;
    if (q == 0.0) return v;
    return copysign(pc_floor(fabs(v) / q + 0.5) * q, v);
}

static void voltage(const pc_drive *d, const pc_controller *c, double i_ref, double v_ref, double i_hat,
                    pc_drive_sample *s)
{
    if (d->current_mode == 0.0) {
        s->v = applied(d, saturate(v_ref, d->v_max));
        s->e = 0.0;
        s->sampled = 0.0;
        s->phase = d->phase;
        return;
    }
    int sampled = pc_sampling_samples(d->phase, d->sample_phase);
    s->e = i_ref - (sampled ? measured_current(d, i_hat) : i_hat);
    s->v = sampled ? applied(d, controller_output(c, s->e)) : d->v;
    s->sampled = sampled ? 1.0 : 0.0;
    s->phase = pc_sampling_next(d->phase, d->substeps);
}

static int check_inputs(double omega, double i_ref, double v_ref, double i_hat, pc_refusal *r)
{
    const double inputs[4] = {omega, i_ref, v_ref, i_hat};   /* PC_DRIVE_OMEGA ... PC_DRIVE_I_HAT */
    for (int k = 0; k < 4; ++k)
        if (!isfinite(inputs[k])) return pc_refuse(r, PC_DRIVE_NONFINITE_INPUT, k, inputs[k]);
    return PC_OK;
}

int pc_drive_peek_voltage(const pc_drive *d, const pc_controller *c, double i_ref, double v_ref, double i_hat,
                          double h, pc_drive_sample *s, pc_refusal *r)
{
    int code = check_inputs(0.0, i_ref, v_ref, i_hat, r);
    if (code != PC_OK) return code;
    if (h != d->h) return pc_refuse(r, PC_DRIVE_UNPREPARED_STEP, 0, h);
    voltage(d, c, i_ref, v_ref, i_hat, s);
    return PC_OK;
}

/* Keep a sample's controller state and phase (not the current nor the applied voltage). */
static void commit_voltage(pc_drive *d, pc_controller *c, const pc_drive_sample *s)
{
    if (s->sampled != 0.0) {
        /* The controller remembers its own output; the PWM quantises only what is applied. */
        controller_commit(c, d->pwm_quantum == 0.0 ? s->v : controller_output(c, s->e), s->e);
        d->sample += 1.0;
    }
    d->phase = s->phase;
}

void pc_drive_commit(pc_drive *d, pc_controller *c, const pc_drive_sample *s, double i)
{
    commit_voltage(d, c, s);
    d->i = i;
    d->v = s->v;
}

int pc_drive_sample_voltage(pc_drive *d, pc_controller *c, double i_ref, double v_ref, double i_hat, double h,
                            double *v, pc_refusal *r)
{
    pc_drive_sample s;
    int code = pc_drive_peek_voltage(d, c, i_ref, v_ref, i_hat, h, &s, r);
    if (code != PC_OK) return code;
    commit_voltage(d, c, &s);   /* the current and the applied v are the caller's to set */
    *v = s.v;
    return PC_OK;
}

/* --- one step ------------------------------------------------------------------------------- */

/* The shaft torque: B.2 (pc_motor.h) or, with the LuGre friction F given, kt i - F. */
static double torque(const pc_drive *d, double i, double omega, const double *friction)
{
    if (friction) return d->kt * i - *friction;
    return pc_shaft_torque(d->kt, d->b, d->mu, d->omega_eps, i, omega);
}

double pc_drive_torque(const pc_drive *d, const pc_lugre *f, double omega)
{
    if (!f) return torque(d, d->i, omega, NULL);
    const double friction = pc_lugre_force(f, f->z, omega);
    return torque(d, d->i, omega, &friction);
}

/* (4.162) over the step and the torque: B.2 (friction NULL) or kt i - F with F = friction[0] at the
 * step's end, friction[1] its mean over the step.  out = {tau, v, i}, also on a refusal. */
static int step(pc_drive *d, pc_controller *c, double i_ref, double v_ref, double omega, double i_hat,
                const double *friction, double out[3], pc_refusal *r)
{
    pc_drive_sample s;
    voltage(d, c, i_ref, v_ref, i_hat, &s);
    double u = s.v - d->ke * omega;
    double i = d->a * d->i + d->g * u;   /* (4.162) over the step */
    double current = i;
    if (d->mean_torque != 0.0) current = d->w_i * d->i + d->w_u * u;   /* mean current over the step */
    double tau = torque(d, current, omega, friction ? friction + (d->mean_torque != 0.0 ? 1 : 0) : NULL);
    out[0] = tau;
    out[1] = s.v;
    out[2] = i;
    if (!isfinite(i)) return pc_refuse(r, PC_DRIVE_DIVERGED, 0, i);
    if (!isfinite(tau)) return pc_refuse(r, PC_DRIVE_DIVERGED, 1, tau);
    pc_drive_commit(d, c, &s, i);
    return PC_OK;
}

static int check_step(const pc_drive *d, double i_ref, double v_ref, double omega, double i_hat, double h,
                      pc_refusal *r)
{
    int code = check_inputs(omega, i_ref, v_ref, i_hat, r);
    if (code != PC_OK) return code;
    if (h != d->h) return pc_refuse(r, PC_DRIVE_UNPREPARED_STEP, 0, h);
    return PC_OK;
}

int pc_drive_step(pc_drive *d, pc_controller *c, pc_lugre *f, double i_ref, double v_ref, double omega,
                  double i_hat, double h, double out[3], pc_refusal *r)
{
    int code = check_step(d, i_ref, v_ref, omega, i_hat, h, r);
    if (code != PC_OK) return code;
    if (!f) return step(d, c, i_ref, v_ref, omega, i_hat, NULL, out, r);
    double bristles[3];   /* z, F_end, F_mean */
    pc_lugre_advance(f, f->z, omega, h, bristles);
    code = step(d, c, i_ref, v_ref, omega, i_hat, bristles + 1, out, r);
    if (code == PC_OK) f->z = bristles[0];
    return code;
}

/* The Python layer's calls (motor.kernel.Calls): x = [i_ref, v_ref, omega, i_hat, h | tau, v, i],
 * the outputs written also on a refusal DIVERGED (the values refused, for the message). */
int pc_drive_step_x(void *context, double *x, pc_refusal *r)
{
    const pc_drive_context *k = (const pc_drive_context *)context;
    return pc_drive_step(k->drive, k->controller, k->lugre, x[0], x[1], x[2], x[3], x[4], x + 5, r);
}

/* x as pc_drive_step_x; the voltage of pc_drive_sample_voltage in x[6]. */
int pc_drive_sample_x(void *context, double *x, pc_refusal *r)
{
    const pc_drive_context *k = (const pc_drive_context *)context;
    return pc_drive_sample_voltage(k->drive, k->controller, x[0], x[1], x[3], x[4], x + 6, r);
}

int pc_drive_io(void *context, double *x, double t, double h, pc_refusal *r)
{
    (void)t;
    const pc_drive_context *k = (const pc_drive_context *)context;
    double out[3];
    int code = pc_drive_step(k->drive, k->controller, k->lugre, x[0], x[1], x[2], x[3], h, out, r);
    if (code == PC_OK) {
        x[4] = out[0];
        x[5] = out[1];
        x[6] = out[2];
    }
    return code;
}
