"""Every mode builds the same agents (the one assembly, ``run/agents.py``).

For every behaviour — the built-ins and the example plugin — with every parameter set
to a value other than its default, the simulation, the console's session, a live agent
process and ``mrcomm agent`` started with the arguments ``mrcomm live`` gives it build
executors made with equal parameters, ranks and options. (Before the one assembly, a
live agent built its executor without the run's parameters: this test failed on every
behaviour.)
"""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any

import pytest
import typer

from mrcomm.cli.main import cli
from mrcomm.live.agent import AgentProcess
from mrcomm.live.launcher import LiveTeam, free_port
from mrcomm.live.settings import LiveSettings
from mrcomm.net.zenoh_config import make_options
from mrcomm.run.config import RunConfig, make_config
from mrcomm.specs import REGISTRY
from mrcomm.testing.assembly import (
    executor_summary,
    live_agent,
    non_default_values,
    simulated_executors,
)
from tests.conftest import S1_PATH

BEHAVIOURS = REGISTRY.names("behaviour")
ROBOTS = ("robot_1", "robot_2")  # robot_2 hosts the task assigner of S1


def varied_config(behaviour: str) -> RunConfig:
    spec = REGISTRY.get("behaviour", behaviour)
    values, missed = non_default_values(spec.params_model())
    assert not missed, f"no other value found for {missed}"
    return make_config(
        None, scenario=S1_PATH, network="ah", threshold="slt", behaviour=behaviour,
        spl=10, seed=7, params={"behaviour": values},
    )  # fmt: skip


def loopback(settings: LiveSettings) -> LiveSettings:
    """The same settings on a session that only listens on loopback (the process is
    built, not run: it needs no peers)."""
    options = make_options(team="parity", listen=["tcp/127.0.0.1:0"])
    return dataclasses.replace(settings, zenoh=options, world=None)


def live_summary(settings: LiveSettings, robot: str) -> dict[str, Any]:
    process = AgentProcess(loopback(settings), robot, incarnation=1)
    try:
        assert process.executor is not None
        summary = executor_summary(process.executor, process.robot_ids)
        if process.assigner is not None:
            summary["assigner_lease"] = _assigner_lease(process.assigner)
        return summary
    finally:
        process._finish()


def _assigner_lease(assigner: Any) -> float | None:
    return None if assigner.aon is None else assigner.aon.lease


def agent_command_summary(
    config: RunConfig, robot: str, record: Path, monkeypatch: pytest.MonkeyPatch
) -> dict[str, Any]:
    """``mrcomm agent`` with the arguments ``mrcomm live`` starts it with: what its
    command line makes of them, built into a live agent process."""
    team = LiveTeam(LiveSettings(config, make_options(team="parity"), record))
    team.ports = {name: free_port("127.0.0.1") for name in team.names}
    made: dict[str, Any] = {}

    def build(settings: LiveSettings, agent: str, incarnation: int | None = None) -> int:
        made.update(live_summary(settings, agent))
        return 0

    monkeypatch.setattr("mrcomm.live.agent_run.run_agent", build)
    try:
        cli(team.command(robot), standalone_mode=False)
    except typer.Exit as done:
        assert done.exit_code == 0, done
    assert made, "mrcomm agent did not start its agent"
    return made


@pytest.mark.parametrize("behaviour", BEHAVIOURS)
def test_every_mode_builds_the_same_executors(
    behaviour: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from mrcomm.console.session import ConsoleSession

    config = varied_config(behaviour)
    simulated = simulated_executors(config)
    console = ConsoleSession(config).mission
    sim_assigner_lease = _assigner_lease(console.assigner)
    defaults = REGISTRY.get("behaviour", behaviour).params_model()().model_dump(mode="json")
    for robot in ROBOTS:
        expected = simulated[robot]
        assert expected["params"] != defaults  # the varied values did reach the executor
        assert executor_summary(console.executors[robot], console.robot_ids) == expected
        live = live_summary(LiveSettings(config, make_options(team="parity"), tmp_path), robot)
        agent = agent_command_summary(config, robot, tmp_path / robot, monkeypatch)
        for made in (live, agent):
            lease = made.pop("assigner_lease", sim_assigner_lease)
            assert lease == sim_assigner_lease
            assert made == expected


def test_the_live_lease_is_a_validated_override(tmp_path: Path) -> None:
    """``--lease`` reaches an AON behaviour's executors and its task assigner as the
    parameter ``aon_lease`` (validated like it), and leaves NB as it is."""
    for behaviour, lease in (("lf", 12.5), ("serried", 12.5), ("nb", None)):
        config = make_config(None, scenario=S1_PATH, behaviour=behaviour)
        settings = LiveSettings(config, make_options(team="parity"), tmp_path, lease=12.5)
        with live_agent(config, "robot_2", tmp_path) as plain:
            assert plain.executor is not None
            before = plain.executor.params
        made = live_summary(settings, "robot_2")
        assert made["params"].get("aon_lease") == lease
        assert made["assigner_lease"] == lease
        assert {k: v for k, v in made["params"].items() if k != "aon_lease"} == {
            k: v for k, v in before.model_dump(mode="json").items() if k != "aon_lease"
        }


def test_a_plugin_that_checks_its_parameter_type_runs_live(tmp_path: Path) -> None:
    """The example plugin reads its own parameter model (it used to be handed NB's
    defaults by a live agent and fail)."""
    config = make_config(
        None, scenario=S1_PATH, behaviour="repeat", params={"behaviour": {"repeats": 4}}
    )
    settings = LiveSettings(config, make_options(team="parity"), tmp_path)
    assert live_summary(settings, "robot_1")["params"]["repeats"] == 4
