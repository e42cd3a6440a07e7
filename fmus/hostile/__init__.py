"""Hostile and careless use of the FMUs: the case generator, the worker, the long campaign."""
