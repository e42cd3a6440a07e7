"""Running one scene: result.csv, metrics.json, plots; the thesis' metrics."""
