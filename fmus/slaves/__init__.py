"""pythonfmu slave modules, one per FMU, each with a unique module name."""
