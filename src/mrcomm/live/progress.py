"""Progress of a live mission while it runs, read from the journals its processes
write (the world's clock ticks and presence changes, the agents' completed tasks).

The journals are followed incrementally: each poll reads only the complete lines
written since the last one, so following a long mission costs little.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

from mrcomm.agents.assigner import ASSIGNER_ID
from mrcomm.agents.commands import OPERATOR_ID
from mrcomm.live.protocol import WORLD_ID

#: Members of a live team that are not robots.
NOT_ROBOTS = (WORLD_ID, ASSIGNER_ID, OPERATOR_ID)


@dataclass
class LiveProgress:
    """What a live mission has done so far."""

    sim_time: float = 0.0
    tasks_done: int = 0
    #: Process name -> whether its presence was last seen alive (the world's view).
    alive: dict[str, bool] = field(default_factory=dict)

    @property
    def robots_alive(self) -> int:
        return sum(1 for name, up in self.alive.items() if up and name not in NOT_ROBOTS)


class JournalFollower:
    """Follows every journal of a record directory (see the module docstring)."""

    def __init__(self, record_dir: Path) -> None:
        self.record_dir = record_dir
        self.offsets: dict[Path, int] = {}
        self.progress = LiveProgress()

    def poll(self) -> LiveProgress:
        for path in sorted(self.record_dir.glob("*.jsonl")):
            self._read(path)
        return self.progress

    def _read(self, path: Path) -> None:
        start = self.offsets.get(path, 0)
        try:
            with path.open("rb") as stream:
                stream.seek(start)
                chunk = stream.read()
        except OSError:
            return
        end = chunk.rfind(b"\n") + 1  # a line still being written waits for the next poll
        self.offsets[path] = start + end
        is_world = path.name.startswith(f"{WORLD_ID}.")
        for raw in chunk[:end].splitlines():
            # Cheap filters first: most lines are messages and poses, of no interest here.
            if is_world and b'"clock"' in raw:
                line = json.loads(raw)
                self.progress.sim_time = max(self.progress.sim_time, float(line.get("sim", 0.0)))
            elif is_world and b'"presence"' in raw:
                line = json.loads(raw)
                self.progress.alive[str(line["agent"])] = bool(line["alive"])
            elif not is_world and b'"task_completed"' in raw:
                line = json.loads(raw)
                if line.get("k") == "ev" and line.get("label") == "task_completed":
                    self.progress.tasks_done += 1
