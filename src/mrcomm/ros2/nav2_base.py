"""Nav2Base: the Base port (ports.py) on a robot's ROS 2 navigation stack.

* ``navigate_to(x, y)`` sends a ``nav2_msgs/action/NavigateToPose`` goal in the map
  frame, facing along the way from the current pose (Nav2 replaces the current goal);
* ``cancel()`` cancels it; ``status`` follows the goal: ACTIVE from ``navigate_to`` until
  its result, SUCCEEDED / ABORTED from the result (a rejected goal is ABORTED), IDLE
  before any goal and after ``cancel`` (a cancelled goal's result is not reported);
* ``pose`` is the latest ``amcl_pose``; ``odometry_distance`` the running sum of
  ``‖Δposition‖`` of ``odom``; ``speed`` its ``twist.linear.x``;
* ``make_plan`` plans on the robot's copy of the scenario's map with MRComm's planner
  (as RemoteBase does), from the latest pose (:class:`~mrcomm.robot.reported.ReportedBase`);
* ``route`` is the part ahead of the latest ``plan`` (``nav_msgs/Path``, what Nav2's
  planner server publishes each time it plans) received since the current goal was
  sent, while that goal is active (a plan for the goal before may still arrive: it
  ends at that goal, which tells a caller comparing ends).

Every ROS call happens on the :class:`~mrcomm.ros2.runtime.RosThread`; the methods of
the port never block. What arrives from ROS is kept under a lock and taken by
:meth:`Nav2Base.sync` at the start of each agent step, so one step sees one state.
"""

from __future__ import annotations

import math
import threading
from typing import Any

from mrcomm.ports import NavStatus
from mrcomm.robot.planner import GridPlanner
from mrcomm.robot.reported import ReportedBase
from mrcomm.ros2.runtime import (
    Nav2Names,
    RosThread,
    seconds_of,
    set_yaw,
    subscription_qos,
    yaw_of,
)
from mrcomm.world.geometry import Pose

Point = tuple[float, float]


class Nav2Base(ReportedBase):
    """Implements the Base port with a NavigateToPose action client."""

    def __init__(
        self,
        robot: str,
        start: Pose,
        names: Nav2Names,
        ros: RosThread,
        planner: GridPlanner | None = None,
    ) -> None:
        from geometry_msgs.msg import PoseWithCovarianceStamped
        from nav2_msgs.action import NavigateToPose
        from nav_msgs.msg import Odometry, Path
        from rclpy.action import ActionClient

        super().__init__(start, planner)
        self.robot = robot
        self.names = names
        self._ros = ros
        self._owns_ros = False
        self._action_type = NavigateToPose
        node = ros.node
        self._client = ActionClient(node, NavigateToPose, names.name(names.action))
        qos = subscription_qos(names.qos)
        node.create_subscription(
            PoseWithCovarianceStamped, names.name(names.pose_topic), self._on_pose, qos
        )
        node.create_subscription(Odometry, names.name(names.odom_topic), self._on_odom, qos)
        node.create_subscription(Path, names.name(names.plan_topic), self._on_plan, qos)
        self._lock = threading.Lock()
        # Written on the ROS thread, under the lock:
        self._latest_pose = start
        self._latest_odometry = 0.0
        self._latest_speed = 0.0
        self._last_odom_xy: Point | None = None
        self._latest_plan: tuple[Point, ...] = ()
        self._goal_status: dict[int, NavStatus] = {}  # goal token -> outcome
        self._cancel_wanted: set[int] = set()  # goal tokens the agent cancelled
        # The agent thread's view (pose, odometer, speed: ReportedBase's), taken by sync():
        self._token = 0  # the current goal's; 0: none
        self._status = NavStatus.IDLE
        self._handles: dict[int, Any] = {}  # goal token -> ClientGoalHandle (ROS thread)
        self.pose_messages = 0  #: amcl_pose messages received
        # The header stamps (s) of the latest amcl_pose and odom: two topics, which DDS
        # does not order one against the other, so one may be a step behind the other.
        self.pose_stamp = -math.inf
        self.odom_stamp = -math.inf
        self.goals_sent = 0
        self.goals_rejected = 0

    # -- Base port -------------------------------------------------------------------
    def navigate_to(self, x: float, y: float) -> None:
        self._token += 1
        token = self._token
        self._status = NavStatus.ACTIVE
        self.goals_sent += 1
        self._forget_plan()  # the one reported was for the goal before
        goal = self._action_type.Goal()
        goal.pose.header.frame_id = self.names.frame
        goal.pose.header.stamp = self._ros.node.get_clock().now().to_msg()
        goal.pose.pose.position.x = float(x)
        goal.pose.pose.position.y = float(y)
        pose = self._pose
        far = pose.distance_to(x, y) > 1e-6
        heading = math.atan2(y - pose.y, x - pose.x) if far else pose.theta
        set_yaw(goal.pose.pose.orientation, heading)
        self._ros.call_soon(lambda: self._send(token, goal))

    def cancel(self) -> None:
        token = self._token
        self._token += 1  # whatever the cancelled goal reports is not ours any more
        self._status = NavStatus.IDLE
        self._forget_plan()
        if token:
            with self._lock:
                self._cancel_wanted.add(token)
            self._ros.call_soon(lambda: self._cancel(token))

    @property
    def status(self) -> NavStatus:
        return self._status

    # -- the agent's step --------------------------------------------------------------
    def sync(self) -> None:
        """Take what ROS delivered since the last step."""
        with self._lock:
            self._pose = self._latest_pose
            self._odometry = self._latest_odometry
            self._speed = self._latest_speed
            self._plan = self._latest_plan
            outcome = self._goal_status.pop(self._token, None)
            self._goal_status.clear()  # older goals' outcomes are no longer wanted
        if outcome is not None and self._status is NavStatus.ACTIVE:
            self._status = outcome
        if self._status is not NavStatus.ACTIVE:
            self._plan = ()  # no route is being driven

    def _forget_plan(self) -> None:
        with self._lock:
            self._latest_plan = ()
        self._plan = ()

    def take(self, state: object = None) -> None:
        """A clock tick (its base state, if any, is the world's: the robot reports over
        ROS): take what ROS delivered."""
        self.sync()

    @property
    def has_state(self) -> bool:
        """A pose arrived from the robot's localisation."""
        return self.pose_messages > 0

    @property
    def server_ready(self) -> bool:
        return bool(self._client.server_is_ready())

    def waiting_for(self) -> str | None:
        """What the robot has not shown yet (None: ready to drive)."""
        if not self.server_ready:
            return f"no NavigateToPose server at {self.names.name(self.names.action)}"
        if not self.has_state:
            return f"no pose on {self.names.name(self.names.pose_topic)}"
        return None

    def close(self) -> None:
        """Stop the ROS thread (when this base started it)."""
        if self._owns_ros:
            self._ros.close()

    @classmethod
    def open(
        cls,
        robot: str,
        start: Pose,
        names: Nav2Names,
        planner: GridPlanner | None = None,
        domain_id: int | None = None,
    ) -> Nav2Base:
        """A base with a ROS thread of its own (node ``mrcomm_<robot>``)."""
        node = "mrcomm_" + "".join(c if c.isalnum() else "_" for c in robot)
        ros = RosThread(node, domain_id)
        base = cls(robot, start, names, ros, planner)
        base._owns_ros = True
        ros.start()
        return base

    # -- on the ROS thread -------------------------------------------------------------
    def _send(self, token: int, goal: Any) -> None:
        future = self._client.send_goal_async(goal)
        future.add_done_callback(lambda done: self._on_goal_response(token, done))

    def _on_goal_response(self, token: int, future: Any) -> None:
        handle = future.result()
        if handle is None or not handle.accepted:
            self.goals_rejected += 1
            self._finish(token, NavStatus.ABORTED)
            return
        # A goal replaced by a newer one is preempted by the server (as Nav2 does).
        self._handles[token] = handle
        result = handle.get_result_async()
        result.add_done_callback(lambda done: self._on_result(token, done))
        with self._lock:
            cancelled = token in self._cancel_wanted
        if cancelled:
            handle.cancel_goal_async()

    def _cancel(self, token: int) -> None:
        handle = self._handles.get(token)
        if handle is not None:
            handle.cancel_goal_async()
        # Not accepted yet: _on_goal_response cancels it on acceptance.

    def _on_result(self, token: int, future: Any) -> None:
        from action_msgs.msg import GoalStatus

        self._handles.pop(token, None)
        with self._lock:
            self._cancel_wanted.discard(token)
        wrapped = future.result()
        status = wrapped.status if wrapped is not None else GoalStatus.STATUS_ABORTED
        if status == GoalStatus.STATUS_SUCCEEDED:
            self._finish(token, NavStatus.SUCCEEDED)
        elif status == GoalStatus.STATUS_CANCELED:
            self._finish(token, NavStatus.IDLE)
        else:
            self._finish(token, NavStatus.ABORTED)

    def _finish(self, token: int, outcome: NavStatus) -> None:
        with self._lock:
            self._goal_status[token] = outcome

    def _on_pose(self, message: Any) -> None:
        p = message.pose.pose
        pose = Pose(p.position.x, p.position.y, yaw_of(p.orientation))
        with self._lock:
            self._latest_pose = pose
        self.pose_stamp = seconds_of(message.header.stamp)
        self.pose_messages += 1

    def _on_plan(self, message: Any) -> None:
        plan = tuple((p.pose.position.x, p.pose.position.y) for p in message.poses)
        with self._lock:
            self._latest_plan = plan

    def _on_odom(self, message: Any) -> None:
        position = message.pose.pose.position
        xy = (position.x, position.y)
        with self._lock:
            if self._last_odom_xy is not None:
                lx, ly = self._last_odom_xy
                self._latest_odometry += math.hypot(xy[0] - lx, xy[1] - ly)
            self._last_odom_xy = xy
            self._latest_speed = message.twist.twist.linear.x
        self.odom_stamp = seconds_of(message.header.stamp)
