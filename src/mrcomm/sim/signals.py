"""Builds a run's signal threshold (network side, all pairs) and each robot's link
sensor (agent side) from its configuration: SLT distance, SSD model table, ESD trace."""

from __future__ import annotations

from collections.abc import Sequence

from mrcomm.net.link_sensors import DistanceSensor, MeasuredSensor, ModelSensor, NoSensor
from mrcomm.net.signal.trace import RssiTrace
from mrcomm.net.signal_thresholds import MeasuredThreshold, ModelThreshold
from mrcomm.net.thresholds import DistanceThreshold, NoThreshold, Threshold, threshold_class
from mrcomm.ports import LinkSensor
from mrcomm.sim.config import RunConfig
from mrcomm.sim.world import SimWorld


def build_threshold(config: RunConfig, world: SimWorld, ids: Sequence[str]) -> Threshold:
    cls = threshold_class(config.threshold)
    if cls is NoThreshold:
        return NoThreshold()
    if cls is DistanceThreshold:
        return DistanceThreshold(config.slt_warning)
    if cls is ModelThreshold:
        return ModelThreshold(world.signal_table(config.signal_model), config.ssd_warning)
    if cls is MeasuredThreshold:
        assert config.rssi_trace is not None  # the config validator insists
        return MeasuredThreshold(world.rssi_trace(config.rssi_trace), ids, config.esd_warning)
    raise NotImplementedError(f"threshold {config.threshold!r} has no builder in sim/signals.py")


def build_link_sensor(config: RunConfig, world: SimWorld) -> LinkSensor:
    """The link sensor a robot's agent judges its links with (one per robot)."""
    if config.threshold == "slt":
        return DistanceSensor(config.slt_warning)
    if config.threshold == "ssd":
        table = world.signal_table(config.signal_model)
        return ModelSensor(world.scenario.grid, table, config.ssd_warning)
    if config.threshold == "esd":
        return MeasuredSensor(config.esd_warning)
    return NoSensor()


class TracePulse:
    """ESD in simulation: plays each robot's pulse process, handing its agent's sensor
    the trace's latest reading of every peer at the pulse rate (2 Hz)."""

    period = 0.5

    def __init__(
        self, trace: RssiTrace, sensors: dict[str, MeasuredSensor], robots: Sequence[str]
    ) -> None:
        self.trace = trace
        self.sensors = sensors
        self.robots = tuple(robots)
        self._next = 0.0

    def step(self, now: float) -> None:
        if now < self._next:
            return
        self._next = now + self.period
        if now > self.trace.t1:
            return  # the recording has ended: the pulse reports nothing more
        matrix = self.trace.matrix_at(now, self.robots)
        for i, robot in enumerate(self.robots):
            sensor = self.sensors.get(robot)
            if sensor is None:
                continue
            for j, peer in enumerate(self.robots):
                value = matrix[i, j]
                if i != j and value == value:  # skip NaN: no reading yet
                    sensor.update(peer, float(value), now)
