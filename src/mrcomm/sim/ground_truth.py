"""What the simulation and the live world both build from a run configuration: every
robot's simulated base, and the network-side link model with its recorder (the links'
ground truth). One place, so that a live run's ground truth is computed exactly as a
simulated run's."""

from __future__ import annotations

from mrcomm.agents.assigner import ASSIGNER_ID
from mrcomm.net.links import LinkModel, LinkRecorder
from mrcomm.robot.base import SimBase
from mrcomm.seeding import stream
from mrcomm.sim.config import RunConfig
from mrcomm.sim.signals import build_threshold
from mrcomm.sim.world import SimWorld


def make_bases(world: SimWorld, seed: int) -> dict[str, SimBase]:
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


def make_links(world: SimWorld, config: RunConfig) -> tuple[LinkModel, LinkRecorder]:
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
