"""The agent process of live mode (``mrcomm agent --robot ID``; issue 7 §2).

One robot's task executor — the same class as in simulation — and, when the scenario
hosts the task assigner on this robot, the assigner too (``--robot assigner`` runs a
base-station or virtual assigner on its own). The process:

1. opens its Zenoh peer session and subscribes (agent topics, the world's clock tick,
   resynchronisation, liveliness; with ESD, its own pulse's readings
   ``<robot>-pulse/rssi``, which feed the robot's measured-signal sensor);
2. joins: waits until the world is reachable (else a one-line error, exit 2), refuses
   an id another live process already holds, declares its liveliness tokens and
   reports *ready* once it sees every team member;
3. runs on the shared clock: Zenoh callbacks only queue; on this one thread, every
   queued message is dispatched (receiver-side perturbations, then the agents'
   handlers) and every clock tick updates the base state and steps the agents (with
   ``--clock host``, ``live.host_clock`` steps them on the host's clock instead);
4. records its own data as it goes (``live.journal``) and stops when the world
   announces the end of the mission (or on SIGTERM / SIGINT).

A robot that joins late (restart after a crash) resynchronises with the team first
(``live.resync``). Losing every peer does not stop the process: Zenoh reconnects by
itself and the agents carry on when the clock comes back; a process back from being
stopped reopens its team session and catches up (``live.away``). Mates whose token
vanished or that fell silent are gone for the behaviour (``live.mates``).
"""

from __future__ import annotations

import time
from typing import Any

from mrcomm.agents.assigner import ASSIGNER_ID, TaskAssigner
from mrcomm.agents.commands import OPERATOR_ID
from mrcomm.agents.executor import TaskExecutor
from mrcomm.errors import InputError, did_you_mean
from mrcomm.live.away import AwayWatch
from mrcomm.live.journal import (
    Journal,
    TimelineTail,
    journal_path,
    track_presence,
)
from mrcomm.live.mates import MateWatch
from mrcomm.live.operator_host import OperatorHost, place_operator
from mrcomm.live.protocol import (
    CH_AGENT_STATE,
    CH_BASE_CMD,
    CH_ROSTER,
    CH_SYNC_REPLY,
    CH_SYNC_REQUEST,
    CH_TICK,
    WORLD_ID,
    AgentState,
    BaseCommand,
    SyncReply,
    SyncRequest,
    Tick,
    decoder_of,
    encoder,
    roster_of,
)
from mrcomm.live.recorder import AgentRecorder
from mrcomm.live.resync import Resync, reply_for
from mrcomm.live.robot_base import AgentBase, open_base
from mrcomm.live.settings import LiveSettings, config_crc, mission_bytes
from mrcomm.live.stop_signals import Stopped, stop_on_signals
from mrcomm.live.tick_guard import IMPLAUSIBLE_TICK, TickGuard, tick_limit
from mrcomm.messaging.messages import TOPIC_RSSI, RssiMsg, decode
from mrcomm.messaging.topics import Lane
from mrcomm.metrics import labels as L
from mrcomm.metrics.timeline import Timeline
from mrcomm.net.link_sensors import MeasuredSensor
from mrcomm.net.origin_signatures import OriginSigner
from mrcomm.net.pulse import pulse_id
from mrcomm.net.zenoh_bus import LinkRules, PositionBook, ZenohBus
from mrcomm.net.zenoh_config import check_key_chunk
from mrcomm.net.zenoh_node import NO_MISSION, Incoming, Presence, ZenohNode, drain
from mrcomm.run.agents import AgentAssembly, AgentOverrides
from mrcomm.run.resources import ScenarioResources
from mrcomm.run.wiring import (
    build_network,
    build_radio_links,
    build_relay_options,
    measures_radio,
)
from mrcomm.world.scenario import Scenario

HEARTBEAT_PERIOD = 0.25  # wall s between heartbeats (and at once on a change)
SNAPSHOT_PERIOD = 1.0  # simulated s between counts / clock snapshots in the journal
ASSIGNMENT_WAIT = 3.0  # simulated s without an assignment before asking for it
SYNC_WAIT = 2.0  # simulated s a (re)joining robot waits for the team's answers
LATE_JOIN = 1.0  # a first tick later than this (simulated s) means a late join
_CH_PULSE = "pulse"  # inbox channel of this robot's own pulse readings


def team_processes(scenario: Scenario) -> tuple[str, ...]:
    """Agent ids that must be present for the team to be complete."""
    return (*(r.id for r in scenario.robots), ASSIGNER_ID)


def check_agent_id(scenario: Scenario, agent: str) -> None:
    """The id must be a robot of the scenario (or the stand-alone assigner)."""
    check_key_chunk(agent, "--robot")
    if agent == OPERATOR_ID:
        return
    robots = [r.id for r in scenario.robots]
    spec = scenario.assigner
    if agent == ASSIGNER_ID:
        if spec.kind == "robot":
            raise InputError(
                f"the task assigner runs on {spec.host} in this scenario "
                f"(assigner.host): start '--robot {spec.host}' instead",
                field="--robot",
            )
        return
    if agent not in robots:
        raise InputError(
            f"robot {agent!r} is not in scenario {scenario.name}{did_you_mean(agent, robots)}; "
            f"robots: {', '.join(robots)}",
            field="--robot",
        )


class AgentProcess:
    """One live agent process (see the module docstring)."""

    def __init__(self, settings: LiveSettings, agent: str, incarnation: int) -> None:
        self.settings = settings
        run = settings.run
        self.resources = ScenarioResources.load(run.scenario)
        self.scenario = self.resources.scenario
        check_agent_id(self.scenario, agent)
        self.agent = agent
        self.incarnation = incarnation
        self.robot_ids = tuple(r.id for r in self.scenario.robots)
        spec = self.scenario.assigner
        hosts_assigner = agent == ASSIGNER_ID or spec.host == agent
        self.hosted = ((agent,) if agent != ASSIGNER_ID else ()) + (
            (ASSIGNER_ID,) if hosts_assigner else ()
        )
        self.node = ZenohNode(settings.zenoh)
        # The world (clock, base) on its own session when configured, sharing the inbox.
        self.infra = (
            ZenohNode(settings.world, inbox=self.node.inbox)
            if settings.world is not None
            else self.node
        )
        self._enc = encoder()
        if settings.mission is not None:  # else adopted from the world's first tick
            self.node.mission = self.infra.mission = mission_bytes(settings.mission)
        positions = PositionBook()
        if spec.kind == "robot" and spec.host is not None:
            positions.aliases[ASSIGNER_ID] = spec.host
        elif spec.kind == "base_station" and spec.position is not None:
            positions.fixed[ASSIGNER_ID] = (spec.position[0], spec.position[1])
        place_operator(positions, self.scenario)
        network = build_network(run, self.resources)
        radio = build_radio_links(run, self.resources, network)
        hops = build_relay_options(run).hops
        rules = LinkRules(network=network, loss_percent=run.spl, radio=radio, relay_hops=hops)
        self.bus = ZenohBus(
            self.node,
            LinkRules(relay_hops=hops) if settings.emulated else rules,  # the kernel drops
            positions,
            members=frozenset((*self.robot_ids, ASSIGNER_ID, OPERATOR_ID)),
            robots=self.robot_ids,
            signer=OriginSigner.from_options(settings.zenoh),  # None: --insecure
        )
        self.journal = Journal(journal_path(settings.record_dir, agent, incarnation))
        self.agents = agents = AgentAssembly(
            run, self.resources, AgentOverrides(aon_lease=settings.lease)
        )
        self.executor: TaskExecutor | None = None
        self.base: AgentBase | None = None
        self.tail: TimelineTail | None = None
        self.resync: Resync | None = None
        #: ESD: the sensor this robot's pulse readings feed, and how many it took.
        self.measured: MeasuredSensor | None = None
        self.pulse_readings = 0
        self.operator: OperatorHost | None = None
        if agent == OPERATOR_ID:
            self.operator = OperatorHost(self.bus, agents, incarnation, settings.operator)
        elif agent != ASSIGNER_ID:
            start = next(r.pose for r in self.scenario.robots if r.id == agent)
            self.base = open_base(
                settings.base, agent, incarnation, start, self._send_command,
                self.resources.planner,
            )  # fmt: skip
            base = self.base
            positions.own[agent] = lambda: (base.pose.x, base.pose.y)
            endpoint = self.bus.endpoint(agent, agents.loss_stream(agent))
            timeline = Timeline(agent)
            sensor = agents.link_sensor()
            if isinstance(sensor, MeasuredSensor):
                self.measured = sensor
            self.executor = agents.executor(
                endpoint, self.base, timeline, link_sensor=sensor, incarnation=incarnation
            )
            self.tail = TimelineTail(timeline, self.journal)
            self.resync = Resync(self.executor, endpoint, self._request_sync, wait=SYNC_WAIT)
        self.assigner: TaskAssigner | None = None
        if hosts_assigner:
            endpoint = self.bus.endpoint(ASSIGNER_ID, agents.loss_stream(ASSIGNER_ID))
            self.assigner = agents.assigner(endpoint, incarnation=incarnation)
        self.recorder = AgentRecorder(self.journal, self.bus, agent, self.executor, self.assigner)
        self.bus.observer = self.recorder.delivery
        self.team = team_processes(self.scenario)
        self.present: dict[str, set[int]] = {}
        self.now = 0.0
        self.tick_time = 0.0  # the latest clock tick's (the base state's) time
        self.tick_guard = TickGuard(limit=tick_limit(run.max_time, run.dt))
        #: Robot mates gone: token vanished, or silent past the link lease (live.mates).
        self.mates = MateWatch((r for r in self.robot_ids if r != agent), settings.zenoh.link_lease)
        self.away = AwayWatch(settings.zenoh.link_lease)
        self.first_tick: float | None = None
        self.ended = False
        self._ready = False
        self._last_beat = -1e9
        self._last_done: tuple[bool, bool] | None = None
        self._next_snapshot = 0.0
        self._crc = config_crc(run)
        self.max_lag = 0.0

    # -- life cycle --------------------------------------------------------------------
    def run(self) -> int:
        with stop_on_signals():
            try:
                self._subscribe()
                self._join()
                self._loop()
            except Stopped:
                self.journal.write("stopped", time=self.now, wall=time.time())
            finally:
                self._finish()
        return 0

    def _subscribe(self) -> None:
        for key, node in (
            (CH_AGENT_STATE, self.infra),
            (CH_BASE_CMD, self.infra),
            (CH_SYNC_REQUEST, self.node),
            (CH_SYNC_REPLY, self.node),
        ):
            node.prepare(node.key(self.agent, key), Lane.CONTROL)
        prefix = self.node.prefix
        self.infra.listen(f"{prefix}/{WORLD_ID}/{CH_TICK}", CH_TICK, decoder_of(Tick))
        self.node.listen(f"{prefix}/*/{CH_SYNC_REQUEST}", CH_SYNC_REQUEST, decoder_of(SyncRequest))
        self.node.listen(f"{prefix}/*/{CH_SYNC_REPLY}", CH_SYNC_REPLY, decoder_of(SyncReply))
        if self.measured is not None:
            # Only this robot's own pulse: readings measured BY this robot, of its peers;
            # published by the world when it measures the modelled radio for the robots.
            key = f"{prefix}/{pulse_id(self.agent)}/{TOPIC_RSSI}"
            pulse_node = self.infra if measures_radio(self.settings.run) else self.node
            pulse_node.listen(key, _CH_PULSE, decode)
        self.node.watch_presence()
        if self.infra is not self.node:
            self.infra.watch_presence(WORLD_ID)

    def _join(self) -> None:
        """Reach the world, refuse a duplicate id, declare our tokens."""
        deadline = time.monotonic() + self.settings.join_timeout
        while WORLD_ID not in self.present or not self.present[WORLD_ID]:
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                world = self.settings.world or self.settings.zenoh
                where = ", ".join(world.connect) or "multicast scouting"
                raise InputError(
                    f"no team reachable within {self.settings.join_timeout:g} s "
                    f"(no world process seen via {where})",
                    field="--world-connect" if self.settings.world else "--connect",
                )
            item = self.node.poll(min(remaining, 0.2))
            if item is not None and item.channel == "presence":
                self._on_presence(item.value)
        self._wait_for_base(deadline)
        # Our own query sees only the peers we are linked to yet (Zenoh peers learn of
        # each other by gossip and do not forward tokens); the world sees everyone.
        seen = roster_of(self.infra.ask(self.infra.key(WORLD_ID, CH_ROSTER)))
        for agent in self.hosted:
            others = sorted({*self.node.present(agent), *seen.get(agent, ())} - {self.incarnation})
            if others:
                raise InputError(
                    f"{agent!r} is already running (incarnation {others[0]}): two agents "
                    "cannot claim the same id (a process that died out of reach is "
                    f"present until its link lease, {self.node.options.link_lease:g} s, ends)",
                    field="--robot",
                )
        self.journal.start(
            process=self.agent,
            incarnation=self.incarnation,
            hosted=list(self.hosted),
            behaviour=self.settings.run.behaviour,
        )
        for agent in self.hosted:
            self.node.declare_alive(agent, self.incarnation)
            if self.infra is not self.node:
                self.infra.declare_alive(agent, self.incarnation)  # for the world

    def _wait_for_base(self, deadline: float) -> None:
        """A robot's own base (Nav2) must be up before the agent joins the team."""
        while self.base is not None and (missing := self.base.waiting_for()) is not None:
            if time.monotonic() > deadline:
                message = f"robot not ready within {self.settings.join_timeout:g} s: {missing}"
                raise InputError(message, field="--base")
            item = self.node.poll(0.05)  # as while joining: only presence matters yet
            if item is not None and item.channel == "presence":
                self._on_presence(item.value)

    def _loop(self) -> None:
        while not self.ended:
            self._heartbeat()
            drain(self.node.poll, self._handle, HEARTBEAT_PERIOD / 2)
            self.journal.flush()

    def _handle(self, item: Incoming) -> bool:
        """Handle one item; True once the mission has ended."""
        self._on_item(item)
        return self.ended

    def _on_item(self, item: Incoming) -> None:
        channel = item.channel
        if channel == "bus":
            self.bus.handle(item)
        elif channel == CH_TICK:
            self._on_tick(item)
        elif channel == "presence":
            self._on_presence(item.value)
        elif channel == CH_SYNC_REQUEST:
            self._on_sync_request(item.value)
        elif channel == CH_SYNC_REPLY and self.resync is not None:
            learnt = self.resync.on_reply(item.value, self.now)
            if learnt:
                self.journal.write("caught_up", time=self.now, learnt=learnt)
        elif channel == _CH_PULSE:
            self._on_pulse(item.value)

    def _on_pulse(self, message: object) -> None:
        """ESD: a reading of this robot's pulse feeds its measured-signal sensor. It is
        dated on the agent's own clock (the shared clock) when it arrives, so its age is
        judged as in simulation: stale 5 s after the pulse stopped reporting that peer.
        The pulse is local to the robot: no emulated network between them."""
        if (
            self.measured is None
            or not isinstance(message, RssiMsg)
            or message.robot != self.agent
            or message.peer == self.agent
        ):
            return
        self.measured.update(message.peer, message.rssi, self.now)
        self.pulse_readings += 1

    # -- the clock -----------------------------------------------------------------------
    def _on_tick(self, item: Incoming) -> None:
        tick = self._take_tick(item)
        if tick is None:
            return
        self.now = now = tick.time
        self.bus.release(now)  # also the messages still on the radio that are now due
        if tick.end:
            self._end(tick.end_time, tick.timed_out)
            return
        if self.first_tick is None:
            self._first_tick(now)
        self._step(now)
        if now >= self._next_snapshot:
            self._next_snapshot = now + SNAPSHOT_PERIOD
            self._snapshot(wall=item.recv_wall, sent_wall=item.sent_wall)
        self.journal.flush()

    def _take_tick(self, item: Incoming) -> Tick | None:
        """Take a tick's state of this robot's base; None for a stale tick."""
        tick: Tick = item.value
        if not self.tick_guard.plausible(tick, time.monotonic()):
            self.node.refuse(IMPLAUSIBLE_TICK)  # counted with the bus edge's refusals
            return None
        if self.node.mission == NO_MISSION and len(tick.mission) == len(NO_MISSION):
            self.node.mission = self.infra.mission = tick.mission  # this world's mission
        if tick.mission != self.node.mission:
            self.node.refuse("other_mission")  # the clock of another run's world
            return None
        if tick.time < self.tick_time:
            return None  # a stale tick overtaken by a newer one
        if item.sent_wall is not None:
            self.max_lag = max(self.max_lag, time.time() - item.sent_wall)
        self._notice_away(tick.time)
        self.tick_time = tick.time
        mine = next((state for state in tick.states if state.robot == self.agent), None)
        if self.base is not None:
            self.base.take(mine)
        return tick

    def _notice_away(self, now: float) -> None:
        """After a silence between ticks longer than the link lease (``live.away``),
        the executor reports again what it completed and, without AON (which re-sends
        by itself), asks the team what it completed meanwhile."""
        wall = time.monotonic()
        gap = self.away.tick(wall)
        if gap is not None:
            self.journal.write("away", time=now, wall_s=round(gap, 3))
        if self.away.due(wall) and self.executor is not None:
            self.executor.rejoined()
            if self.resync is not None and not self.executor.uses_aon:
                self.resync.catch_up(now)

    def _first_tick(self, now: float) -> None:
        self.first_tick = now
        self.journal.write("first_tick", time=now, wall=time.time())
        if now > LATE_JOIN and self.resync is not None:
            self.resync.start(now)  # joined a running mission: catch up first

    def _step(self, now: float) -> None:
        self.mates.step(time.monotonic(), self.bus.samples)
        self._judge_mates()
        alive = self._alive()  # nothing below changes who is present or silent
        if self.resync is not None and self.executor is not None:
            processes = {self._process_of(a) for a in alive}
            processes.discard(self.agent)
            if self.resync.step(now, processes):
                self.journal.write("resync", time=now, skipped=self.resync.skipped)
            elif (
                not self.resync.active
                and not self.resync.applied
                and self.executor.timeline.first(L.ASSIGNMENT_RECEIVED) is None
                and self.first_tick is not None
                and now - self.first_tick >= ASSIGNMENT_WAIT
            ):
                self.resync.start(now)  # missed the assignment: ask for it
        self._heard_from_present(now, alive)
        if self.assigner is not None:
            self.assigner.step(now)
            self.recorder.receipts()
        if self.executor is not None:
            self.executor.step(now)
            absent = [a for a in self.team if a != self.agent and a not in alive]
            self.recorder.left_out(now, sorted(absent))
        if self.operator is not None:
            self.operator.step(now)
        if self.tail is not None:
            self.tail.flush(now)

    def _end(self, end: float, timed_out: bool) -> None:
        if self.executor is not None:
            self.executor.timeline.close_all(end)
            assert self.tail is not None
            self.tail.flush(end)
        if self.operator is not None:
            self.operator.journal(self.journal, end)
        self.journal.write("end", time=end, timed_out=timed_out, wall=time.time())
        self.ended = True

    # -- team ----------------------------------------------------------------------------
    def _process_of(self, agent: str) -> str:
        """The process that hosts ``agent`` (the assigner may live on a robot)."""
        host = self.scenario.assigner.host
        return host if agent == ASSIGNER_ID and host is not None else agent

    def _on_presence(self, presence: Presence) -> None:
        track_presence(self.present, presence, self.journal, self.now)
        self._judge_mates()

    def _judge_mates(self) -> None:
        """A mate's process has gone (its token vanished: SIGKILL, a crash, a lost link
        past the lease; or silent past the lease: hung) or is back: the behaviour decides
        what that means for the team."""
        for mate, alive in self.mates.changes(self.present):
            silent = mate in self.mates.silent
            self.journal.write("mate", time=self.now, agent=mate, alive=alive, silent=silent)
            if self.executor is not None:
                self.executor.mate_presence(mate, alive)

    def _alive(self) -> set[str]:
        """Team members whose token is present and whose process is not silent."""
        silent = self.mates.silent
        return {
            a
            for a, incs in self.present.items()
            if incs and a in self.team and self._process_of(a) not in silent
        }

    def _heard_from_present(self, now: float, alive: set[str]) -> None:
        """A member whose liveliness token is present (and whose process is not silent:
        ``alive``) is alive for the AON lease (the assigner publishes no poses; a crashed
        robot's token vanishes with its session), so only a member that has really gone
        is ever left out."""
        for aon in self.recorder.aon_endpoints().values():
            for agent in alive:
                aon.heard_from(agent, now)

    def _heartbeat(self) -> None:
        stood = self.away.loop(time.monotonic())
        if stood is not None:  # this process did not run: its team session is stale
            reopened = self.node.reopen()
            self.journal.write("reopened", time=self.now, wall_s=round(stood, 3), ok=reopened)
        ready = all(self.present.get(a) for a in (*self.team, WORLD_ID))
        done = self.executor.done if self.executor is not None else True
        settled = self.assigner.settled if self.assigner is not None else True
        if self.operator is not None:
            done, settled = self.operator.done, self.operator.settled
        wall = time.monotonic()
        changed = (done, settled) != self._last_done or ready != self._ready
        if not changed and wall - self._last_beat < HEARTBEAT_PERIOD:
            return
        self._ready = ready
        self._last_done = (done, settled)
        self._last_beat = wall
        state = AgentState(
            agent=self.agent,
            incarnation=self.incarnation,
            ready=ready,
            done=done,
            hosted=self.hosted,
            settled=settled,
            time=self.now,
            config_crc=self._crc,
        )
        self.infra.put(
            self.infra.key(self.agent, CH_AGENT_STATE), self._enc.encode(state), Lane.CONTROL
        )

    def _send_command(self, command: BaseCommand) -> None:
        self.infra.put(
            self.infra.key(self.agent, CH_BASE_CMD), self._enc.encode(command), Lane.CONTROL
        )

    def _request_sync(self) -> None:
        self.journal.write("sync_request", time=self.now)
        request = SyncRequest(self.agent, self.incarnation)
        self.node.put(
            self.node.key(self.agent, CH_SYNC_REQUEST), self._enc.encode(request), Lane.CONTROL
        )

    def _on_sync_request(self, request: SyncRequest) -> None:
        if request.robot == self.agent:
            return
        reply = reply_for(request, self.agent, self.executor, self.assigner, self.now)
        self.node.put(
            self.node.key(self.agent, CH_SYNC_REPLY), self._enc.encode(reply), Lane.CONTROL
        )

    # -- recording -----------------------------------------------------------------------
    def _snapshot(self, **clock: Any) -> None:  # wall: when our clock read self.now
        self.journal.write("clock", sim=self.now, **clock, lag=round(self.max_lag, 6))
        self.recorder.counts()
        self._record_pulse()

    def _record_pulse(self) -> None:
        """ESD: how many pulse readings arrived so far, and the latest of each peer."""
        if self.measured is not None:
            latest = {p: [rssi, t] for p, (rssi, t) in sorted(self.measured.latest.items())}
            self.journal.write("pulse", time=self.now, readings=self.pulse_readings, latest=latest)

    def _finish(self) -> None:
        if self.base is not None:
            self.base.close()
        self.recorder.final(self.max_lag)
        self._record_pulse()
        self.journal.close()
        if self.infra is not self.node:
            self.infra.close()
        self.node.close()
