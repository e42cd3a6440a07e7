"""Bode plot and figures of merit of the derivators (thesis 7.2.3).

Run from the repository root::

    python -m scenarios.examples.plot_derivators [--out out/derivators_bode.png | --docs]

Writes the Bode plot of both estimates relative to ideal differentiation and prints
the numbers quoted in ``docs/derivators.md``: delays, phase lags, encoder
quantisation noise, phase margin of the position loop, transient lengths, and the
same figures for neighbouring cut-offs.
"""

import argparse
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from controller.derivators import DEFAULT_FC_ACC, DEFAULT_FC_VEL, SAMPLE_TIME, Derivator  # noqa: E402

ENCODER_STEP = 2 * np.pi / 20000
"""One quadrature count of the bench encoders, rad (the brief ../shared/spec/SYSTEM.md section 3)."""
LOOP_LAMBDAS = (35.0, 60.0, 70.0)
"""Position-loop parameters of Tables 6-8, rad/s."""
REPORT_FREQUENCIES = (1.0, 5.0, 11.0)
"""Hz: the trajectories' 1 Hz, and half and all of lambda = 70 rad/s."""
TRANSIENT_TOLERANCE = 1e-9


def lag_degrees(derivator, f):
    """Phase lags (deg) of the velocity and acceleration estimates behind the ideal derivatives."""
    velocity, acceleration = derivator.frequency_response(f)
    omega = 2 * np.pi * np.asarray(f)
    return (
        -np.degrees(np.angle(velocity / (1j * omega))),
        -np.degrees(np.angle(acceleration / -(omega**2))),
    )


def impulse_noise_gains(derivator, samples=4000):
    """rms outputs per unit rms white input: sqrt(sum h^2) of both estimates, from the implementation."""
    derivator.reset([0.0])
    responses = np.array([np.concatenate(derivator.step([1.0 if k == 0 else 0.0])) for k in range(samples)])
    return np.sqrt((responses**2).sum(axis=0))


def simulated_quantisation_noise(derivator, seconds=10.0):
    """rms of (estimate of encoder counts - estimate of exact angle) on a 1 Hz, 0.5 rad sine.

    Returns the velocity and acceleration rms, and the velocity rms of the bare
    backward difference for comparison.
    """
    t = np.arange(int(seconds / derivator.T)) * derivator.T
    exact = 0.5 * np.sin(2 * np.pi * t) + 0.3
    counted = np.round(exact / ENCODER_STEP) * ENCODER_STEP
    derivator.reset([exact[0], counted[0]])
    estimates = np.array([np.stack(derivator.step([a, b])) for a, b in zip(exact, counted)])
    settled = estimates[len(t) // 10 :]
    error = settled[:, :, 1] - settled[:, :, 0]
    bare = np.diff(counted - exact) / derivator.T
    return np.sqrt((error**2).mean(axis=0)), np.sqrt((bare**2).mean())


def phase_margin(derivator, lam, extra_delay_steps=0):
    """Phase margin (deg) and crossover (Hz) of kp + kv*velocity estimate on 1/s^2 behind a zero-order hold.

    The loop is L(z) = (lam^2 + 2 lam H_v(z)) T^2 (z + 1) / (2 (z - 1)^2) z^-d, the
    feedback-linearised joint (or task) loop with kp = lam^2, kv = 2 lam (7.29-7.30).
    """
    T = derivator.T
    f = np.linspace(0.01, 0.5 / T * 0.999, 200000)
    z = np.exp(2j * np.pi * f * T)
    velocity, _ = derivator.frequency_response(f)
    loop = (lam**2 + 2 * lam * velocity) * T**2 * (z + 1) / (2 * (z - 1) ** 2) * z ** (-extra_delay_steps)
    crossing = np.argmax(np.abs(loop) < 1.0)
    phase = np.degrees(np.unwrap(np.angle(loop)))[crossing]
    return 180.0 + phase, f[crossing]


def ideal_phase_margin(lam):
    """Phase margin (deg) of (lam^2 + 2 lam s)/s^2 with exact velocity and no sampling."""
    crossover = lam * np.sqrt(2 + np.sqrt(5))
    return np.degrees(np.arctan(2 * crossover / lam))


def transient_samples(derivator, horizon=1000):
    """Last sample (from a start at rest) where the ramp/parabola results miss by more than 1e-9 relative.

    Returns the counts for: ramp velocity, ramp acceleration (relative to the slope,
    in 1/s), parabola acceleration.
    """
    t = np.arange(horizon) * derivator.T
    slope, curvature = 2.7, 7.3
    ramp, parabola = 1.3 + slope * t, 0.4 + 0.5 * curvature * t**2
    derivator.reset([ramp[0], parabola[0]])
    estimates = np.array([np.stack(derivator.step([r, p])) for r, p in zip(ramp, parabola)])
    misses = (
        np.abs(estimates[:, 0, 0] - slope) > TRANSIENT_TOLERANCE * slope,
        np.abs(estimates[:, 1, 0]) > TRANSIENT_TOLERANCE * slope,
        np.abs(estimates[:, 1, 1] - curvature) > TRANSIENT_TOLERANCE * curvature,
    )
    return tuple(int(np.nonzero(miss)[0].max()) + 1 for miss in misses)


def report(derivator):
    """Print the figures of merit of one pair of cut-offs."""
    velocity_gain, acceleration_gain = impulse_noise_gains(derivator)
    white_scale = ENCODER_STEP / np.sqrt(12)
    print(f"fc_vel = {derivator.fc_vel:g} Hz, fc_acc = {derivator.fc_acc:g} Hz, T = {derivator.T:g} s")
    print(f"  delays: velocity {derivator.velocity_delay * 1e3:.2f} ms, acceleration {derivator.acceleration_delay * 1e3:.2f} ms")
    velocity_lag, acceleration_lag = lag_degrees(derivator, REPORT_FREQUENCIES)
    velocity, acceleration = derivator.frequency_response(REPORT_FREQUENCIES)
    for f, lag_v, lag_a, h_v, h_a in zip(REPORT_FREQUENCIES, velocity_lag, acceleration_lag, velocity, acceleration):
        omega = 2 * np.pi * f
        print(
            f"  {f:4g} Hz: velocity lag {lag_v:5.2f} deg, gain {abs(h_v) / omega:.4f}; "
            f"acceleration lag {lag_a:5.2f} deg, gain {abs(h_a) / omega**2:.4f}"
        )
    print(
        f"  white quantisation noise (variance step^2/12): velocity {white_scale * velocity_gain:.4f} rad/s rms, "
        f"acceleration {white_scale * acceleration_gain:.3f} rad/s^2 rms"
    )
    (noise_v, noise_a), bare_v = simulated_quantisation_noise(derivator)
    print(
        f"  encoder counts on a 1 Hz 0.5 rad sine: velocity {noise_v:.4f} rad/s rms (bare difference {bare_v:.4f}), "
        f"acceleration {noise_a:.3f} rad/s^2 rms"
    )
    for lam in LOOP_LAMBDAS:
        margin, crossover = phase_margin(derivator, lam)
        delayed_margin, _ = phase_margin(derivator, lam, extra_delay_steps=1)
        print(
            f"  lambda {lam:g} rad/s: phase margin {margin:.1f} deg at {crossover:.1f} Hz "
            f"({delayed_margin:.1f} deg with one more step of delay; ideal {ideal_phase_margin(lam):.1f} deg)"
        )
    ramp_v, ramp_a, parabola_a = transient_samples(derivator)
    print(
        f"  within {TRANSIENT_TOLERANCE:g} relative from sample: ramp velocity {ramp_v}, "
        f"ramp acceleration {ramp_a}, parabola acceleration {parabola_a}"
    )


def compare_cutoffs(fc_vels=(60.0, 80.0, 100.0, 150.0), fc_accs=(30.0, 40.0, 50.0, 60.0)):
    """Print lag, white-noise rms and phase margin (lambda = 70) for neighbouring cut-offs."""
    white_scale = ENCODER_STEP / np.sqrt(12)
    print("velocity cut-off: delay, lag at 5/11 Hz, noise, phase margin at lambda 70 (plain / one more step)")
    for fc_vel in fc_vels:
        derivator = Derivator(fc_vel, DEFAULT_FC_ACC)
        lag, _ = lag_degrees(derivator, (5.0, 11.0))
        noise = white_scale * impulse_noise_gains(derivator)[0]
        margins = [phase_margin(derivator, 70.0, steps)[0] for steps in (0, 1)]
        print(
            f"  {fc_vel:5g} Hz: {derivator.velocity_delay * 1e3:.2f} ms, {lag[0]:.1f}/{lag[1]:.1f} deg, "
            f"{noise:.4f} rad/s, {margins[0]:.1f}/{margins[1]:.1f} deg"
        )
    print(f"acceleration cut-off (fc_vel {DEFAULT_FC_VEL:g} Hz): delay, lag at 1/5/11 Hz, noise")
    for fc_acc in fc_accs:
        derivator = Derivator(DEFAULT_FC_VEL, fc_acc)
        _, lag = lag_degrees(derivator, REPORT_FREQUENCIES)
        noise = white_scale * impulse_noise_gains(derivator)[1]
        print(
            f"  {fc_acc:5g} Hz: {derivator.acceleration_delay * 1e3:.2f} ms, "
            f"{lag[0]:.1f}/{lag[1]:.1f}/{lag[2]:.1f} deg, {noise:.3f} rad/s^2"
        )


def plot_bode(derivator, path):
    """Write the Bode plot of both estimates, relative to ideal differentiation, to ``path``."""
    f = np.logspace(-1, np.log10(0.5 / derivator.T), 600)[:-1]
    omega = 2 * np.pi * f
    velocity, acceleration = derivator.frequency_response(f)
    velocity_phase, acceleration_phase = (np.degrees(np.unwrap(-np.radians(lag))) for lag in lag_degrees(derivator, f))
    figure, (magnitude_axes, phase_axes) = plt.subplots(2, 1, sharex=True, figsize=(7.5, 6.5))
    magnitude_axes.semilogx(f, 20 * np.log10(np.abs(velocity) / omega), label=f"velocity, 2nd-order Bessel {derivator.fc_vel:g} Hz")
    magnitude_axes.semilogx(f, 20 * np.log10(np.abs(acceleration) / omega**2), label=f"acceleration, 8th-order Bessel {derivator.fc_acc:g} Hz")
    magnitude_axes.set_ylabel("|H| / ideal  [dB]")
    magnitude_axes.set_ylim(-80, 10)
    phase_axes.semilogx(f, velocity_phase, label=f"velocity (delay {derivator.velocity_delay * 1e3:.2f} ms)")
    phase_axes.semilogx(f, acceleration_phase, label=f"acceleration (delay {derivator.acceleration_delay * 1e3:.2f} ms)")
    phase_axes.set_ylabel("phase - ideal  [deg]")
    phase_axes.set_xlabel("frequency  [Hz]")
    for axes in (magnitude_axes, phase_axes):
        for marker in (5.0, 11.0):
            axes.axvline(marker, color="grey", lw=0.8, ls=":")
        axes.grid(True, which="both", lw=0.3)
        axes.legend(loc="lower left", fontsize=8)
    magnitude_axes.set_title(f"Derivators at T = {derivator.T * 1e3:g} ms, relative to d/dt and d2/dt2 (dotted: 5, 11 Hz)")
    figure.tight_layout()
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    figure.savefig(path, dpi=120)
    print(f"wrote {path}")


def main():
    """Parse the arguments, print the figures, write the plot."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="out/derivators_bode.png", help="PNG path (default out/derivators_bode.png)")
    parser.add_argument("--docs", action="store_true", help="write docs/derivators_bode.png instead")
    parser.add_argument("--fc-vel", type=float, default=DEFAULT_FC_VEL, help="velocity cut-off, Hz")
    parser.add_argument("--fc-acc", type=float, default=DEFAULT_FC_ACC, help="acceleration cut-off, Hz")
    arguments = parser.parse_args()
    derivator = Derivator(arguments.fc_vel, arguments.fc_acc, SAMPLE_TIME)
    report(derivator)
    compare_cutoffs()
    plot_bode(derivator, Path(__file__).resolve().parents[2] / "docs" / "derivators_bode.png" if arguments.docs
              else arguments.out)


if __name__ == "__main__":
    main()
