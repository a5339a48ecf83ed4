"""Wiring of one run from its configuration, the same for every mode: the signal
threshold (network side, all pairs), each robot's link sensor (agent side), every
robot's simulated base, and the network-side link model with its recorder (the links'
ground truth). One place, so that a live run's ground truth is computed exactly as a
simulated run's."""

from __future__ import annotations

from collections.abc import Sequence

from mrcomm.agents.assigner import ASSIGNER_ID
from mrcomm.net.link_sensors import DistanceSensor, MeasuredSensor, ModelSensor, NoSensor
from mrcomm.net.links import LinkModel, LinkRecorder
from mrcomm.net.signal.trace import RssiTrace
from mrcomm.net.signal_thresholds import MeasuredThreshold, ModelThreshold
from mrcomm.net.thresholds import DistanceThreshold, NoThreshold, Threshold, threshold_class
from mrcomm.ports import LinkSensor
from mrcomm.robot.base import SimBase
from mrcomm.run.config import RunConfig
from mrcomm.run.resources import ScenarioResources
from mrcomm.seeding import stream


def build_threshold(config: RunConfig, world: ScenarioResources, ids: Sequence[str]) -> Threshold:
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


def build_link_sensor(config: RunConfig, world: ScenarioResources) -> LinkSensor:
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


def make_bases(world: ScenarioResources, seed: int) -> dict[str, SimBase]:
    """Every robot's base at its start pose, each with its own seeded noise stream."""
    scenario = world.scenario
    return {
        r.id: SimBase(
            r.id,
            scenario.grid,
            world.planner,
            r.pose,
            world.robot_params,
            stream(seed, "robot", r.id),
        )
        for r in scenario.robots
    }


def make_links(world: ScenarioResources, config: RunConfig) -> tuple[LinkModel, LinkRecorder]:
    """The link model of the robots and the task assigner (in that order) and its
    recorder. A hosted assigner shares its robot's position, so its links are its
    host's (evaluated once; ESD's trace has no row for it: it measures with its host's
    card) and its link to its host is not a link."""
    scenario = world.scenario
    robot_ids = tuple(r.id for r in scenario.robots)
    node_ids = (*robot_ids, ASSIGNER_ID)
    host = scenario.assigner.host
    aliases = {ASSIGNER_ID: host} if host else {}
    evaluated = tuple(n for n in node_ids if n not in aliases)
    links = LinkModel(
        node_ids,
        scenario.grid,
        config.network,
        build_threshold(config, world, evaluated),
        ah_range=config.ah_range,
        aliases=aliases,
    )
    skip = {(ASSIGNER_ID, host), (host, ASSIGNER_ID)} if host else set()
    return links, LinkRecorder(node_ids, len(robot_ids), skip)
