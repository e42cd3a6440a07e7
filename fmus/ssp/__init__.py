"""SSP 1.0: export and read a package, run one in fmpy, Ecos or libcosim."""
