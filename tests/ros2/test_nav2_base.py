"""The agent's side (``ros2.nav2_base.Nav2Base``): the Base port's rules on a Nav2
robot (the world's, served over ROS 2) — status ACTIVE from ``navigate_to`` until the
goal's result, never the previous goal's SUCCEEDED; IDLE after ``cancel`` whatever the
cancelled goal reports; ABORTED when the goal is unreachable or rejected; the pose,
odometer and speed as the robot's base reports them."""

from __future__ import annotations

import math
import time
from collections.abc import Iterator

import pytest

from mrcomm.ports import NavStatus

from .helpers import SteppedWorld, fresh_domain, needs_ros2

pytestmark = needs_ros2


class Agent:
    """A Nav2Base for robot_1, synchronised with the stepped world: after each step it
    waits until that step's pose and odometry have arrived, then takes them (as an agent
    step does). They are two topics, and DDS does not order one against the other."""

    def __init__(self, world: SteppedWorld, domain: int, frame: str = "map") -> None:
        from mrcomm.ros2.nav2_base import Nav2Base
        from mrcomm.ros2.runtime import Nav2Names

        self.world = world
        start = world.bases["robot_1"].pose
        names = Nav2Names.of("robot_1", frame=frame)
        self.base = Nav2Base.open("robot_1", start, names, world.resources.planner, domain)

    def spin(self) -> None:
        base, now = self.base, self.world.now - 1e-6
        deadline = time.monotonic() + 2.0
        while (base.pose_stamp < now or base.odom_stamp < now) and (time.monotonic() < deadline):
            time.sleep(0.001)  # the ROS thread delivers; polled with a deadline
        base.sync()

    def drive(self, until: NavStatus | None = None, steps: int = 600) -> int:
        def done() -> bool:
            return until is not None and self.base.status is until

        return self.world.run_until(done, steps, self.spin, f"status {until}")


@pytest.fixture
def agent() -> Iterator[Agent]:
    domain = fresh_domain()
    world = SteppedWorld(domain)
    agent = Agent(world, domain)
    try:
        world.run_until(lambda: agent.base.waiting_for() is None, 500, agent.spin, "robot ready")
        yield agent
    finally:
        agent.base.close()
        world.close()


def test_goal_reached(agent: Agent) -> None:
    base, sim = agent.base, agent.world.bases["robot_1"]
    start = sim.pose
    assert base.status is NavStatus.IDLE
    base.navigate_to(start.x + 2.0, start.y)
    assert base.status is NavStatus.ACTIVE  # at once, before any answer
    agent.drive(NavStatus.SUCCEEDED)
    assert base.pose.distance_to(start.x + 2.0, start.y) < 0.3
    assert base.odometry_distance == pytest.approx(sim.odometry_distance, rel=1e-6)
    assert base.odometry_distance > 1.9
    # A new goal: ACTIVE again, never the previous goal's SUCCEEDED.
    base.navigate_to(start.x, start.y)
    for _ in range(5):
        assert base.status is NavStatus.ACTIVE
        agent.world.step()
        agent.spin()
    assert base.speed == pytest.approx(sim.speed, abs=1e-9)


def test_cancel_is_idle_at_once(agent: Agent) -> None:
    base, sim = agent.base, agent.world.bases["robot_1"]
    start = sim.pose
    base.navigate_to(start.x + 6.0, start.y)
    agent.world.run_until(lambda: sim.speed > 0.2, 300, agent.spin, "driving")
    base.cancel()
    assert base.status is NavStatus.IDLE
    agent.world.run_until(
        lambda: agent.world.server.outcomes.get("canceled"), 300, agent.spin, "cancelled"
    )
    for _ in range(10):
        agent.world.step()
        agent.spin()
        assert base.status is NavStatus.IDLE
    assert sim.status is NavStatus.IDLE


def test_cancel_before_the_goal_is_accepted(agent: Agent) -> None:
    base, sim = agent.base, agent.world.bases["robot_1"]
    start = sim.pose
    base.navigate_to(start.x + 6.0, start.y)
    base.cancel()  # the goal is still on its way
    agent.world.run_until(
        lambda: agent.world.server.outcomes.get("canceled"), 300, agent.spin, "cancelled"
    )
    assert base.status is NavStatus.IDLE
    assert sim.status is NavStatus.IDLE


def test_route_is_the_reported_plan_ahead_of_the_robot(agent: Agent) -> None:
    base, sim = agent.base, agent.world.bases["robot_1"]
    assert base.route == ()
    base.navigate_to(22.2, 13.8)  # to the conference room: seven corners on the way
    agent.world.run_until(lambda: len(base.route) > 0, 300, agent.spin, "a plan")
    first = base.route
    # The server's plan is the simulated base's route from its pose: the agent has it
    # from the segment the robot is on, the goal last.
    assert first[-1] == sim.goal and first == sim.path[len(sim.path) - len(first) :]
    agent.world.run_until(lambda: sim.pose.distance_to(*first[0]) < 0.3, 300, agent.spin, "")
    for _ in range(25):  # a plan published since, from further on
        agent.world.step()
        agent.spin()
    later = base.route
    assert later[-1] == sim.goal and len(later) < len(first)
    base.cancel()
    assert base.route == ()  # no goal, no route
    for _ in range(15):  # plans of the cancelled goal still arriving change nothing
        agent.world.step()
        agent.spin()
        assert base.route == ()


def test_unreachable_goal_aborts(agent: Agent) -> None:
    agent.base.navigate_to(-100.0, -100.0)
    # Steps follow pose messages, not the goal's round trip over DDS: allow as many as
    # for a rejected goal (50 were too few once, on a fresh domain of a busy machine).
    agent.drive(NavStatus.ABORTED, steps=300)


def test_rejected_goal_aborts() -> None:
    domain = fresh_domain()
    world = SteppedWorld(domain)
    agent = Agent(world, domain, frame="odom")  # the world's robots take goals in map
    try:
        world.run_until(lambda: agent.base.waiting_for() is None, 500, agent.spin, "ready")
        agent.base.navigate_to(1.0, 1.0)
        agent.drive(NavStatus.ABORTED, steps=300)
        assert agent.base.goals_rejected == 1
    finally:
        agent.base.close()
        world.close()


def test_waiting_for_names_what_is_missing() -> None:
    from mrcomm.ros2.nav2_base import Nav2Base
    from mrcomm.ros2.runtime import Nav2Names
    from mrcomm.world.geometry import Pose

    base = Nav2Base.open("robot_9", Pose(0, 0), Nav2Names.of("robot_9"), domain_id=fresh_domain())
    try:
        assert base.waiting_for() == "no NavigateToPose server at /robot_9/navigate_to_pose"
        assert base.status is NavStatus.IDLE and base.pose == Pose(0, 0)
        assert math.isclose(base.odometry_distance, 0.0)
    finally:
        base.close()
