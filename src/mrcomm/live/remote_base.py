"""RemoteBase: the Base port of an agent process whose robot's body lives elsewhere
(the world process in live mode; a robot's navigation stack behind an adapter).

``navigate_to`` / ``cancel`` publish a :class:`~mrcomm.live.protocol.BaseCommand`
on the reliable control lane and never block. The base's state arrives with every
clock tick; :meth:`update` takes it. Until the state acknowledges the latest command,
the status is what that command implies (ACTIVE after ``navigate_to``, IDLE after
``cancel``), so an agent never mistakes the previous goal's SUCCEEDED for the new one.

Pose, odometer, speed and ``make_plan`` are :class:`~mrcomm.robot.reported.ReportedBase`'s.
"""

from __future__ import annotations

from collections.abc import Callable

from mrcomm.live.protocol import BaseCommand, BaseState
from mrcomm.ports import NavStatus
from mrcomm.robot.planner import GridPlanner
from mrcomm.robot.reported import ReportedBase
from mrcomm.world.geometry import Pose

SendFn = Callable[[BaseCommand], None]


class RemoteBase(ReportedBase):
    """Implements the Base port from commands sent and states received."""

    def __init__(
        self,
        robot: str,
        incarnation: int,
        start: Pose,
        send: SendFn,
        planner: GridPlanner | None = None,
    ) -> None:
        super().__init__(start, planner)
        self.robot = robot
        self.incarnation = incarnation
        self._send = send
        self._seq = 0
        self._pending_status = NavStatus.IDLE
        self._state: BaseState | None = None

    # -- Base port -------------------------------------------------------------------
    def navigate_to(self, x: float, y: float) -> None:
        self._command("goto", float(x), float(y))
        self._pending_status = NavStatus.ACTIVE

    def cancel(self) -> None:
        self._command("cancel", 0.0, 0.0)
        self._pending_status = NavStatus.IDLE

    @property
    def status(self) -> NavStatus:
        if not self.acknowledged:
            return self._pending_status
        assert self._state is not None
        return NavStatus(self._state.status)

    # -- state from the world / the robot ----------------------------------------------
    @property
    def acknowledged(self) -> bool:
        """The last state received reflects our latest command."""
        state = self._state
        if self._seq == 0:
            return state is not None
        if state is None or state.incarnation != self.incarnation:
            return False
        return state.ack >= self._seq

    @property
    def has_state(self) -> bool:
        return self._state is not None

    def take(self, state: BaseState | None) -> None:
        """A clock tick's state of this robot's base (None: the tick had none)."""
        if state is not None:
            self.update(state)

    def waiting_for(self) -> str | None:
        """Nothing to wait for: the state comes with the world's ticks."""
        return None

    def close(self) -> None:
        """Nothing to release."""

    def update(self, state: BaseState) -> None:
        self._state = state
        self._pose = Pose(state.x, state.y, state.theta)
        self._odometry = state.odometry
        self._speed = state.v

    def _command(self, kind: str, x: float, y: float) -> None:
        self._seq += 1
        self._send(BaseCommand(self.robot, self.incarnation, self._seq, kind, x, y))
