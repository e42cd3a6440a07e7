"""Where a mechanism can go, and why the controller refuses a trajectory: ``parcosim workspace``
(:func:`plot_workspace`, in ``plot``), the figure's parts (``figure``), a spec's slice (``spec``)."""
from scenarios.studies.workspace.figure import (BAND, OUTSIDE, TABLE, TrajectoryCheck,  # noqa: F401
                                                WorkspaceReport, check_trajectory, signed_measures,
                                                thesis_trajectories, user_circle)
from scenarios.studies.workspace.plot import plot_workspace  # noqa: F401
