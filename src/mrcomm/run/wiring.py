"""Wiring of one run from its configuration, the same for every mode: the signal
threshold (network side, all pairs), each robot's link sensor (agent side), every
robot's simulated base, and the network-side link model with its recorder (the links'
ground truth). One place, so that a live run's ground truth is computed exactly as a
simulated run's."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path

from pydantic import BaseModel

from mrcomm.agents.assigner import ASSIGNER_ID
from mrcomm.agents.commands import OPERATOR_ID
from mrcomm.net.link_sensors import MeasuredSensor
from mrcomm.net.links import LinkModel, LinkRecorder, LinkState
from mrcomm.net.network import NetworkModel
from mrcomm.net.radio.channel import fading_gain_db
from mrcomm.net.radio.links import RadioLinks
from mrcomm.net.relay import RelayOptions, relay_options
from mrcomm.net.signal.trace import RssiTrace
from mrcomm.net.signal_thresholds import EsdParams, esd_warning_dbm
from mrcomm.net.thresholds import Threshold
from mrcomm.ports import LinkSensor
from mrcomm.robot.base import SimBase
from mrcomm.robot.variation import VariationParams, robot_variations
from mrcomm.run.config import RunConfig
from mrcomm.run.resources import ScenarioResources
from mrcomm.seeding import stream
from mrcomm.world.scenario import Scenario


def build_network(config: RunConfig, resources: ScenarioResources | None = None) -> NetworkModel:
    """The run's network model, from its spec and parameters (``resources``: the
    scenario's, for models that need the map)."""
    cls: type[NetworkModel] = config.spec("network").load()
    return cls.build(config.variant_params("network"), resources, config.seed)


def threshold_params(config: RunConfig) -> BaseModel:
    """The threshold's parameters with what depends on the network resolved: ESD's
    warning level, by default what the original's -41 dBm meant on the network its
    pulses measure (:func:`~mrcomm.net.signal_thresholds.esd_warning_dbm`)."""
    params = config.variant_params("threshold")
    if isinstance(params, EsdParams) and params.warning_dbm is None:
        level = esd_warning_dbm(params, config.network, config.variant_params("network"))
        return params.model_copy(update={"warning_dbm": level})
    return params


def build_threshold(
    config: RunConfig, resources: ScenarioResources, ids: Sequence[str]
) -> Threshold:
    """The network-side threshold of the nodes ``ids``, from its spec and parameters."""
    cls: type[Threshold] = config.spec("threshold").load()
    return cls.build(threshold_params(config), resources, ids)


def build_relay_options(config: RunConfig) -> RelayOptions:
    """What the run's bus relays, from its network parameters (``network.relay``)."""
    return relay_options(config.variant_params("network"))


def build_link_sensor(config: RunConfig, resources: ScenarioResources) -> LinkSensor:
    """The link sensor a robot's agent judges its links with (one per robot)."""
    cls: type[Threshold] = config.spec("threshold").load()
    return cls.sensor(threshold_params(config), resources)


def pulse_trace_path(config: RunConfig) -> Path | None:
    """The RSSI trace the pulses of a run replay: the ``trace`` parameter of a
    threshold whose robots measure with a pulse (ESD; None for other thresholds, or
    when the pulses read the radio)."""
    if not config.spec("threshold").pulse:
        return None
    trace: Path | None = getattr(config.variant_params("threshold"), "trace", None)
    return trace


def build_pulse(
    config: RunConfig,
    resources: ScenarioResources,
    sensors: Mapping[str, LinkSensor],
    network: NetworkModel,
) -> TracePulse | RadioPulse | None:
    """A pulse threshold (ESD) in simulation: the pulses that hand each robot's
    measured sensor its readings — replayed from the run's RSSI trace, or measured on
    the radio when there is no trace (None for other thresholds)."""
    if not config.spec("threshold").pulse:
        return None
    measured = {r: s for r, s in sensors.items() if isinstance(s, MeasuredSensor)}
    if measures_radio(config):
        return RadioPulse(network, tuple(measured), tuple(sensors), config.seed, measured)
    path = pulse_trace_path(config)
    assert path is not None
    return TracePulse(resources.rssi_trace(path), measured, tuple(sensors))


def measures_radio(config: RunConfig) -> bool:
    """Whether the run's pulses read the radio (a pulse threshold without a trace; the
    live world then publishes every robot's readings, as :func:`build_pulse`'s pulse
    takes them)."""
    return config.spec("threshold").pulse and pulse_trace_path(config) is None


class RadioPulse:
    """ESD on the radio: each robot's pulse reads, at the pulse rate (2 Hz), the power
    at which each peer's packets reach it — the link's modelled power, plus a fast-fading
    gain per reading when the profile has fading, rounded to the card's 1 dBm. A peer
    out of range gives no reading (the card hears no frame of it), so its last reading
    goes stale as on a real robot."""

    period = 0.5

    def __init__(
        self,
        network: NetworkModel,
        measuring: Sequence[str],
        robots: Sequence[str],
        seed: int,
        sensors: Mapping[str, MeasuredSensor] | None = None,
    ) -> None:
        """``measuring``: the robots whose pulse reads (of their peers among
        ``robots``); ``sensors``: where :meth:`step` hands their readings."""
        profile = getattr(network, "profile", None)
        self.network = network
        self.measuring = frozenset(measuring)
        self.sensors = dict(sensors or {})
        self.robots = tuple(robots)
        self._next = 0.0
        self._fading = profile is not None and profile.fading != "none"
        self._k_db = profile.rician_k_db if profile is not None else None
        self._rngs = {r: stream(seed, "radio", "pulse", r) for r in self.robots}

    def step(self, now: float, links: LinkState) -> None:
        """Hand each robot's sensor its readings when a reading is due."""
        for robot, peer, value in self.readings(now, links):
            self.sensors[robot].update(peer, value, now)

    def readings(self, now: float, links: LinkState) -> list[tuple[str, str, float]]:
        """(robot, peer, dBm) of every reading taken now by the robots with a sensor —
        none until a reading is due. The live world publishes them as each robot's
        pulse would."""
        if now < self._next or links.power is None:
            return []
        self._next = now + self.period
        index = {node: i for i, node in enumerate(links.ids)}
        power, connected = links.power, links.connected
        sight = links.line_of_sight
        out: list[tuple[str, str, float]] = []
        for robot in self.robots:
            if robot not in self.measuring:
                continue
            r = index[robot]
            for peer in self.robots:
                p = index[peer]
                if p == r or not connected[p, r]:
                    continue
                value = float(power[p, r])
                if self._fading:
                    k_db = self._k_db if sight is None or sight[p, r] else None
                    value += fading_gain_db(self._rngs[robot], k_db)
                out.append((robot, peer, float(round(value))))
        return out


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

    def step(self, now: float, links: LinkState | None = None) -> None:
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


def make_bases(
    resources: ScenarioResources, seed: int, variation: VariationParams | None = None
) -> dict[str, SimBase]:
    """Every robot's base at its start pose, each with its own seeded noise stream and
    its share of the run's variation (``config.robot_variation()``; None or profile
    ``none``: the robots of earlier versions)."""
    scenario = resources.scenario
    ids = [r.id for r in scenario.robots]
    varied = robot_variations(variation or VariationParams(), seed, ids, resources.planner)
    return {
        r.id: SimBase(
            r.id,
            scenario.grid,
            resources.planner,
            r.pose,
            resources.robot_params,
            stream(seed, "robot", r.id),
            varied[r.id],
        )
        for r in scenario.robots
    }


def make_links(
    resources: ScenarioResources, config: RunConfig, operator: str | None = None
) -> tuple[LinkModel, LinkRecorder]:
    """The link model of the robots and the task assigner (in that order; then the
    operator when there is one, placed ``operator``: "base" or a robot id) and its
    recorder. A hosted assigner shares its robot's position, so its links are its
    host's (evaluated once; ESD's trace has no row for it: it measures with its host's
    card) and its link to its host is not a link; the same for the operator and where
    it sits."""
    scenario = resources.scenario
    node_ids, aliases = link_nodes(scenario, operator)
    evaluated = tuple(n for n in node_ids if n not in aliases)
    links = LinkModel(
        node_ids,
        scenario.grid,
        build_network(config, resources),
        build_threshold(config, resources, evaluated),
        aliases=aliases,
    )
    skip = {pair for node, host in aliases.items() for pair in ((node, host), (host, node))}
    if OPERATOR_ID in aliases and ASSIGNER_ID in aliases:  # both on the same robot
        skip |= {(OPERATOR_ID, ASSIGNER_ID), (ASSIGNER_ID, OPERATOR_ID)}
    return links, LinkRecorder(node_ids, len(scenario.robots), skip)


def link_nodes(
    scenario: Scenario, operator: str | None = None
) -> tuple[tuple[str, ...], dict[str, str]]:
    """The nodes of the link model in its order (the robots, the task assigner, then
    the operator when ``operator`` places one) and the aliases among them (an assigner
    hosted on a robot shares its position; an operator shares the position of the
    robot it is on, or of the task assigner at "base"; a "virtual" one has none)."""
    host = scenario.assigner.host
    aliases = {ASSIGNER_ID: host} if host else {}
    if operator is None:
        return (*(r.id for r in scenario.robots), ASSIGNER_ID), aliases
    if operator != "virtual":  # virtual: no position, never out of range
        host_of_base = aliases.get(ASSIGNER_ID, ASSIGNER_ID)
        aliases[OPERATOR_ID] = host_of_base if operator == "base" else operator
    return (*(r.id for r in scenario.robots), ASSIGNER_ID, OPERATOR_ID), aliases


def build_radio_links(
    config: RunConfig, resources: ScenarioResources, network: NetworkModel
) -> RadioLinks | None:
    """Live mode: what one process judges its agents' links with, for a network model
    that decides each message from received power (the radio); None for the others."""
    node_ids, aliases = link_nodes(resources.scenario)
    links: RadioLinks | None = network.live_links(resources.scenario.grid, node_ids, aliases)
    return links
