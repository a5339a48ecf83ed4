"""A simulated mission with an operator, stepped in its own thread at a pace the console
sets (paused, ×1, ×10, as fast as possible), and what the console shows of it.

The mission, the operator and everything they hold belong to the stepping thread; the
console talks to it only through :meth:`ConsoleSession.submit` (a command queue, applied
between steps) and reads :attr:`ConsoleSession.view`, a frozen snapshot replaced every
:data:`VIEW_PERIOD` of wall time — so the page never sees a half-made step and the
mission stays deterministic: a command takes effect at the step it is applied, and is
recorded with that time.
"""

from __future__ import annotations

import math
import threading
import time
from dataclasses import replace
from typing import Any

from mrcomm.console.desk import OperatorDesk
from mrcomm.console.view import ConsoleView, snapshot
from mrcomm.run.config import RunConfig
from mrcomm.run.operator_plan import OperatorPlan
from mrcomm.run.resources import ScenarioResources
from mrcomm.run.result import MissionResult
from mrcomm.sim.mission import Mission
from mrcomm.world.occupancy import OccupancyGrid

#: The speeds the console offers (× real time; 0: paused; inf: as fast as possible).
SPEEDS = {"pause": 0.0, "x1": 1.0, "x10": 10.0, "max": math.inf}
#: Wall time between two snapshots.
VIEW_PERIOD = 0.25  # the page refreshes four times a second: no need for more


class ConsoleSession:
    def __init__(
        self,
        config: RunConfig,
        resources: ScenarioResources | None = None,
        plan: OperatorPlan | None = None,
        speed: float = 1.0,
    ) -> None:
        self.mission = Mission(config, resources, plan or OperatorPlan())
        assert self.mission.operator is not None
        self.operator = self.mission.operator
        self.speed = speed
        self.result: MissionResult | None = None
        self.desk = OperatorDesk(self.operator, on_end=self._end)
        self.events = self.desk.events
        self.notes = self.desk.notes  # replies to the console (refused commands)
        self._indices = dict.fromkeys(self.mission.robot_ids, 0)
        self._stop = threading.Event()
        #: The operator ends the mission (a console keeps a mission whose statuses did
        #: not all arrive open, so that robots can be sent back for them).
        self.end_requested = False
        self.finished = threading.Event()
        self.view: ConsoleView = snapshot(self.mission, self.operator, self.events)

    #: The simulation has ground truth for the page to show.
    has_truth = True

    @property
    def grid(self) -> OccupancyGrid:
        return self.mission.resources.scenario.grid

    @property
    def robot_ids(self) -> tuple[str, ...]:
        return self.mission.robot_ids

    @property
    def waiting(self) -> bool:
        """The robots are done and the mission stays open for the operator."""
        return self.mission.finished

    def submit(
        self, kind: str, robot: str = "", task: str = "", where: tuple[float, float] | None = None
    ) -> bool:
        """Queue an operator command; it is sent at the next step (False: refused,
        see :class:`OperatorDesk`)."""
        return self.desk.submit(kind, robot, task, where)

    def _end(self) -> None:
        self.end_requested = True

    def stop(self) -> None:
        self._stop.set()

    def run(self) -> MissionResult:
        """Step the mission to its end at the chosen pace (call in its own thread)."""
        mission = self.mission
        started = time.perf_counter()
        wall0, sim0 = started, mission.now
        last_speed, next_view = self.speed, 0.0
        while not self._over() and not self._stop.is_set():
            speed = self.speed
            if speed != last_speed:  # a new pace counts from now
                wall0, sim0, last_speed = time.perf_counter(), mission.now, speed
            if speed <= 0.0:
                self._stop.wait(VIEW_PERIOD)
                wall0, sim0 = time.perf_counter(), mission.now
                self._publish_view()
                continue
            self.desk.apply(mission.now)
            mission.step()
            self._collect_events()
            wall = time.perf_counter()
            if math.isfinite(speed):
                ahead = (mission.now - sim0) / speed - (wall - wall0)
                if ahead > 0:
                    self._stop.wait(ahead)
            if wall >= next_view:
                next_view = wall + VIEW_PERIOD
                self._publish_view()
        result = mission.result()
        self.result = replace(result, wall_time_s=time.perf_counter() - started)
        self._publish_view(ended=True)
        self.finished.set()
        return self.result

    def _over(self) -> bool:
        """The time limit, or the robots done and every status arrived (or the operator
        ends it)."""
        m = self.mission
        if m.now >= m.config.max_time - 1e-9:
            return True
        return m.finished and (self.end_requested or not m.assigner.failed())

    def _collect_events(self) -> None:
        for rid, timeline in self.mission.timelines.items():
            for event in timeline.events[self._indices[rid] :]:
                details = " ".join(f"{k}={v}" for k, v in event.data.items())
                self.events.append(f"{event.time:7.1f} {rid} {event.label} {details}".rstrip())
            self._indices[rid] = len(timeline.events)
        self.desk.log_commands()

    def _publish_view(self, *, ended: bool = False) -> None:
        view = snapshot(self.mission, self.operator, self.events)
        successful = self.result.mission["successful"] if self.result is not None else None
        self.view = replace(
            view,
            ended=ended,
            successful=successful,
            notes=tuple(list(self.desk.notes)[-5:]),
            result=result_line(self.result.mission) if self.result is not None else "",
        )


def result_line(mission: dict[str, Any]) -> str:
    """A mission's result in one line, for the page once it has ended."""
    done, total = mission["tasks_completed"], mission["tasks_total"]
    parts = [f"{done}/{total} tasks"]
    if mission.get("execution_phase_time") is not None:
        parts.append(f"execution phase {mission['execution_phase_time']:.1f} s")
    parts.append(f"{mission['near_collisions']} near collisions")
    return " · ".join(parts)
