"""The FMI layer: pythonfmu slaves over the pure models, their build and the
model-description fix."""
