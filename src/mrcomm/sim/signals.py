"""Builds the run's signal threshold from its configuration (SLT distance, SSD model
table, ESD trace)."""

from __future__ import annotations

from mrcomm.net.link_sensors import DistanceSensor, NoSensor
from mrcomm.net.thresholds import DistanceThreshold, NoThreshold, Threshold, threshold_class
from mrcomm.ports import LinkSensor
from mrcomm.sim.config import RunConfig
from mrcomm.world.occupancy import OccupancyGrid


def build_threshold(config: RunConfig) -> Threshold:
    cls = threshold_class(config.threshold)
    if cls is NoThreshold:
        return NoThreshold()
    if cls is DistanceThreshold:
        return DistanceThreshold(config.slt_warning)
    raise NotImplementedError(f"threshold {config.threshold!r} is not wired yet")


def build_link_sensor(config: RunConfig, grid: OccupancyGrid) -> LinkSensor:
    """The link sensor a robot's agent judges its links with (one per robot)."""
    if config.threshold == "none":
        return NoSensor()
    if config.threshold == "slt":
        return DistanceSensor(config.slt_warning)
    raise NotImplementedError(f"threshold {config.threshold!r} is not wired yet")
