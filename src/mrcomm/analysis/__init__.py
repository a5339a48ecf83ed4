"""Analysis layer: statistics, figures and reports built from run results."""
