"""Why a per-component package stepped at the 1 ms period oscillates under the task-space PD laws.

    python benchmarks/jacobi_delay_margin.py [--delays 0,0 2,3 2,2 1,1] [--points 24] [--predict | --compensate]

A Jacobi master (Ecos, libcosim, fmpy's ``simulate_ssp``) steps every instance from the
values all held at the step's start, so each connection costs a step.  At h = T = 1 ms the
bench's chain plant -> controller -> drive -> plant puts the torque computed from the angles
of t_k on the plant over [t_k+2, t_k+3] (our Gauss-Seidel master: over [t_k, t_k+1]), and the
velocity comes one connection later (plant -> derivator -> controller): 2 periods of delay on
the position feedback, 3 on the velocity feedback.  Each strategy family's joint loop
linearised about rest along the circle and the triangle (``benchmarks/twin_linear_margin.py``'s
plant with the bench's own link inertias and rotors, the derivator's velocity chain, the law
τ = G (λ² e + 2λ ė)), with those delays on the two feedbacks: the smallest λ whose closed
loop has a pole on or outside the unit circle along the path, beside the strategies' λ.
``--predict``: the controller extrapolates the angle it has over the position delay with the
velocity estimate it has (y + a T v), the usual compensation of a known delay.
``--compensate``: the law's delay compensation (``kernels/src/law.h``, ``delay_compensation``):
the rates carried from b periods back and the angles over the a periods with the accelerations
the law commanded (its model: G is the inertia), less their low-passed part (at λ), against which
the plant is taken not to move.  The drives' current loops, friction, quantisation and the
sliding-mode terms are left out.
Figures: docs/ssp.md ("A drive that closes its own current loop").
"""
from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from twin_linear_margin import T, loop_at, plant, rotor_inertias, velocity_chain  # noqa: E402

from controller.strategies import get_strategy  # noqa: E402
from controller.trajectories import get_trajectory  # noqa: E402
from plant import get_preset  # noqa: E402

#: (position delay, velocity delay) in periods: our master, the 1 ms package, alternatives.
DELAYS = ((0, 0), (2, 3), (2, 2), (1, 1))


def closed_loop(Ad, Bd, Cm, G, lam, derivator, position_delay: int, velocity_delay: int,
                predict: bool = False, compensate: bool = False) -> np.ndarray:
    """The closed loop's state matrix on [plant, derivator, the last ``position_delay``
    angle samples, the last ``velocity_delay`` velocity estimates]: u_k = -G (λ² y_k-a +
    2λ v_k-b) held over [t_k, t_k+1], y = Cm x, v the derivator's estimate of y; with
    ``predict`` y_k-a + a T v_k-b in place of y_k-a; with ``compensate`` also the last
    max(a, b) commanded accelerations and their low-passed part (``pc_law_predict``)."""
    va, vb, vc, vd = (np.kron(np.eye(2), m) for m in derivator)
    n, nv, a, b = Ad.shape[0], va.shape[0], position_delay, velocity_delay
    kept = max(a, b) if compensate else 0
    size = n + nv + 2 * a + 2 * b + (2 * kept + 2 if compensate else 0)
    iy, iv = n + nv, n + nv + 2 * a          # the registers' first slots (newest first)
    ia = iv + 2 * b                          # commanded accelerations (newest first), then the bias
    E = np.eye(size)
    M = np.zeros((size, size))
    M[:n, :n] = Ad
    M[n:n + nv, :n], M[n:n + nv, n:n + nv] = vb @ Cm, va
    y_now, v_now = np.zeros((2, size)), np.zeros((2, size))
    y_now[:, :n] = Cm
    v_now[:, :n], v_now[:, n:n + nv] = vd @ Cm, vc
    y_used = y_now if a == 0 else E[iy + 2 * (a - 1):iy + 2 * a]
    v_used = v_now if b == 0 else E[iv + 2 * (b - 1):iv + 2 * b]
    if compensate:
        bias = E[ia + 2 * kept:ia + 2 * kept + 2]
        acc = [None] + [E[ia + 2 * (j - 1):ia + 2 * j] - bias for j in range(1, kept + 1)]
        v = v_used + T * sum((acc[j] for j in range(a + 1, b + 1)), np.zeros((2, size))) \
            - T * sum((acc[j] for j in range(b + 1, a + 1)), np.zeros((2, size)))
        y = y_used
        for j in range(a, 0, -1):
            y, v = y + T * v + 0.5 * T * T * acc[j], v + T * acc[j]
        command = -(lam ** 2 * y + 2 * lam * v)
    else:
        horizon = a * T if predict else 0.0
        command = -(lam ** 2 * (y_used + horizon * v_used) + 2 * lam * v_used)
    M[:n] += Bd @ G @ command
    registers = [(iy, a, y_now), (iv, b, v_now)] + ([(ia, kept, command)] if compensate else [])
    for start, depth, now in registers:
        if depth:
            M[start:start + 2] = now
            for i in range(1, depth):
                M[start + 2 * i:start + 2 * i + 2, start + 2 * (i - 1):start + 2 * i] = np.eye(2)
    if compensate:                            # bias <- bias + α (command - bias), α = Tλ / (1 + Tλ)
        alpha = T * lam / (1.0 + T * lam)
        M[ia + 2 * kept:ia + 2 * kept + 2] = (1.0 - alpha) * bias + alpha * command
    return M


def limit(system, G, derivator, delays, predict=False, compensate=False, lams=np.arange(1.0, 300.0, 1.0)) -> float:
    """The smallest λ of ``lams`` with a closed-loop pole on or outside the unit circle."""
    for lam in lams:
        loop = closed_loop(*system, G, lam, derivator, *delays, predict, compensate)
        if max(abs(np.linalg.eigvals(loop))) >= 1.0:
            return float(lam)
    return math.inf


def path_limits(kind: str, delays, points: int = 24, predict: bool = False, compensate: bool = False) -> dict:
    """{family: smallest λ limit over ``points`` points of trajectory ``kind``} with ``delays``."""
    params = get_preset("bench")
    links, Jr, derivator = params.with_rotors(0.0, 0.0), rotor_inertias(params), velocity_chain()
    trajectory = get_trajectory(kind)
    best = {}
    for t in np.linspace(0.0, trajectory.duration, points, endpoint=False):
        Ml, families = loop_at(params, links, trajectory(t).x, trajectory(t).y)
        system = plant(Ml, Jr)
        for name, (G, _lam) in families.items():
            best[name] = min(best.get(name, math.inf), limit(system, G, derivator, delays, predict, compensate))
    return best


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--delays", nargs="+", default=[f"{a},{b}" for a, b in DELAYS],
                        help="position,velocity delays in periods (0,0: our master; 2,3: the 1 ms package)")
    parser.add_argument("--points", type=int, default=24)
    parser.add_argument("--predict", action="store_true", help="the controller extrapolates the angle over its delay")
    parser.add_argument("--compensate", action="store_true",
                        help="the law's delay compensation (delay_compensation) over the delays given")
    args = parser.parse_args(argv)
    lams = {"PDq": {k: get_strategy("PDq", k).lam for k in ("circle", "triangle")},
            "TCq/TCx": {k: get_strategy("TCx").lam for k in ("circle", "triangle")},
            "PDx": {k: get_strategy("PDx").lam for k in ("circle", "triangle")}}
    print("| path | delays (position, velocity) [periods] | " + " | ".join(f"{f} limit (λ)" for f in lams) + " |")
    print("|---|---|" + "---|" * len(lams))
    for kind in ("circle", "triangle"):
        for text in args.delays:
            delays = tuple(int(v) for v in text.split(","))
            found = path_limits(kind, delays, args.points, args.predict, args.compensate)
            cells = [f"{found[f]:.0f} ({lams[f][kind]:.0f})" for f in lams]
            print(f"| {kind} | {delays[0]}, {delays[1]} | " + " | ".join(cells) + " |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
