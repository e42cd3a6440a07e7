"""The slave base and what every slave shares: refusals, sampling, the work budget, the FMU state,
shared declarations, the identity and designs an FMU carries, the model registry."""
