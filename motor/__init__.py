"""DC motor drives: model, discrete current control, current observer, identification.

Thesis (Coutinho 2019) eq. 4.162-4.164, 7.20, section 7.2.10, appendices B, C, D.
All quantities SI.

The package's names are loaded when first used (PEP 562 ``__getattr__``): importing one
module (an FMU's ``motor.observer``) imports that module only, not the current controller's
design (python-control) or the identification.
"""
import importlib

#: Name -> the submodule that defines it.
_EXPORTS = {
    **dict.fromkeys(("MotorParams", "MOTOR_PRESETS", "get_motor_preset", "motor1", "motor2"), "presets"),
    **dict.fromkeys(("ELECTRICAL_METHODS", "electrical_step_coefficients", "mean_current_coefficients",
                     "advance_current", "coulomb_friction", "armature_current_rate", "shaft_torque"), "electrics"),
    **dict.fromkeys(("THESIS_POLES", "THESIS_T", "current_transfer_function", "solve_pole_placement",
                     "design_current_controller", "CurrentControllerDesign", "CurrentController"),
                    "current_controller"),
    **dict.fromkeys(("DRIVE_MODES", "Drive"), "drive"),
    **dict.fromkeys(("OBSERVER_KINDS", "CurrentObserver"), "observer"),
    **dict.fromkeys(("DATASHEET_KT_OVER_KE", "MEASURED_L", "THESIS_SETTLING_TIMES", "identify", "read_motor_csv",
                     "normal_equations_electrical", "normal_equations_friction", "pole_from_settling_time",
                     "inertia_from_pole"), "identification"),
}

__all__ = list(_EXPORTS)


def __getattr__(name):
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(f"{__name__}.{module}"), name)
    globals()[name] = value
    return value


def __dir__():
    return sorted(set(globals()) | set(_EXPORTS))
