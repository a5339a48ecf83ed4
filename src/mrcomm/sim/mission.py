"""One mission in simulation: the lock-step loop (the ``sim`` mode).

Each step of ``dt`` simulated seconds:

1. evaluate every link from the robots' true positions (distance, range, threshold);
2. deliver the messages published during the previous step (receiver-side range cut
   and packet loss happen here);
3. step every agent (assigner, executors);
4. advance every robot's base (navigation and kinematics).

The mission ends when every executor is done and no message is in flight, or at the
time limit. The life cycle (``step``/``done``) is separate from the results, which are
assembled once by :meth:`Mission.result`.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable

from mrcomm.agents.assigner import ASSIGNER_ID
from mrcomm.agents.commands import OPERATOR_ID
from mrcomm.agents.executor import TaskExecutor
from mrcomm.agents.operator import Operator
from mrcomm.metrics.timeline import Timeline
from mrcomm.net.delivery import DeliveryPolicy
from mrcomm.net.inprocess import InProcessNetwork
from mrcomm.net.links import LinkState
from mrcomm.net.relay import make_relay
from mrcomm.run.agents import AgentAssembly
from mrcomm.run.assemble import AonAgentFacts, RunFacts, assemble
from mrcomm.run.bodies import RobotBodies
from mrcomm.run.config import RunConfig
from mrcomm.run.operator_plan import OperatorPlan, ScriptedOperator
from mrcomm.run.proximity import make_proximity
from mrcomm.run.resources import ScenarioResources
from mrcomm.run.result import MissionResult
from mrcomm.run.trajectory import Trajectory
from mrcomm.run.wiring import (
    build_pulse,
    build_relay_options,
    link_nodes,
    make_bases,
    make_links,
)


class Mission:
    """A mission being simulated; drive it with :meth:`run` or :meth:`step`."""

    def __init__(
        self,
        config: RunConfig,
        resources: ScenarioResources | None = None,
        operator: OperatorPlan | None = None,
    ) -> None:
        """``operator``: an operator in the loop, sending the plan's commands (None:
        no operator, as in every run before it existed)."""
        self.config = config
        self.resources = resources or ScenarioResources.load(config.scenario)
        scenario = self.resources.scenario
        self.robot_ids = tuple(r.id for r in scenario.robots)
        placement = operator.placement if operator is not None else None
        self.node_ids = link_nodes(scenario, placement)[0]
        seed = config.seed
        self.links, self.link_recorder = make_links(self.resources, config, placement)
        self.proximity = make_proximity(config, self.robot_ids)
        self.agents = agents = AgentAssembly(config, self.resources)
        self.network = InProcessNetwork(
            self.node_ids,
            policy=DeliveryPolicy(config.spl),
            loss_rngs=agents.loss_streams(self.node_ids),
            channel=self.links.network.channel(self.node_ids),
            relay=make_relay(self.node_ids, len(scenario.robots), build_relay_options(config)),
        )
        self.bodies = RobotBodies(
            make_bases(self.resources, seed, config.robot_variation()), scenario.assigner
        )
        self.bases = self.bodies.bases
        self.timelines = {rid: Timeline(rid) for rid in self.robot_ids}
        self.sensors = {rid: agents.link_sensor() for rid in self.robot_ids}
        self.pulse = build_pulse(config, self.resources, self.sensors, self.links.network)
        self.executors: dict[str, TaskExecutor] = {
            rid: agents.executor(
                self.network.endpoint(rid),
                self.bases[rid],
                self.timelines[rid],
                link_sensor=self.sensors[rid],
            )
            for rid in self.robot_ids
        }
        self.assigner = agents.assigner(self.network.endpoint(ASSIGNER_ID))
        self.operator: Operator | None = None
        self.script: ScriptedOperator | None = None
        if operator is not None:
            self.operator = agents.operator(self.network.endpoint(OPERATOR_ID))
            self.script = ScriptedOperator(self.operator, operator)
        self.trajectories = {rid: Trajectory() for rid in self.robot_ids}
        self.now = 0.0
        self.steps = 0
        self.finished = False
        self.last_links: LinkState | None = None
        self._wall = 0.0

    # -- life cycle ------------------------------------------------------------------
    @property
    def done(self) -> bool:
        return self.finished or self.now >= self.config.max_time - 1e-9

    def run(self, progress: Callable[[Mission], None] | None = None) -> MissionResult:
        """Step to the end; ``progress(self)`` after every step when given (it only
        reads: a mission's result is the same with or without it)."""
        start = time.perf_counter()
        while not self.done:
            self.step()
            if progress is not None:
                progress(self)
        self._wall = time.perf_counter() - start
        return self.result()

    def step(self) -> None:
        now = self.now
        dt = self.config.dt
        truth = self.bodies.true_xy()
        positions = self.bodies.node_positions(truth)
        if self.operator is not None:
            positions.append((math.nan, math.nan))  # it shares its host's position
        links = self.links.update(positions, now)
        self.last_links = links
        self.network.set_connected(links.connected)
        if self.network.channel is not None and links.power is not None:
            self.network.channel.set_links(links.power, links.line_of_sight)
        self.assigner.set_time(now)
        if self.operator is not None:
            self.operator.set_time(now)
        for executor in self.executors.values():
            executor.set_time(now)
        self.network.deliver(now)
        if self.pulse is not None:
            self.pulse.step(now, links)
        self.assigner.step(now)
        if self.operator is not None and self.script is not None:
            self.script.step(now)
            self.operator.step(now)
        for executor in self.executors.values():
            executor.step(now)
        # Bases have not moved since `truth` was taken: it is each one's view of the others.
        self.bodies.advance(dt, now, truth)
        self.link_recorder.record(links, dt, now)
        if self.proximity is not None:
            self.proximity.record(links.distance, now)
        if self.bodies.sample_due(now):
            self._sample_trajectories(now)
        self.steps += 1
        self.now = round(now + dt, 9)
        if (
            all(e.done for e in self.executors.values())
            and self.assigner.settled
            and self.network.awaited() == 0
            and self._operator_settled()
        ):
            self.finished = True

    def _operator_settled(self) -> bool:
        """No operator, or every command of its plan sent and finished."""
        if self.operator is None or self.script is None:
            return True
        return self.script.done and self.operator.settled

    # -- per-step bookkeeping ------------------------------------------------------------
    def _sample_trajectories(self, now: float) -> None:
        t = round(now, 3)
        for rid, (x, y) in self.bodies.sample().items():
            self.trajectories[rid].append((t, x, y))

    # -- results -------------------------------------------------------------------------
    def result(self) -> MissionResult:
        end = self.now
        self._sample_trajectories(end)
        for tl in self.timelines.values():
            tl.close_all(end)
        endpoints = {rid: getattr(e, "aon", None) for rid, e in self.executors.items()}
        endpoints[ASSIGNER_ID] = self.assigner.aon
        aon = {
            agent: AonAgentFacts(
                counters=endpoint.stats.counters(),
                pending=len(endpoint.pending_ids()),
                finish_times=list(endpoint.stats.finish_times.values()),
            )
            for agent, endpoint in endpoints.items()
            if endpoint is not None
        }
        result = assemble(
            RunFacts(
                config=self.config,
                scenario=self.resources.scenario,
                end_time=end,
                finished=self.finished,
                wall_time_s=self._wall,
                timelines=self.timelines,
                agenda=self.assigner.agenda,
                received=set(self.assigner.success_received),
                robots=self.bodies.truth(self.link_recorder),
                counts_by_agent=self.network.counts_by_agent(),
                aon=aon,
                links=self.link_recorder.summaries(),
                connectivity=self.link_recorder.connectivity(),
                relay=self.network.relay.stats() if self.network.relay is not None else {},
                trajectories=self.trajectories,
                rssi_series=list(self.link_recorder.rssi_series),
                link_states=self.link_recorder.state_intervals(end),
                encounters=self.proximity.encounters(end) if self.proximity else None,
            )
        )
        if self.operator is not None:
            confirmed = sorted({task for task, _ in self.assigner.confirmed})
            result.operator = {**self.operator.summary(), "confirmed": confirmed}
        return result


def run_mission(
    config: RunConfig,
    resources: ScenarioResources | None = None,
    operator: OperatorPlan | None = None,
    progress: Callable[[Mission], None] | None = None,
) -> MissionResult:
    """Simulate one mission to its end and return its results (``progress``: see
    :meth:`Mission.run`)."""
    return Mission(config, resources, operator).run(progress)
