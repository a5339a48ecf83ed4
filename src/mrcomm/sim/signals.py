"""Builds the run's signal threshold from its configuration (SLT distance, SSD model
table, ESD trace)."""

from __future__ import annotations

from mrcomm.net.thresholds import DistanceThreshold, NoThreshold, Threshold, threshold_class
from mrcomm.sim.config import RunConfig


def build_threshold(config: RunConfig) -> Threshold:
    cls = threshold_class(config.threshold)
    if cls is NoThreshold:
        return NoThreshold()
    if cls is DistanceThreshold:
        return DistanceThreshold(config.slt_warning)
    raise NotImplementedError(f"threshold {config.threshold!r} is not wired yet")
