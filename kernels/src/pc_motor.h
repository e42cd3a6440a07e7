/* The DC motor's two equations every kernel that holds a motor shares (the drive, the
 * actuated 5R): the shaft torque (B.2, thesis appendix B; motor.shaft_torque) and the
 * armature current rate (4.162).  The drive's LuGre friction extends the torque (drive.h). */
#ifndef PC_MOTOR_H
#define PC_MOTOR_H

#include <math.h>

/* tau = kt i - b omega - mu tanh(omega / omega_eps)  (B.2: viscous + smoothed Coulomb). */
static inline double pc_shaft_torque(double kt, double b, double mu, double omega_eps, double i, double omega)
{
    return kt * i - b * omega - mu * tanh(omega / omega_eps);
}

/* di/dt = (v - R i - ke omega) / L  (4.162). */
static inline double pc_armature_rate(double R, double L, double ke, double v, double i, double omega)
{
    return (v - R * i - ke * omega) / L;
}

#endif
