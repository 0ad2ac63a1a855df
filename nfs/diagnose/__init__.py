"""Model against measurements: fit a model to runs, compare, diagnose the missing effect."""
