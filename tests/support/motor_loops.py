"""The in-process drive + observer loop shared by the motor tests and the motor FMU tests."""
import numpy as np

from motor import CurrentObserver, Drive

T = 1e-3


def current_step(params, kind, omega, n=40):
    """1 A step at t = 0; observer in the loop; drive started in electrical steady state.

    Returns the drive's current at t = 0, T, ..., n T.
    """
    drive, obs = Drive(params), CurrentObserver(params, kind)
    drive.start(omega)
    obs.reset(0.0, omega)
    i_hat = obs.estimate(drive.v, omega, T)
    i = [drive.i]
    for _ in range(n):
        _, v, i_end = drive.step(1.0, 0.0, omega, i_hat, T)
        i_hat = obs.estimate(v, omega, T)
        i.append(i_end)
    return np.array(i)
