"""Nav2Server: every simulated robot of the live world as a Nav2-compatible robot
(``mrcomm world --ros2``), so agents drive them through ROS 2 as they would real ones.

Per robot, in its namespace (``/<robot id>`` by default):

* the action server ``navigate_to_pose`` (``nav2_msgs/action/NavigateToPose``): a goal in
  the map frame is accepted (another frame is rejected) and handed to the robot's
  simulated base; a new goal preempts the current one (aborted, as Nav2's navigator
  does); a cancel request stops the robot; the goal succeeds when the base arrives and
  is aborted when the base gives up (no path, stuck). Feedback (current pose, distance
  remaining, navigation time, recoveries) every few ticks;
* ``amcl_pose`` (``geometry_msgs/PoseWithCovarianceStamped``): the base's localisation
  estimate, every tick;
* ``odom`` (``nav_msgs/Odometry``): a pose in the ``odom`` frame dead-reckoned from the
  base's odometer (its path length is the odometer's distance) and the forward speed;
* ``plan`` (``nav_msgs/Path``): the route the base drives, from its pose, when a goal
  starts and then once a second while it is active (Nav2's default navigator plans
  again once a second and its planner server publishes each plan);

and ``/clock`` carries the mission time (stamps are mission time, as a simulator with
``use_sim_time`` gives them).

The world's thread calls :meth:`Nav2Server.apply` before advancing the bases (goals and
cancels that arrived) and :meth:`Nav2Server.publish` after; the ROS side runs on the
:class:`~mrcomm.ros2.runtime.RosThread`.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from mrcomm.ports import Base, NavStatus
from mrcomm.ros2.runtime import Nav2Names, RosThread, publisher_qos, set_seconds, set_yaw

FEEDBACK_EVERY = 5  # ticks between feedback messages of an active goal
PLAN_PERIOD = 1.0  # mission s between the plans published for an active goal
#: What an aborted goal's result says (Nav2's own error codes and messages).
ABORTED_MESSAGE = "the robot could not reach the goal (no path, or stuck)"
PREEMPTED_MESSAGE = "preempted by a new goal"


@dataclass
class _Goal:
    robot: str
    handle: Any
    x: float
    y: float
    future: Any
    started: float = 0.0
    planned: float = -float("inf")  # when its plan was last published
    done: bool = False
    outcome: tuple[str, int, str] = field(default=("", 0, ""))


@dataclass
class _Odom:
    x: float = 0.0
    y: float = 0.0
    distance: float = 0.0


class Nav2Server:
    """The ROS 2 face of the world's simulated bases."""

    def __init__(
        self, robots: Sequence[str], frame: str = "map", domain_id: int | None = None
    ) -> None:
        from geometry_msgs.msg import PoseStamped, PoseWithCovarianceStamped
        from nav2_msgs.action import NavigateToPose
        from nav_msgs.msg import Odometry, Path
        from rclpy.action import ActionServer
        from rosgraph_msgs.msg import Clock

        self.frame = frame
        self.ros = RosThread("mrcomm_world", domain_id)
        node = self.ros.node
        self._action_type = NavigateToPose
        self._pose_type = PoseWithCovarianceStamped
        self._pose_stamped_type = PoseStamped
        self._odom_type = Odometry
        self._path_type = Path
        self._clock_type = Clock
        qos = publisher_qos()
        self.names = {r: Nav2Names.of(r, frame=frame) for r in robots}
        self._servers = []
        self._pose_pub: dict[str, Any] = {}
        self._odom_pub: dict[str, Any] = {}
        self._plan_pub: dict[str, Any] = {}
        for robot, names in self.names.items():
            self._servers.append(
                ActionServer(
                    node,
                    NavigateToPose,
                    names.name(names.action),
                    execute_callback=self._execute_for(robot),
                    goal_callback=self._check_goal,
                    cancel_callback=self._on_cancel,
                )
            )
            self._pose_pub[robot] = node.create_publisher(
                PoseWithCovarianceStamped, names.name(names.pose_topic), qos
            )
            self._odom_pub[robot] = node.create_publisher(
                Odometry, names.name(names.odom_topic), qos
            )
            self._plan_pub[robot] = node.create_publisher(Path, names.name(names.plan_topic), qos)
        self._clock_pub = node.create_publisher(Clock, "/clock", qos)
        #: (kind, goal) from the ROS thread to the world's, in arrival order.
        self._ops: deque[tuple[str, _Goal]] = deque()
        self._goals: dict[bytes, _Goal] = {}  # by goal id (ROS thread)
        self._current: dict[str, _Goal] = {}  # robot -> goal its base drives to (world)
        self._odom = {r: _Odom() for r in robots}
        self._ticks = 0
        self.now = 0.0
        self.goals_received = 0
        self.outcomes: dict[str, int] = {}  #: results sent, by outcome
        self.ros.start()

    # -- the world's thread ----------------------------------------------------------
    def apply(self, bases: Mapping[str, Base]) -> None:
        """Hand the goals and cancels that arrived to the bases."""
        while self._ops:
            kind, goal = self._ops.popleft()
            base = bases[goal.robot]
            if kind == "goto":
                previous = self._current.get(goal.robot)
                if previous is not None and not previous.done:
                    self._finish(previous, "aborted", PREEMPTED_MESSAGE)
                self._current[goal.robot] = goal
                goal.started = self.now
                base.navigate_to(goal.x, goal.y)
            elif kind == "cancel" and not goal.done:
                if self._current.get(goal.robot) is goal:
                    base.cancel()
                    del self._current[goal.robot]
                self._finish(goal, "canceled", "")

    def publish(self, now: float, bases: Mapping[str, Base]) -> None:
        """Publish every robot's pose, odometry and goal progress at mission time ``now``."""
        self.now = now
        self._ticks += 1
        messages: list[tuple[Any, Any]] = []
        clock = self._clock_type()
        set_seconds(clock.clock, now)
        messages.append((self._clock_pub, clock))
        feedback_due = self._ticks % FEEDBACK_EVERY == 0
        feedbacks: list[tuple[Any, Any]] = []
        for robot, base in bases.items():
            pose = base.pose
            messages.append((self._pose_pub[robot], self._pose_message(now, pose)))
            messages.append((self._odom_pub[robot], self._odom_message(now, robot, base)))
            goal = self._current.get(robot)
            if goal is None or goal.done:
                continue
            status = base.status
            if status is NavStatus.SUCCEEDED:
                self._finish(goal, "succeeded", "")
                continue
            if status is not NavStatus.ACTIVE:
                self._finish(goal, "aborted", ABORTED_MESSAGE)
                continue
            if feedback_due:
                feedbacks.append((goal.handle, self._feedback(now, goal, base)))
            if now - goal.planned >= PLAN_PERIOD - 1e-9 and base.route:
                goal.planned = now
                messages.append((self._plan_pub[robot], self._plan_message(now, pose, base)))
        self.ros.call_soon(lambda: _send(messages, feedbacks))

    def summary(self) -> dict[str, object]:
        return {
            "server": "nav2",
            "goals": self.goals_received,
            "outcomes": dict(sorted(self.outcomes.items())),
        }

    def close(self) -> None:
        self.ros.close()

    # -- messages ------------------------------------------------------------------------
    def _pose_message(self, now: float, pose: Any) -> Any:
        message = self._pose_type()
        message.header.frame_id = self.frame
        set_seconds(message.header.stamp, now)
        message.pose.pose.position.x = float(pose.x)
        message.pose.pose.position.y = float(pose.y)
        set_yaw(message.pose.pose.orientation, float(pose.theta))
        return message

    def _odom_message(self, now: float, robot: str, base: Base) -> Any:
        odom = self._odom[robot]
        travelled = base.odometry_distance - odom.distance
        odom.distance = base.odometry_distance
        theta = base.pose.theta
        odom.x += travelled * math.cos(theta)
        odom.y += travelled * math.sin(theta)
        message = self._odom_type()
        message.header.frame_id = "odom"
        message.child_frame_id = "base_link"
        set_seconds(message.header.stamp, now)
        message.pose.pose.position.x = odom.x
        message.pose.pose.position.y = odom.y
        set_yaw(message.pose.pose.orientation, float(theta))
        message.twist.twist.linear.x = float(base.speed)
        return message

    def _plan_message(self, now: float, pose: Any, base: Base) -> Any:
        message = self._path_type()
        message.header.frame_id = self.frame
        set_seconds(message.header.stamp, now)
        for x, y in ((pose.x, pose.y), *base.route):
            stamped = self._pose_stamped_type()
            stamped.header = message.header
            stamped.pose.position.x = float(x)
            stamped.pose.position.y = float(y)
            message.poses.append(stamped)
        return message

    def _feedback(self, now: float, goal: _Goal, base: Base) -> Any:
        feedback = self._action_type.Feedback()
        pose = base.pose
        feedback.current_pose.header.frame_id = self.frame
        set_seconds(feedback.current_pose.header.stamp, now)
        feedback.current_pose.pose.position.x = float(pose.x)
        feedback.current_pose.pose.position.y = float(pose.y)
        set_yaw(feedback.current_pose.pose.orientation, float(pose.theta))
        elapsed = max(0.0, now - goal.started)
        set_seconds(feedback.navigation_time, elapsed)
        remaining = pose.distance_to(goal.x, goal.y)
        feedback.distance_remaining = float(remaining)
        speed = abs(base.speed)
        if speed > 1e-3:
            set_seconds(feedback.estimated_time_remaining, remaining / speed)
        feedback.number_of_recoveries = int(getattr(base, "recoveries", 0))
        return feedback

    def _finish(self, goal: _Goal, outcome: str, text: str) -> None:
        """World thread: the goal is over; its execute coroutine ends on the ROS thread."""
        result = self._action_type.Result
        code = result.NONE if outcome != "aborted" else result.UNKNOWN
        goal.done = True
        goal.outcome = (outcome, code, text)
        self.outcomes[outcome] = self.outcomes.get(outcome, 0) + 1
        self.ros.call_soon(lambda: goal.future.set_result(goal.outcome))

    # -- the ROS thread ------------------------------------------------------------------
    def _check_goal(self, request: Any) -> Any:
        from rclpy.action import GoalResponse

        frame = request.pose.header.frame_id
        if frame not in ("", self.frame):
            return GoalResponse.REJECT
        return GoalResponse.ACCEPT

    def _on_cancel(self, handle: Any) -> Any:
        from rclpy.action import CancelResponse

        goal = self._goals.get(bytes(handle.goal_id.uuid))
        if goal is None or goal.done:
            return CancelResponse.REJECT
        self._ops.append(("cancel", goal))
        return CancelResponse.ACCEPT

    def _execute_for(self, robot: str) -> Any:
        async def execute(handle: Any) -> Any:
            from rclpy.task import Future

            position = handle.request.pose.pose.position
            goal = _Goal(robot, handle, float(position.x), float(position.y), Future())
            key = bytes(handle.goal_id.uuid)
            self._goals[key] = goal
            self.goals_received += 1
            self._ops.append(("goto", goal))
            outcome, code, text = await goal.future
            del self._goals[key]
            if outcome == "succeeded":
                handle.succeed()
            elif outcome == "canceled" and handle.is_cancel_requested:
                handle.canceled()
            else:
                handle.abort()
            result = self._action_type.Result()
            result.error_code = code
            result.error_msg = text
            return result

        return execute


def _send(messages: list[tuple[Any, Any]], feedbacks: list[tuple[Any, Any]]) -> None:
    """ROS thread: one tick's messages, then the feedback of goals still active."""
    for publisher, message in messages:
        publisher.publish(message)
    for handle, feedback in feedbacks:
        if handle.is_active:
            handle.publish_feedback(feedback)
