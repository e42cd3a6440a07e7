"""Scenes and what is done with them: scenes as data (``scenes/``), running one (``run/``), the
monolithic reference (``reference.py``), batch work (``batch/``), SSP packages of a scene
(``packaging/``), studies (``studies/``) and examples to copy (``examples/``); docs/layout.md."""
from fmus.moved import install

#: Old module -> its place since the layout of issue 29 (:mod:`fmus.moved`).
MOVED = {
    "scenarios.accurate_bench": "scenarios.examples.accurate_bench",
    "scenarios.balancing": "scenarios.studies.balancing", "scenarios.engine": "scenarios.batch.engine",
    "scenarios.friction_demo": "scenarios.examples.friction_demo", "scenarios.hostile": "fmus.hostile.cases",
    "scenarios.hostile_campaign": "fmus.hostile.campaign", "scenarios.hostile_worker": "fmus.hostile.worker",
    "scenarios.metrics": "scenarios.run.metrics", "scenarios.package": "scenarios.packaging.chain",
    "scenarios.pendulum": "scenarios.scenes.pendulum",
    "scenarios.pendulum_trade": "scenarios.studies.pendulum_trade",
    "scenarios.per_component": "scenarios.packaging.per_component",
    "scenarios.perturb": "scenarios.scenes.perturb", "scenarios.plant_demo": "scenarios.examples.plant_demo",
    "scenarios.plot_derivators": "scenarios.examples.plot_derivators",
    "scenarios.regression": "scenarios.batch.regression", "scenarios.report": "scenarios.batch.report",
    "scenarios.robustness": "scenarios.studies.robustness", "scenarios.sweep": "scenarios.batch.sweep",
    "scenarios.sweep_plots": "scenarios.batch.sweep_plots", "scenarios.tools": "scenarios.studies.tools",
    "scenarios.trade": "scenarios.studies.trade", "scenarios.twin": "scenarios.scenes.twin",
    "scenarios.twin_fit": "scenarios.studies.twin_fit",
    "scenarios.twin_margin": "scenarios.studies.twin_margin",
    "scenarios.worker_path": "scenarios.batch.worker_path",
    "scenarios.workspace": "scenarios.studies.workspace",
    "scenarios.workspace_spec": "scenarios.studies.workspace.spec",
}

install(MOVED)
