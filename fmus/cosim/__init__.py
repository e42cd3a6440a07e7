"""Co-simulation: the system as data, the master, the stepper, its back ends (in process, fmpy),
foreign FMUs and the compiled mode's loop."""
