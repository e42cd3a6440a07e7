"""SSP 1.0: export a system to a package and read one back (``export``), run a package in fmpy
or Ecos (``run``) or in libcosim (``libcosim``).  ``fmus.ssp.export_ssp`` and the readers keep
their names from before the layout of issue 29."""
from fmus.ssp.export import export_ssp, read_ssp_experiment, read_ssp_parameters  # noqa: F401
