"""What both sides of the Nav2 interface share: the import check, the interface names
and QoS of one robot, pose conversions, and :class:`RosThread`.

rclpy objects are used from one thread only, the one its executor spins in: the agent
and the world step on their own threads and hand work over with
:meth:`RosThread.call_soon` (a queue and a guard condition, which rclpy documents as
safe to trigger from any thread). Results come back the other way as plain values
under a lock.
"""

from __future__ import annotations

import math
import threading
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from mrcomm.errors import InputError

#: How the ROS 2 pieces are installed here (and on a robot: its own ROS 2).
INSTALL_HINT = (
    "install the extra (make ros2: mrcomm[ros2] and nav2_msgs built locally) "
    "or run in a sourced ROS 2 environment with nav2_msgs"
)
QOS_CHOICES = ("best_effort", "reliable")


def ros2_missing() -> str | None:
    """Why the Nav2 adapters cannot run here (None when they can)."""
    try:
        import rclpy
        import rclpy.action  # noqa: F401
    except ImportError as error:
        return f"rclpy is not importable ({error})"
    try:
        from nav2_msgs.action import NavigateToPose  # noqa: F401
    except ImportError as error:
        return f"nav2_msgs is not importable ({error})"
    try:
        from geometry_msgs.msg import PoseWithCovarianceStamped  # noqa: F401
        from nav_msgs.msg import Odometry  # noqa: F401
    except ImportError as error:
        return f"geometry_msgs / nav_msgs are not importable ({error})"
    return None


def need_ros2(option: str) -> None:
    """One-line error (exit 2) before any work when the ROS 2 pieces are missing."""
    missing = ros2_missing()
    if missing is not None:
        raise InputError(f"{missing}: {INSTALL_HINT}", field=option)


@dataclass(frozen=True)
class Nav2Names:
    """One robot's Nav2 interfaces: ``<namespace>/navigate_to_pose`` (action),
    ``<namespace>/amcl_pose``, ``<namespace>/odom`` and ``<namespace>/plan`` (topics),
    poses in ``frame``."""

    namespace: str
    frame: str = "map"
    action: str = "navigate_to_pose"
    pose_topic: str = "amcl_pose"
    odom_topic: str = "odom"
    #: The global plan Nav2's planner server publishes (``nav_msgs/Path``).
    plan_topic: str = "plan"
    #: Reliability of the agent's subscriptions. ``best_effort`` matches any publisher
    #: (AMCL publishes reliable, many robots' odometry best effort); ``reliable``
    #: refuses best-effort publishers.
    qos: str = "best_effort"

    def __post_init__(self) -> None:
        if self.qos not in QOS_CHOICES:
            raise InputError(
                f"unknown QoS {self.qos!r}; choose {' or '.join(QOS_CHOICES)}", field="--ros-qos"
            )
        for name, value in (("--ros-namespace", self.namespace), ("--ros-frame", self.frame)):
            if not value or any(c.isspace() for c in value):
                raise InputError(f"not a ROS name: {value!r}", field=name)

    @classmethod
    def of(cls, robot: str, namespace: str | None = None, **options: Any) -> Nav2Names:
        """A robot's names; the namespace defaults to ``/<robot id>``."""
        return cls(namespace or f"/{robot}", **options)

    def name(self, leaf: str) -> str:
        return f"{self.namespace.rstrip('/')}/{leaf}"


def yaw_of(q: Any) -> float:
    """Yaw (rad) of a ``geometry_msgs/Quaternion``."""
    return math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))


def set_yaw(q: Any, yaw: float) -> None:
    """Write a rotation about z into a ``geometry_msgs/Quaternion``."""
    q.x = 0.0
    q.y = 0.0
    q.z = math.sin(yaw / 2.0)
    q.w = math.cos(yaw / 2.0)


def seconds_of(stamp: Any) -> float:
    """A ``builtin_interfaces/Time`` (or Duration) in seconds."""
    return stamp.sec + stamp.nanosec * 1e-9


def set_seconds(stamp: Any, seconds: float) -> None:
    """Write ``seconds`` (>= 0) into a ``builtin_interfaces/Time`` (or Duration)."""
    whole = math.floor(seconds)
    stamp.sec = int(whole)
    stamp.nanosec = round((seconds - whole) * 1e9) % 1_000_000_000


def subscription_qos(reliability: str, depth: int = 5) -> Any:
    """Volatile (matches both volatile and transient-local publishers, e.g. AMCL's)."""
    from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

    return QoSProfile(
        history=HistoryPolicy.KEEP_LAST,
        depth=depth,
        reliability=(
            ReliabilityPolicy.RELIABLE
            if reliability == "reliable"
            else ReliabilityPolicy.BEST_EFFORT
        ),
        durability=DurabilityPolicy.VOLATILE,
    )


def publisher_qos(depth: int = 5) -> Any:
    """Reliable and volatile: every subscriber QoS can match it."""
    from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

    return QoSProfile(
        history=HistoryPolicy.KEEP_LAST,
        depth=depth,
        reliability=ReliabilityPolicy.RELIABLE,
        durability=DurabilityPolicy.VOLATILE,
    )


class RosThread:
    """An rclpy context, one node and a single-threaded executor spinning in a thread
    of its own. Work for the node is handed over with :meth:`call_soon`."""

    def __init__(self, node_name: str, domain_id: int | None = None) -> None:
        """``domain_id``: the ROS domain (default: ``ROS_DOMAIN_ID``, else 0)."""
        import rclpy
        from rclpy.context import Context
        from rclpy.executors import SingleThreadedExecutor

        # A context of our own: the process may hold others (tests run both sides).
        self.context = Context()
        rclpy.init(context=self.context, domain_id=domain_id)
        self.node = rclpy.create_node(node_name, context=self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self._work: deque[Callable[[], None]] = deque()
        self._guard = self.node.create_guard_condition(self._run_work)
        self._thread = threading.Thread(target=self._spin, name=f"rclpy-{node_name}", daemon=True)
        self.error: BaseException | None = None

    def start(self) -> RosThread:
        self._thread.start()
        return self

    def call_soon(self, work: Callable[[], None]) -> None:
        """Run ``work`` on the executor's thread (from any thread)."""
        self._work.append(work)
        self._guard.trigger()

    def _run_work(self) -> None:
        while self._work:
            self._work.popleft()()

    def _spin(self) -> None:
        from rclpy.executors import ExternalShutdownException

        try:
            while self.context.ok():
                self.executor.spin_once(timeout_sec=0.2)
        except ExternalShutdownException:
            pass
        except BaseException as error:  # surfaced by the owner (alive / close)
            self.error = error

    @property
    def alive(self) -> bool:
        return self._thread.is_alive()

    def close(self) -> None:
        if self.context.ok():
            self.context.try_shutdown()
        self._thread.join(timeout=5.0)
        self.executor.shutdown(timeout_sec=1.0)
        self.node.destroy_node()
