"""Helpers of the live tests: Zenoh peers on loopback, waiting on conditions, S1-based
short scenarios, reading a process's journal."""

from __future__ import annotations

import json
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any, TypeVar

import yaml

from mrcomm.live.launcher import free_port
from mrcomm.net.zenoh_config import ZenohOptions, make_options
from mrcomm.net.zenoh_node import Incoming, ZenohNode

ROOT = Path(__file__).resolve().parents[2]
S1 = ROOT / "data" / "scenarios" / "s1.yaml"

T = TypeVar("T")


def wait_for(condition: Callable[[], T | None], timeout: float, what: str) -> T:
    """Poll ``condition`` until it returns something truthy, or fail after ``timeout``."""
    deadline = time.monotonic() + timeout
    while True:
        value = condition()
        if value:
            return value
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out after {timeout:g} s waiting for {what}")
        time.sleep(0.01)  # polling a condition with a deadline, not waiting for a guess


def mesh_options(count: int, team: str = "t", **kwargs: object) -> list[ZenohOptions]:
    """Options for ``count`` peers on loopback, each listening on its own port and
    connecting to every other one."""
    ports = [free_port("127.0.0.1") for _ in range(count)]
    out = []
    for i, port in enumerate(ports):
        others = [f"tcp/127.0.0.1:{p}" for j, p in enumerate(ports) if j != i]
        out.append(
            make_options(
                team=team,
                listen=[f"tcp/127.0.0.1:{port}"],
                connect=others,
                **kwargs,  # type: ignore[arg-type]
            )
        )
    return out


@contextmanager
def nodes(options: list[ZenohOptions]) -> Iterator[list[ZenohNode]]:
    opened = [ZenohNode(o) for o in options]
    try:
        yield opened
    finally:
        for node in opened:
            node.close()


def drain(
    node: ZenohNode, until: Callable[[list[Incoming]], bool], timeout: float
) -> list[Incoming]:
    """Collect a node's incoming samples until ``until(items)`` holds."""
    items: list[Incoming] = []
    deadline = time.monotonic() + timeout
    while not until(items):
        remaining = deadline - time.monotonic()
        if remaining <= 0:
            raise AssertionError(f"timed out after {timeout:g} s; got {len(items)} samples")
        item = node.poll(min(remaining, 0.05))
        if item is not None:
            items.append(item)
    return items


def s1_variant(directory: Path, name: str, tasks: list[dict[str, Any]]) -> Path:
    """S1's map, team and start with other tasks (written next to the scenario)."""
    (directory / f"{name}_tasks.yaml").write_text(yaml.safe_dump(tasks))
    scenario = yaml.safe_load(S1.read_text())
    scenario.update(
        name=name,
        map=str((ROOT / "data" / "maps" / "office.yaml").resolve()),
        tasks=f"{name}_tasks.yaml",
    )
    path = directory / f"{name}.yaml"
    path.write_text(yaml.safe_dump(scenario))
    return path


def journal(record_dir: Path, process: str) -> list[dict[str, Any]]:
    """Every complete line of a process's journals (all incarnations, in order)."""
    lines: list[dict[str, Any]] = []
    for path in sorted(record_dir.glob(f"{process}.*.jsonl")):
        for raw in path.read_text().splitlines():
            try:
                lines.append(json.loads(raw))
            except json.JSONDecodeError:
                break  # a line being written
    return lines
