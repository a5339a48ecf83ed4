"""Metrics layer: per-robot timelines of labelled intervals and events, and the SPEC §8
metrics computed from them."""
