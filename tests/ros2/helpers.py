"""Helpers of the ROS 2 tests: the skip of an environment without the ros2 extra, and a
simulated world stepped by the test thread with its robots served over ROS 2."""

from __future__ import annotations

import itertools
import os
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from mrcomm.ros2.runtime import ros2_missing
from mrcomm.run.bodies import RobotBodies
from mrcomm.run.resources import ScenarioResources
from mrcomm.run.wiring import make_bases
from tests import needs

ROOT = Path(__file__).resolve().parents[2]
S1 = ROOT / "data" / "scenarios" / "s1.yaml"
MISSING = ros2_missing()
_WHY = f"ROS 2 not installed here ({MISSING}); make test runs these in .venv-ros2"
needs_ros2 = pytest.mark.skipif(
    MISSING is not None,
    # make test sets MRCOMM_ROS2_ENV=1 in the ROS 2 environment, where ROS 2 must be.
    reason=needs.reason(_WHY) if os.environ.get("MRCOMM_ROS2_ENV") == "1" else _WHY,
)
DT = 0.1
#: A ROS domain per test (from the process's own, see conftest): a test never sees the
#: participants of the one before, which DDS forgets only after a while.
_DOMAINS = itertools.count()


def fresh_domain() -> int:
    return (int(os.environ["ROS_DOMAIN_ID"]) + next(_DOMAINS)) % 200 + 1


class SteppedWorld:
    """S1's simulated robots behind a Nav2Server, advanced one step at a time by the
    test (as the world process's tick loop does: goals in, advance, publish)."""

    def __init__(self, domain_id: int, seed: int = 1) -> None:
        from mrcomm.ros2.nav2_server import Nav2Server

        self.resources = ScenarioResources.load(S1)
        self.bases = make_bases(self.resources, seed)
        self.bodies = RobotBodies(self.bases, self.resources.scenario.assigner)
        self.server = Nav2Server(tuple(self.bases), domain_id=domain_id)
        self.now = 0.0
        self.server.publish(self.now, self.bases)

    def step(self) -> None:
        self.server.apply(self.bases)
        self.bodies.advance(DT, self.now, self.bodies.true_xy())
        self.now = round(self.now + DT, 9)
        self.server.publish(self.now, self.bases)

    def run_until(
        self, done: Callable[[], Any], max_steps: int, spin: Callable[[], None], what: str
    ) -> int:
        """Step (and let the client side spin) until ``done()``; the number of steps."""
        for k in range(max_steps):
            if done():
                return k
            self.step()
            spin()
        raise AssertionError(f"{what}: not after {max_steps} steps")

    def close(self) -> None:
        self.server.close()


def spin_client(executor: Any, wall: float = 0.01) -> None:
    """Let a client executor handle what arrived for up to ``wall`` seconds."""
    deadline = time.monotonic() + wall
    while time.monotonic() < deadline:
        executor.spin_once(timeout_sec=0.002)
