"""A system inside one FMU: the cores that step it, the slave base, ``parcosim export-fmu``."""
