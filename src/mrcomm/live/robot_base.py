"""The base an agent process drives: the world's simulated base over Zenoh
(:class:`~mrcomm.live.remote_base.RemoteBase`) or a Nav2 robot over ROS 2
(:class:`~mrcomm.ros2.nav2_base.Nav2Base`, ``--base nav2``; needs ``mrcomm[ros2]``).

Both implement the Base port and three more methods the agent process calls:
``take(state)`` on every clock tick (RemoteBase takes the tick's state of its base,
Nav2Base what ROS delivered since), ``waiting_for()`` while joining (what the robot has
not shown yet) and ``close()``.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Protocol

from mrcomm.live.protocol import BaseCommand, BaseState
from mrcomm.live.remote_base import RemoteBase
from mrcomm.live.settings import BaseOptions
from mrcomm.ports import Base
from mrcomm.robot.planner import GridPlanner
from mrcomm.world.geometry import Pose


class AgentBase(Base, Protocol):
    def take(self, state: BaseState | None) -> None: ...

    def waiting_for(self) -> str | None: ...

    def close(self) -> None: ...


def open_base(
    options: BaseOptions,
    robot: str,
    incarnation: int,
    start: Pose,
    send: Callable[[BaseCommand], None],
    planner: GridPlanner | None,
) -> AgentBase:
    """The robot's base as the options say (``nav2``: its ROS thread started)."""
    if options.kind == "nav2":
        from mrcomm.ros2.nav2_base import Nav2Base
        from mrcomm.ros2.runtime import Nav2Names, need_ros2

        need_ros2("--base")
        names = Nav2Names.of(robot, options.namespace, frame=options.frame, qos=options.qos)
        return Nav2Base.open(robot, start, names, planner)
    return RemoteBase(robot, incarnation, start, send, planner)
