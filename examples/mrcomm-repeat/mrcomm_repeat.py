"""``repeat`` — an example MRComm behaviour written outside MRComm, in one file.

NB with redundancy: each task status is published ``repeats`` times, one second apart,
instead of once. It is the cheapest way to fight packet loss without acknowledgements:
at SPL X % a status is lost only if every copy is (X^repeats), where NB loses X and
LF's AON makes sure at the cost of n(n+1) publications per status.

Everything a behaviour needs is here: the executor class (a subclass of MRComm's NB
executor), its parameter model (with defaults, limits, units), the metric it adds
(``status_copies``: each robot counts the copies it published; the team's total is a
team metric, stored with every run, tested by ``mrcomm analyze`` and drawn by
``mrcomm report``) and its spec. The entry point in ``pyproject.toml`` registers the
spec.
"""

from __future__ import annotations

from typing import Any, ClassVar

from mrcomm.agents.behaviour import AgentContext
from mrcomm.agents.executor import ExecutorParams, TaskExecutor
from mrcomm.messaging.messages import TOPIC_TASK_STATUS, TaskState, TaskStatus
from mrcomm.metrics.timeline import Timeline
from mrcomm.specs import TeamMetric, VariantSpec, parameter

REPEAT_PERIOD_S = 1.0  # between copies of a status
COPY_EVENT = "status_copy"  # recorded in the robot's timeline for each copy published


class RepeatParams(ExecutorParams):
    """NB's parameters and one more."""

    repeats: int = parameter(3, "times each task status is published (1: plain NB)", ge=1, le=20)


class RepeatExecutor(TaskExecutor):
    """NB that publishes each status ``repeats`` times."""

    Params: ClassVar[type[ExecutorParams]] = RepeatParams

    def __init__(self, context: AgentContext, params: ExecutorParams) -> None:
        super().__init__(context, params)  # refuses parameters that are not RepeatParams
        # (due time, copies left, status): copies still to publish.
        self._copies: list[tuple[float, int, TaskStatus]] = []

    @property
    def repeats(self) -> int:
        params = self.params
        assert isinstance(params, RepeatParams)  # the executor was made with its own
        return params.repeats

    def send_status(self, task_id: str, state: TaskState) -> None:
        status = self.status_message(task_id, state)
        self.bus.publish(TOPIC_TASK_STATUS, status)
        if state is TaskState.SUCCESS and self.repeats > 1:
            self._copies.append((self.now + REPEAT_PERIOD_S, self.repeats - 1, status))

    def before_state_step(self) -> None:
        """Publish the copies that are due (the same message: receivers see duplicates
        of one status, not new statuses)."""
        pending = []
        for due, left, status in self._copies:
            if self.now + 1e-9 >= due:
                self.bus.publish(TOPIC_TASK_STATUS, status)
                self.timeline.event(COPY_EVENT, self.now, task_id=status.task_id)
                left -= 1
                due += REPEAT_PERIOD_S
            if left > 0:
                pending.append((due, left, status))
        self._copies = pending

    @property
    def done(self) -> bool:
        return super().done and not self._copies


def repeat_metrics(timeline: Timeline) -> dict[str, Any]:
    """The metric this behaviour adds to each robot's: the copies it published."""
    return {"status_copies": timeline.count(COPY_EVENT)}


SPEC = VariantSpec(
    kind="behaviour",
    name="repeat",
    entry=RepeatExecutor,
    params=RepeatParams,
    summary="NB that publishes each task status `repeats` times, 1 s apart (example plugin)",
    topics=("pose", "task_status"),
    robot_metrics=repeat_metrics,
    metrics=("status_copies",),
    team_metrics=(TeamMetric("status_copies", "Status copies sent", "count", "greater"),),
)
