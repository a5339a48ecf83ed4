"""Metrics layer: per-robot timelines of labelled intervals and events, and the
metrics computed from them."""
