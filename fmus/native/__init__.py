"""Native FMUs: the parcosim models as FMI 2.0 (or 3.0) co-simulation FMUs without Python (issue 28).

``parcosim build --native --out DIR`` (:func:`fmus.native.build.build_native_all`) writes,
per model of :data:`fmus.native.models.NATIVE`, an FMU whose binary is compiled from C alone:
the one generic core (``pcn_core.c``, ``pcn_values.c``, ``pcn_state.c``, ``pcn_text.c``) under
its FMI layer (``fmi2_native.c``, or ``fmi3_native.c`` with ``--fmi-version 3``), the
model's adapter (``adapters/<model>.c``) over its kernel (``kernels/src``), and a generated
table of its variables and of the data its build computed.  Names, value references, start
values and descriptions come from the pythonfmu slave's declarations (the slave is
instantiated and set up at build time), so they exist once.  ``parcosim export-fmu SCENE
OUT.fmu --native`` (:func:`fmus.native.loopbuild.export_native_fmu`) writes a scene's whole
loop the same way: the compiled loop's plan and every component's kernel buffers as build
data (:mod:`fmus.native.loopimage`), run by ``adapters/pcn_closedloop.c``.  docs/native.md.
"""
