"""The Jacobi delay benchmark's compensated loop (benchmarks/jacobi_delay_margin.py
``--compensate``, the law's ``delay_compensation`` linearised)."""
from benchmarks.jacobi_delay_margin import limit
from benchmarks.twin_linear_margin import loop_at, plant, rotor_inertias, velocity_chain
from controller.trajectories import get_trajectory
from plant import get_preset


def _pdx_at_start():
    params = get_preset("bench")
    x, y = get_trajectory("circle").start_point
    Ml, families = loop_at(params, params.with_rotors(0.0, 0.0), x, y)
    return plant(Ml, rotor_inertias(params)), families["PDx"][0], velocity_chain()


def test_compensation_without_delay_is_the_plain_loop():
    """With no delay the compensation has nothing to predict: the same limit as the plain law.
    Catches the compensated loop feeding its registers or its low-passed part into the law
    when there is no delay."""
    system, G, derivator = _pdx_at_start()
    assert limit(system, G, derivator, (0, 0), compensate=True) == limit(system, G, derivator, (0, 0))


def test_compensation_gives_back_part_of_the_margin_the_delay_takes():
    """The 1 ms package's delays (2, 3) put the task-space PD at its limit (71 against its
    λ 70); compensated, the limit is well above λ and still below the undelayed loop's.
    Catches a prediction with the wrong sign or period (it lowers the limit) and one that
    claims more than the undelayed loop."""
    system, G, derivator = _pdx_at_start()
    undelayed = limit(system, G, derivator, (0, 0))
    plain = limit(system, G, derivator, (2, 3))
    compensated = limit(system, G, derivator, (2, 3), compensate=True)
    assert plain < 80 < 1.2 * 70 < compensated < undelayed, (plain, compensated, undelayed)
