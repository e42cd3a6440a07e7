"""Running one scene (``runner``: ``parcosim run``, result.csv, metrics.json, plots) and the
thesis' metrics of a run (``metrics``).

``scenarios.run.run_scene`` keeps its name from before the layout of issue 29 (README,
docs/index.md); code inside the project imports from :mod:`scenarios.run.runner`.
"""
from scenarios.run.runner import result_columns, run_scene  # noqa: F401
