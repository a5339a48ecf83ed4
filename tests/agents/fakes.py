"""A fake base and a fake bus for unit tests of the behaviours' state machines: no
simulator, no network. The test moves the robot, decides how navigation ends and
delivers messages by hand."""

from __future__ import annotations

import math
from typing import Any

from mrcomm.agents.behaviour import AgentContext
from mrcomm.agents.executor import TaskExecutor
from mrcomm.messaging.messages import TOPIC_ASSIGNMENT, TOPIC_POSE, Assignment, Message, PoseMsg
from mrcomm.metrics.timeline import Timeline
from mrcomm.net.link_sensors import NoSensor
from mrcomm.ports import Handler, NavStatus
from mrcomm.world.geometry import Pose
from mrcomm.world.tasks import TaskSpec


class FakeBase:
    """A base that goes where the test says: ``status`` is set by the test."""

    def __init__(self, x: float = 0.0, y: float = 0.0, theta: float = 0.0) -> None:
        self.pose = Pose(x, y, theta)
        self.status = NavStatus.IDLE
        self.goal: tuple[float, float] | None = None
        self.goals: list[tuple[float, float]] = []
        self.cancels = 0
        self.speed = 0.0
        self.odometry_distance = 0.0
        self.route: tuple[tuple[float, float], ...] = ()  # the route driven: untold

    def navigate_to(self, x: float, y: float) -> None:
        self.goal = (x, y)
        self.goals.append((x, y))
        self.status = NavStatus.ACTIVE

    def cancel(self) -> None:
        self.goal = None
        self.cancels += 1
        self.status = NavStatus.IDLE

    def make_plan(self, x: float, y: float) -> tuple[tuple[float, float], ...] | None:
        return ((self.pose.x, self.pose.y), (x, y))

    def arrive(self) -> None:
        """The robot reached its goal."""
        assert self.goal is not None
        self.pose = Pose(self.goal[0], self.goal[1], self.pose.theta)
        self.status = NavStatus.SUCCEEDED


class FakeBus:
    """Records what the agent publishes; the test delivers messages to its handlers."""

    def __init__(self, owner: str) -> None:
        self._owner = owner
        self.handlers: dict[str, list[Handler]] = {}
        self.sent: list[tuple[str, Message]] = []

    @property
    def owner(self) -> str:
        return self._owner

    def publish(self, topic: str, message: Message) -> None:
        self.sent.append((topic, message))

    def subscribe(self, topic: str, handler: Handler) -> None:
        self.handlers.setdefault(topic, []).append(handler)

    def deliver(self, topic: str, message: Message) -> None:
        for handler in self.handlers.get(topic, []):
            handler(message)

    def published(self, topic: str) -> list[Any]:
        return [m for t, m in self.sent if t == topic]


def task(task_id: str, x: float, y: float, **options: Any) -> TaskSpec:
    return TaskSpec(task_id=task_id, type="SENSOR_SWEEP", x=x, y=y, **options)


def pose_of(mate: str, x: float, y: float, theta: float = 0.0, **options: Any) -> PoseMsg:
    """A mate's pose message (sent at 0 s, as its first, unless ``options`` say)."""
    fields: dict[str, Any] = dict(sender=mate, incarnation=1, seq=1, stamp=0.0)
    return PoseMsg(**{**fields, "x": x, "y": y, "theta": theta, **options})


class Harness:
    """One executor on a fake base and bus, with the transitions it takes recorded."""

    def __init__(self, cls: type[TaskExecutor], robot: str = "robot_1", **kwargs: Any) -> None:
        self.base = FakeBase()
        self.bus = FakeBus(robot)
        self.timeline = Timeline(robot)
        self.now = 0.0
        ranks = {f"robot_{i}": float(i - 1) for i in range(1, 10)}  # robot_1 first
        params = kwargs.pop("params", None) or cls.Params()
        context = AgentContext(
            bus=self.bus,
            base=self.base,
            timeline=self.timeline,
            tie_break_rank=ranks.__getitem__,
            link_sensor=kwargs.pop("link_sensor", None) or NoSensor(),
            **kwargs,
        )
        self.agent = cls(context, params)
        self.taken: list[tuple[str, str]] = []
        self._state = self.agent.state
        inner = self.agent._after_state_change

        def record() -> None:
            self.taken.append((self._state, self.agent.state))
            self._state = self.agent.state
            inner()

        self.agent._after_state_change = record  # type: ignore[method-assign]

    def assign(self, tasks: list[TaskSpec], team: tuple[str, ...] = ("robot_1", "robot_2")) -> None:
        self.bus.deliver(
            TOPIC_ASSIGNMENT,
            Assignment(sender="assigner", incarnation=1, seq=1, stamp=self.now,
                       robot=self.bus.owner, tasks=tuple(tasks), team=team),
        )  # fmt: skip

    def hear(self, message: PoseMsg) -> None:
        self.agent.set_time(self.now)
        self.bus.deliver(TOPIC_POSE, message)

    def step(self, dt: float = 0.1, times: int = 1) -> str:
        for _ in range(times):
            self.agent.set_time(self.now)
            self.agent.step(self.now)
            self.now = round(self.now + dt, 9)
        return str(self.agent.state)


def untaken(
    transitions: list[dict[str, Any]], taken: list[tuple[str, str]], prefix: str = ""
) -> list[dict[str, Any]]:
    """The transitions of a table (``prefix``: of a sub-machine) that no taken
    (from, to) pair matches, from any of their sources."""
    out = []
    for t in transitions:
        sources = t["source"] if isinstance(t["source"], list) else [t["source"]]
        dest = prefix + t["dest"]
        if not any(covers(taken, prefix + s, dest) for s in sources):
            out.append(t)
    return out


def covers(taken: list[tuple[str, str]], source: str, dest: str) -> bool:
    """Whether a taken (from, to) pair is the table's (source, dest), where a compound
    source or dest stands for any of its sub-states."""

    def within(state: str, name: str) -> bool:
        return state == name or state.startswith(name + "_")

    return any(within(a, source) and within(b, dest) for a, b in taken)


def distance(a: tuple[float, float], b: tuple[float, float]) -> float:
    return math.hypot(a[0] - b[0], a[1] - b[1])
