"""kernels/src/design.c's ZOH model and design against 50 digits over draws of the tests' range.

Prints, for n1, n0, d1, d0 (the model) and alpha, beta, gamma, delta (the design), the largest
relative error against mpmath (tests/kernels/test_kernels_design.py's oracles) and the largest
error in units of eps times the value's condition number, over `--draws` log-uniform, as many
uniform and as many bound-heavy motors (R 0.1..20, L 1e-5..2e-2, k 5e-3..0.5, b 1e-7..2e-3,
J 1e-6..2e-3, T of the tests' six) and the s37 Hypothesis draw.  Another build of the kernels
(``PARCOSIM_KERNELS_LIB``, e.g. of an older design.c) is measured the same way (docs/native.md,
"Accuracy of the C design").

    python benchmarks/design_accuracy.py --draws 300 --seed 7
"""
import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from tests.kernels.test_kernels_design import (STIFF, augmented_entries, c_design, c_zoh,  # noqa: E402
                                               condition_numbers, design_values, drawn_motor, zoh_values)

NAMES = ("n1", "n0", "d1", "d0", "alpha", "beta", "gamma", "delta")
LOW = np.array([0.1, 1e-5, 5e-3, 1e-7, 1e-6])
HIGH = np.array([20.0, 2e-2, 0.5, 2e-3, 2e-3])
PERIODS = (1e-4, 2.5e-4, 5e-4, 1e-3, 2e-3, 1e-2)


def draws(rng, n):
    """n log-uniform, n uniform and n bound-heavy (each value a bound, or log-uniform) motors with a T."""
    for mode in ("log", "uniform", "bounds"):
        for _ in range(n):
            values = np.exp(rng.uniform(np.log(LOW), np.log(HIGH))) if mode != "uniform" else rng.uniform(LOW, HIGH)
            if mode == "bounds":
                pick = rng.integers(0, 3, 5)
                values = np.where(pick == 0, LOW, np.where(pick == 1, HIGH, values))
            yield drawn_motor(*values), PERIODS[rng.integers(0, len(PERIODS))]


def errors(p, T):
    """Relative errors and condition numbers of the eight values (values below the smallest normal
    double, a refused design, or one whose 4x4 system is singular in 50 digits, as the tests skip
    it, count as no error)."""
    entries = augmented_entries(p, T)
    try:
        design, design_kappa = design_values(entries), condition_numbers(design_values, entries)
    except ZeroDivisionError:     # the armature's pole underflowed: no unique placement
        design, design_kappa = [0.0] * 4, np.ones(4)
    exact = np.array([float(v) for v in [*zoh_values(entries), *design]])
    kappa = np.concatenate([condition_numbers(zoh_values, entries), design_kappa])
    num, den = c_zoh(p, T)
    code, coefficients, _ = c_design(p, T)
    got = np.array([*num, *den[1:], *coefficients])
    with np.errstate(all="ignore"):
        relative = np.where(np.abs(exact) < np.finfo(float).tiny, 0.0, np.abs(got - exact) / np.abs(exact))
    if code != 0:
        relative[4:] = 0.0
    return relative, kappa


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--draws", type=int, default=300, help="draws of each kind (default: 300)")
    parser.add_argument("--seed", type=int, default=7, help="the draws' seed (default: 7)")
    args = parser.parse_args()
    start, worst, worst_kappa, count = time.time(), np.zeros(8), np.zeros(8), 0
    for p, T in [STIFF[0], *draws(np.random.default_rng(args.seed), args.draws)]:
        relative, kappa = errors(p, T)
        worst = np.maximum(worst, relative)
        worst_kappa = np.maximum(worst_kappa, relative / (np.finfo(float).eps * np.maximum(kappa, 1.0)))
        count += 1
    print(f"{count} motors, {time.time() - start:.0f} s\n\n| value | max relative error | max error / (eps kappa) |\n|---|---|---|")
    for name, w, k in zip(NAMES, worst, worst_kappa):
        print(f"| {name} | {w:.2e} | {k:.3g} |")


if __name__ == "__main__":
    main()
