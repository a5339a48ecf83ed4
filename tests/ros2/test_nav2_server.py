"""The world's robots as Nav2 robots (``ros2.nav2_server``, served by ``mrcomm world
--ros2``), seen by a plain rclpy client as any Nav2 client sees Nav2: NavigateToPose
goals with feedback and success, cancel, abort when the goal is unreachable,
preemption by a new goal, a goal in a foreign frame rejected; ``amcl_pose`` and
``odom`` as the simulated base reports them."""

from __future__ import annotations

import itertools
import math
from collections.abc import Iterator
from typing import Any

import pytest

from .helpers import SteppedWorld, fresh_domain, needs_ros2, spin_client

pytestmark = needs_ros2


class Client:
    """A plain rclpy node with an action client for robot_1 and its topics."""

    def __init__(self, domain_id: int) -> None:
        import rclpy
        from geometry_msgs.msg import PoseWithCovarianceStamped
        from nav2_msgs.action import NavigateToPose
        from nav_msgs.msg import Odometry
        from rclpy.action import ActionClient
        from rclpy.context import Context
        from rclpy.executors import SingleThreadedExecutor

        self.context = Context()
        rclpy.init(context=self.context, domain_id=domain_id)
        self.node = rclpy.create_node("test_client", context=self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self.action = NavigateToPose
        self.client = ActionClient(self.node, NavigateToPose, "/robot_1/navigate_to_pose")
        self.poses: list[Any] = []
        self.odoms: list[Any] = []
        self.node.create_subscription(
            PoseWithCovarianceStamped, "/robot_1/amcl_pose", self.poses.append, 50
        )
        self.node.create_subscription(Odometry, "/robot_1/odom", self.odoms.append, 50)
        self.feedback: list[Any] = []

    def spin(self) -> None:
        spin_client(self.executor)

    def send(self, x: float, y: float, frame: str = "map") -> Any:
        goal = self.action.Goal()
        goal.pose.header.frame_id = frame
        goal.pose.pose.position.x = x
        goal.pose.pose.position.y = y
        goal.pose.pose.orientation.w = 1.0
        return self.client.send_goal_async(
            goal, feedback_callback=lambda message: self.feedback.append(message.feedback)
        )

    def close(self) -> None:
        self.executor.shutdown(timeout_sec=1.0)
        self.node.destroy_node()
        self.context.try_shutdown()


@pytest.fixture
def world_and_client() -> Iterator[tuple[SteppedWorld, Client]]:
    domain = fresh_domain()
    world = SteppedWorld(domain)
    client = Client(domain)
    try:
        world.run_until(
            lambda: client.client.server_is_ready(), 500, client.spin, "server discovered"
        )
        yield world, client
    finally:
        client.close()
        world.close()


def accepted(world: SteppedWorld, client: Client, future: Any) -> Any:
    world.run_until(future.done, 300, client.spin, "goal response")
    handle = future.result()
    assert handle.accepted
    return handle


def outcome(world: SteppedWorld, client: Client, handle: Any, steps: int = 600) -> Any:
    result = handle.get_result_async()
    world.run_until(result.done, steps, client.spin, "goal result")
    return result.result()


def test_goal_succeeds_with_feedback(world_and_client: tuple[SteppedWorld, Client]) -> None:
    from action_msgs.msg import GoalStatus

    world, client = world_and_client
    start = world.bases["robot_1"].true_pose
    gx, gy = start.x + 2.0, start.y
    handle = accepted(world, client, client.send(gx, gy))
    done = outcome(world, client, handle)
    assert done.status == GoalStatus.STATUS_SUCCEEDED
    assert done.result.error_code == client.action.Result.NONE
    end = world.bases["robot_1"].true_pose
    assert math.hypot(end.x - gx, end.y - gy) < 0.3
    # Feedback while driving: the pose moves towards the goal, the distance shrinks.
    assert len(client.feedback) >= 3
    remaining = [f.distance_remaining for f in client.feedback]
    assert remaining[0] > remaining[-1] and remaining[0] > 1.0
    assert client.feedback[-1].navigation_time.sec >= 1
    assert client.feedback[-1].current_pose.header.frame_id == "map"


def test_cancel_stops_the_robot(world_and_client: tuple[SteppedWorld, Client]) -> None:
    from action_msgs.msg import GoalStatus

    from mrcomm.ports import NavStatus

    world, client = world_and_client
    base = world.bases["robot_1"]
    start = base.true_pose
    handle = accepted(world, client, client.send(start.x + 6.0, start.y))
    world.run_until(lambda: base.speed > 0.2, 300, client.spin, "robot driving")
    cancel = handle.cancel_goal_async()
    world.run_until(cancel.done, 300, client.spin, "cancel response")
    assert len(cancel.result().goals_canceling) == 1
    done = outcome(world, client, handle)
    assert done.status == GoalStatus.STATUS_CANCELED
    assert base.status is NavStatus.IDLE
    world.run_until(lambda: abs(base.speed) < 1e-6, 100, client.spin, "robot stopped")
    assert base.true_pose.distance_to(start.x + 6.0, start.y) > 1.0  # it did not go on


def test_unreachable_goal_is_aborted(world_and_client: tuple[SteppedWorld, Client]) -> None:
    from action_msgs.msg import GoalStatus

    world, client = world_and_client
    handle = accepted(world, client, client.send(-100.0, -100.0))  # off the map
    done = outcome(world, client, handle, steps=50)
    assert done.status == GoalStatus.STATUS_ABORTED
    assert done.result.error_code == client.action.Result.UNKNOWN
    assert "could not reach" in done.result.error_msg


def test_new_goal_preempts_the_current(world_and_client: tuple[SteppedWorld, Client]) -> None:
    from action_msgs.msg import GoalStatus

    world, client = world_and_client
    start = world.bases["robot_1"].true_pose
    first = accepted(world, client, client.send(start.x + 6.0, start.y))
    for _ in range(10):
        world.step()
        client.spin()
    # Along the start heading (down the corridor): away from the mates at the start.
    gx, gy = start.x + math.cos(start.theta), start.y + math.sin(start.theta)
    second = accepted(world, client, client.send(gx, gy))
    preempted = outcome(world, client, first)
    assert preempted.status == GoalStatus.STATUS_ABORTED
    assert "preempted" in preempted.result.error_msg
    assert outcome(world, client, second).status == GoalStatus.STATUS_SUCCEEDED
    assert world.bases["robot_1"].true_pose.distance_to(gx, gy) < 0.3


def test_goal_in_another_frame_is_rejected(
    world_and_client: tuple[SteppedWorld, Client],
) -> None:
    world, client = world_and_client
    future = client.send(1.0, 1.0, frame="odom")
    world.run_until(future.done, 300, client.spin, "goal response")
    assert not future.result().accepted


def test_pose_and_odometry_topics(world_and_client: tuple[SteppedWorld, Client]) -> None:
    from mrcomm.ros2.runtime import seconds_of, yaw_of

    world, client = world_and_client
    base = world.bases["robot_1"]
    start = base.true_pose
    handle = accepted(world, client, client.send(start.x + 2.0, start.y + 0.5))
    outcome(world, client, handle)
    for _ in range(20):  # let the last messages arrive
        client.spin()
    last = client.poses[-1]
    assert last.header.frame_id == "map"
    pose = base.pose  # the localisation estimate, as AMCL gives it
    assert last.pose.pose.position.x == pytest.approx(pose.x, abs=1e-9)
    assert last.pose.pose.position.y == pytest.approx(pose.y, abs=1e-9)
    assert yaw_of(last.pose.pose.orientation) == pytest.approx(pose.theta, abs=1e-9)
    # Stamps are mission time (use_sim_time).
    stamp = seconds_of(last.header.stamp)
    assert stamp == pytest.approx(world.now, abs=1e-6)
    # The odom frame's path length is the odometer's distance.
    xy = [(o.pose.pose.position.x, o.pose.pose.position.y) for o in client.odoms]
    path = sum(math.dist(a, b) for a, b in itertools.pairwise(xy))
    assert len(client.odoms) > 20
    assert path == pytest.approx(base.odometry_distance, rel=1e-6)
    assert client.odoms[-1].header.frame_id == "odom"
