"""The FMI layer: the slave base and what slaves share (``slave/``), the slaves (``slaves/``),
FMU files (``export/``), co-simulation (``cosim/``), a system inside one FMU (``systemfmu/``),
SSP (``ssp/``), native FMUs (``native/``) and hostile use (``hostile/``); docs/layout.md."""

#: Old module -> its place since the layout of issue 29 (:mod:`fmus.moved`).
MOVED = {
    "fmus.adapters": "fmus.cosim.compiled_adapters", "fmus.archive": "fmus.export.archive",
    "fmus.budget": "fmus.slave.budget", "fmus.build": "fmus.export.build",
    "fmus.bundle": "fmus.export.bundle", "fmus.compiled": "fmus.cosim.compiled",
    "fmus.designs": "fmus.slave.designs", "fmus.embedded": "fmus.systemfmu.cores",
    "fmus.fmustate": "fmus.slave.state", "fmus.foreign": "fmus.cosim.foreign",
    "fmus.guarded": "fmus.slave.base", "fmus.identity": "fmus.slave.identity",
    "fmus.instances": "fmus.cosim.backends", "fmus.libcosim_runner": "fmus.ssp.libcosim",
    "fmus.master": "fmus.cosim.master", "fmus.modeldescription": "fmus.export.modeldescription",
    "fmus.parts": "fmus.slave.declarations", "fmus.refusals": "fmus.slave.refusals",
    "fmus.registry": "fmus.slave.registry", "fmus.sampling": "fmus.slave.sampling",
    "fmus.slavestate": "fmus.slave.state_calls", "fmus.specfmu": "fmus.export.specfmu",
    "fmus.ssp_run": "fmus.ssp.run", "fmus.stateformat": "fmus.slave.state_format",
    "fmus.stepper": "fmus.cosim.stepper", "fmus.system": "fmus.cosim.system",
    "fmus.systemslave": "fmus.systemfmu.slave_base", "fmus.wrapper": "fmus.export.wrapper",
}

if __name__ == "fmus":     # not inside an FMU, whose bundle (fmus/export/bundle.py) has no old names
    from fmus.moved import install

    install(MOVED)
