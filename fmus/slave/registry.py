"""Which parcosim models exist: model name -> the module of its slave in ``fmus/slaves``.

Kept apart from :mod:`fmus.export.build` so that code running inside an FMU (the in-process
instances of :mod:`fmus.systemfmu.cores`) can look models up without the build machinery.
"""

#: Model name -> slave module (unique module names: one interpreter per process).
SLAVES = {
    "FiveBarPlant": "parcosim_fivebarplant",
    "DCMotorDrive": "parcosim_dcmotordrive",
    "CurrentObserver": "parcosim_currentobserver",
    "Trajectory": "parcosim_trajectory",
    "Derivator": "parcosim_derivator",
    "PositionController": "parcosim_positioncontroller",
    "ActuatedFiveBarPlant": "parcosim_actuatedfivebarplant",
    "WheeledPendulum": "parcosim_wheeledpendulum",
    "BalanceController": "parcosim_balancecontroller",
    # one line per FMU; keep this order (plant, drives, controller chain)
}
