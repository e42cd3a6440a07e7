"""parcosim: FMI 2.0 co-simulation components for the 5R parallel robot."""
__version__ = "0.1.0"
