"""Many runs on dask.distributed: the engine, sweeps, the reproduction report, the regression."""
