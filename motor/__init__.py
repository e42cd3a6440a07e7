"""DC motor drives: model, discrete current control, current observer, identification.

Thesis (Coutinho 2019) eq. 4.162-4.164, 7.20, section 7.2.10, appendices B, C, D.
All quantities SI.
"""

from motor.current_controller import (THESIS_POLES, THESIS_T, CurrentController, CurrentControllerDesign,
                                      current_transfer_function, design_current_controller,
                                      solve_pole_placement)
from motor.drive import DRIVE_MODES, Drive
from motor.electrics import (ELECTRICAL_METHODS, advance_current, armature_current_rate, coulomb_friction,
                             electrical_step_coefficients, mean_current_coefficients, shaft_torque)
from motor.identification import (DATASHEET_KT_OVER_KE, MEASURED_L, THESIS_SETTLING_TIMES, identify,
                                  inertia_from_pole, normal_equations_electrical,
                                  normal_equations_friction, pole_from_settling_time, read_motor_csv)
from motor.observer import OBSERVER_KINDS, CurrentObserver
from motor.presets import MOTOR_PRESETS, MotorParams, get_motor_preset, motor1, motor2

__all__ = [
    "MotorParams", "MOTOR_PRESETS", "get_motor_preset", "motor1", "motor2",
    "ELECTRICAL_METHODS", "electrical_step_coefficients", "mean_current_coefficients", "advance_current", "coulomb_friction",
    "armature_current_rate",
    "shaft_torque",
    "THESIS_POLES", "THESIS_T", "current_transfer_function", "solve_pole_placement",
    "design_current_controller", "CurrentControllerDesign", "CurrentController",
    "DRIVE_MODES", "Drive",
    "OBSERVER_KINDS", "CurrentObserver",
    "DATASHEET_KT_OVER_KE", "MEASURED_L", "THESIS_SETTLING_TIMES", "identify", "read_motor_csv",
    "normal_equations_electrical", "normal_equations_friction", "pole_from_settling_time",
    "inertia_from_pole",
]
