"""Speed against accuracy: a sweep over a scene's settings, measured against its monolithic reference.

``parcosim trade [SCENE] [--quick] [--out DIR]`` is :func:`run_trade`
(:mod:`scenarios.studies.trade.study`; the settings in ``settings``, the runs and their
measurement in ``measure``, the files in ``report``)::

    from scenarios.studies.trade import run_trade
    trade = run_trade("bench_circle_TCMDx", quick=True, out_dir="out/trade")
    for row in trade.rows:
        print(row["setting"], row["wall_s"], row["rms_err_m"])

Each setting is the scene with one change (:data:`Setting.build` rewrites its
:class:`fmus.cosim.system.System`). Every run is compared with ONE reference run of the unmodified
scene (:func:`scenarios.reference.reference_run`, the truth). The deviation means different
things for the two kinds of row:

* ``kind = "accuracy"``: the same model computed differently (plant integrator, sub-steps
  and tolerances, the drive's electrical integration, drive/plant sub-stepping, the drive's
  torque output, the drives integrated inside the plant, Gauss-Seidel or Jacobi, ``fmu`` or
  ``inprocess``). The deviation is an error. The Pareto front (wall time against RMS error)
  is taken over these rows only.
* ``kind = "fidelity"``: a different model (the :class:`scenarios.scenes.thesis.Fidelity` switches,
  the controller's exact or tabulated model and its grid, another sample time). The
  deviation is what the effect changes in the result, not an error. These rows are in the
  table and the plot (another marker), never on the front.

Columns of ``trade.csv`` (one row per setting): ``setting``, ``kind``, ``what`` (the change);
``wall_s`` (the whole :func:`fmus.cosim.master.simulate` call: loading, initialisation and stepping,
best of the rounds, so one-time costs such as imports and table builds drop out);
``cpu_s`` (the process's CPU time over the same call); ``speedup`` (the defaults' wall over
this one); ``rms_err_m`` and ``max_err_m`` (end-effector distance from the reference over the
whole run); ``gain`` (the defaults' RMS over this one); ``residual_m`` (largest loop-closure
residual, 5.18); ``current_err_A`` (RMS over the samples of the drives' current deviation,
sqrt(Δi1² + Δi2²)); ``energy_err`` (relative deviation of the electrical energy the drives
draw, ∫ (v1 i1 + v2 i2) dt); ``enc_diff`` (samples at which an encoder reading differs from the
reference's) and ``enc_first_s`` (the first one's time); ``e_ef_mm`` (the thesis' tracking
error, 7.31); ``pareto``; ``error`` (why a run stopped). Columns that do not apply are empty.

The full sweep also writes ``noquant.csv``: the drive/plant coupling settings against a
reference of the same scene with the encoders' quantisation removed (2^30 counts per
revolution, in the reference and in every run): what those settings buy where a change
smaller than one encoder count does not flip the closed loop onto another path (see
``docs/trade.md``).
"""
from scenarios.studies.trade.measure import Trade, measure, pareto  # noqa: F401
from scenarios.studies.trade.report import COLUMNS, markdown_table  # noqa: F401
from scenarios.studies.trade.settings import Setting, settings  # noqa: F401
from scenarios.studies.trade.study import DEFAULT_SCENE, run_trade  # noqa: F401
