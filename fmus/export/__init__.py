"""FMU files: the build (pythonfmu, bundle, C wrapper), the ModelStructure fix, archive copies,
``parcosim build-plant``."""
