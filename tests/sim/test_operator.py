"""The operator in the loop, in whole simulated missions: its commands go with AON to
the robots and the task assigner under loss and range cuts and are recorded; a task
reassigned is done and reported by its new owner; a robot sent back for a task whose
status was lost ends the mission successful; an operator out of range hears nothing
until a robot comes within range; a bad operator file is one line before any run."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import pytest

from mrcomm.agents.commands import OPERATOR_ID
from mrcomm.errors import InputError
from mrcomm.run.config import make_config
from mrcomm.run.operator_plan import OperatorPlan, PlannedCommand, load_operator_plan
from mrcomm.run.resources import ScenarioResources
from mrcomm.sim.mission import Mission, run_mission
from tests.conftest import ROOT, S1_PATH

EVERYONE = ["assigner", "operator", "robot_1", "robot_2", "robot_3"]


def _config(network: str, behaviour: str, spl: float, seed: int, **fields: Any) -> Any:
    return make_config(
        None, scenario=S1_PATH, network=network, behaviour=behaviour, spl=spl, seed=seed,
        **fields,
    )  # fmt: skip


def _plan(*commands: dict[str, Any], placement: str = "base") -> OperatorPlan:
    return OperatorPlan(placement=placement, commands=tuple(PlannedCommand(**c) for c in commands))


@pytest.mark.parametrize(("behaviour", "spl"), [("nb", 0), ("lf", 50)])
def test_a_reassigned_task_is_done_and_reported_by_its_new_owner(
    behaviour: str, spl: float, s1_resources: ScenarioResources
) -> None:
    # Task 4 is robot_1's (round-robin); at 20 s, out of range of robot_1 on AH (and
    # for LF with half the packets lost), the operator gives it to robot_2, which hosts
    # the task assigner (so even NB's one status reaches it).
    config = _config("ah", behaviour, spl, 1, threshold="slt")
    plan = _plan({"at": 20, "command": "reassign", "task": "4", "robot": "robot_2"})
    mission = Mission(config, s1_resources, plan)
    result = mission.run()
    done = {rid: [e.data["task_id"] for e in tl.events if e.label == "task_completed"]
            for rid, tl in result.timelines.items()}  # fmt: skip
    assert "4" in done["robot_2"] and "4" not in done["robot_1"]
    assert ("4", "robot_2") in mission.assigner.success_received
    assert result.robots["robot_2"]["tasks_assigned"] == 3
    assert result.robots["robot_1"]["tasks_assigned"] == 2
    (command,) = result.summary()["operator"]["commands"]
    assert command["former"] == "robot_1" and command["time"] == 20.0
    assert sorted(command["acknowledged"]) == EVERYONE and command["finished_at"] > 20.0
    # It took AON: re-sends over the range cut (NB's robots spread) or the losses.
    counts = result.messages["command"]
    assert counts["sent"] > 5
    assert counts["dropped_loss"] > 0 if spl else counts["dropped_range"] > 0


def test_a_robot_sent_back_for_a_lost_status_makes_the_mission_successful(
    s1_resources: ScenarioResources,
) -> None:
    # NB sends each status once: at SPL 50, seed 3 loses four of them.
    config = _config("wlan", "nb", 50, 3)
    plain = run_mission(config, s1_resources)
    lost = plain.mission["failed_tasks"]
    assert lost == ["1", "3", "4", "7"] and not plain.mission["successful"]
    # The operator sees them missing and sends their robots back, three times over.
    plan = _plan(
        *({"at": at, "command": "redo", "task": t} for at in (200, 300, 400) for t in lost)
    )
    result = run_mission(config, s1_resources, plan)
    assert result.mission["successful"] and result.mission["failed_tasks"] == []
    assert len(result.summary()["operator"]["commands"]) == 12


def test_a_paused_robot_stands_still_until_resumed(s1_resources: ScenarioResources) -> None:
    config = _config("wlan", "nb", 0, 1)
    plan = _plan(
        {"at": 30, "command": "pause", "robot": "robot_3"},
        {"at": 60, "command": "resume", "robot": "robot_3"},
    )
    mission = Mission(config, s1_resources, plan)
    trail: list[tuple[float, float, float]] = []
    while not mission.done:
        mission.step()
        pose = mission.bases["robot_3"].true_pose
        trail.append((mission.now, pose.x, pose.y))
    paused = [(x, y) for t, x, y in trail if 32.0 <= t <= 60.0]  # stopped within 2 s
    assert max(math.dist(paused[0], p) for p in paused) < 0.05
    after = [(x, y) for t, x, y in trail if 62.0 <= t <= 70.0]
    assert math.dist(after[0], after[-1]) > 1.0  # on its way again
    assert mission.result().mission["successful"]


def test_an_operator_out_of_range_hears_nothing_until_a_robot_comes_close(
    tmp_path: Path,
) -> None:
    # S1 with the task assigner (and the operator with it) at a base station at task
    # 1, 14 m from the robots' start room: out of AH's 8 m range at first.
    scenario = tmp_path / "s1_base.yaml"
    text = (S1_PATH.read_text().replace("assigner: {host: robot_2}",
            "assigner: {kind: base_station, position: {x: 2.5, y: 5.7}}"))  # fmt: skip
    text = text.replace("map: ../maps/office.yaml", f"map: {ROOT / 'data/maps/office.yaml'}")
    text = text.replace("tasks: s1_tasks.yaml", f"tasks: {S1_PATH.parent / 's1_tasks.yaml'}")
    scenario.write_text(text)
    config = make_config(None, scenario=scenario, network="ah", behaviour="nb", seed=1)
    mission = Mission(config, None, _plan({"at": 1, "command": "pause", "robot": "robot_1"}))
    operator = mission.operator
    assert operator is not None
    op = mission.node_ids.index(OPERATOR_ID)
    ever_in_range: set[str] = set()
    silent_steps = 0
    while not mission.done and mission.now < 120:
        mission.step()
        links = mission.last_links
        assert links is not None
        for i, robot in enumerate(mission.robot_ids):
            if links.connected[i, op]:
                ever_in_range.add(robot)
        # Whatever reached the operator came from a robot that was in its range.
        assert set(operator.poses) <= ever_in_range
        silent_steps += not operator.poses
    assert silent_steps > 50  # more than 5 s without a word
    assert operator.poses  # then robot_1 drove to task 1, at the base station
    # The pause reached robot_1 only once it came within range.
    (record,) = operator.log
    assert "robot_1" in record.acknowledged


@pytest.mark.parametrize(
    ("plan", "message"),
    [
        ("placement: nowhere\n", "placement: must be one of base, virtual, robot_1"),
        ("commands: [{at: 5, command: fly, robot: robot_1}]\n", "commands[0]: unknown command"),
        ("commands: [{at: 5, command: reassign, task: '99', robot: robot_2}]\n",
         "commands[0]: unknown task '99'"),
        ("commands: [{at: 5, command: reassign, task: '4', robot: robot_1}]\n",
         "commands[0]: task '4' is robot_1's already"),
        ("commands: [{at: 5, command: pause, robot: robot_9}]\n", "unknown robot 'robot_9'"),
        ("commands: [{at: 5, command: add, task: x, x: 0.1, y: 0.1, robot: robot_1}]\n",
         "commands[0]: (0.1, 0.1) is not free space"),
        ("commands: [{at: 5, command: add, task: '1', x: 5.0, y: 5.7, robot: robot_1}]\n",
         "task '1' exists already"),
        ("commands: [{at: -1, command: pause, robot: robot_1}]\n", "commands[0].at"),
        ("commands: [{at: 9, command: reassign, task: '4', robot: robot_2},"
         " {at: 5, command: reassign, task: '4', robot: robot_2}]\n",
         "commands[0]: task '4' is robot_2's already"),  # checked in time order
    ],
)  # fmt: skip
def test_a_bad_operator_file_is_one_line_naming_the_command(
    plan: str, message: str, tmp_path: Path, s1_resources: ScenarioResources
) -> None:
    path = tmp_path / "operator.yaml"
    path.write_text(plan)
    with pytest.raises(InputError) as err:
        load_operator_plan(path, s1_resources.scenario)
    line = err.value.one_line()
    assert "\n" not in line and str(path) in line and message in line


def test_the_operators_commands_are_in_the_recording(
    s1_resources: ScenarioResources, tmp_path: Path
) -> None:
    from mcap.reader import make_reader
    from mcap_protobuf.decoder import DecoderFactory

    from mrcomm.experiment.recording import run_and_record

    plan = _plan({"at": 10, "command": "pause", "robot": "robot_1"},
                 {"at": 20, "command": "resume", "robot": "robot_1"})  # fmt: skip
    path = tmp_path / "run.mcap"
    run_and_record(_config("wlan", "nb", 0, 1), s1_resources, path, operator=plan)
    with path.open("rb") as stream:
        reader = make_reader(stream, decoder_factories=[DecoderFactory()])
        logs = [(d.name, d.message) for *_, d in reader.iter_decoded_messages(topics=["/events"])]
    assert ("operator", "command_sent command=pause robot=robot_1 task=") in logs
    assert ("robot_1", "operator_command command=resume") in logs


def test_the_cli_refuses_a_bad_operator_file_before_running(
    capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    from tests.cli.test_report_cli import in_process

    bad = tmp_path / "operator.yaml"
    bad.write_text("commands: [{at: 5, command: redo, task: '77'}]\n")
    out = tmp_path / "out"
    out.mkdir()
    args = ["run", str(S1_PATH), "--operator", str(bad), "--record", str(out / "r.mcap")]
    outcome = in_process(capsys, monkeypatch, *args)
    assert outcome.returncode == 2
    assert outcome.stderr.strip() == f"mrcomm: error: {bad}: commands[0]: unknown task '77'"
    assert list(out.iterdir()) == []


@pytest.mark.parametrize("behaviour", ["nb", "lf", "lf-wait", "rps", "serried"])
def test_every_behaviour_acts_on_the_operators_commands(
    behaviour: str, s1_resources: ScenarioResources
) -> None:
    # Task 7 is robot_1's; the operator gives it to robot_3 and stops robot_2 for 20 s
    # (WLAN: every status arrives, so each mission must succeed).
    config = _config("wlan", behaviour, 0, 1, threshold="slt")
    plan = _plan(
        {"at": 15, "command": "reassign", "task": "7", "robot": "robot_3"},
        {"at": 20, "command": "pause", "robot": "robot_2"},
        {"at": 40, "command": "resume", "robot": "robot_2"},
    )
    mission = Mission(config, s1_resources, plan)
    result = mission.run()
    done = {rid: [e.data["task_id"] for e in tl.events if e.label == "task_completed"]
            for rid, tl in result.timelines.items()}  # fmt: skip
    assert "7" in done["robot_3"] and "7" not in done["robot_1"]
    assert result.mission["successful"], result.mission["failed_tasks"]
    assert all(c["finished_at"] is not None for c in result.operator["commands"])


def test_a_behaviour_that_refuses_reassignment_refuses_it_before_the_run(
    s1_resources: ScenarioResources, tmp_path: Path
) -> None:
    import dataclasses

    from mrcomm.specs import REGISTRY, get_spec

    fixed = dataclasses.replace(get_spec("behaviour", "nb"), name="nb-fixed",
                                accepts_reassignment=False)  # fmt: skip
    path = tmp_path / "operator.yaml"
    path.write_text("commands: [{at: 5, command: reassign, task: '4', robot: robot_2}]\n")
    with REGISTRY.registered(fixed):
        with pytest.raises(InputError, match=r"commands\[0\]: the behaviour does not accept"):
            load_operator_plan(path, s1_resources.scenario, reassignable=False)
        # Sending a robot back and pausing still apply.
        config = _config("wlan", "nb-fixed", 0, 1)
        plan = _plan({"at": 5, "command": "pause", "robot": "robot_1"},
                     {"at": 9, "command": "resume", "robot": "robot_1"})  # fmt: skip
        mission = Mission(config, s1_resources, plan)
        assert mission.operator is not None
        with pytest.raises(ValueError, match="does not accept add"):
            mission.operator.command("add", "robot_1", "x", (5.0, 5.7))
        assert mission.run().mission["successful"]


def test_a_confirmed_task_is_known_done_but_still_counted_as_a_lost_status(
    s1_resources: ScenarioResources,
) -> None:
    # WLAN · NB · SPL 50, seed 3 loses the statuses of tasks 1, 3, 4 and 7.
    plan = _plan({"at": 200, "command": "confirm", "task": "4"})
    mission = Mission(_config("wlan", "nb", 50, 3), s1_resources, plan)
    result = mission.run()
    assert result.operator["confirmed"] == ["4"]
    assert ("4", "robot_1") in mission.assigner.confirmed
    assert "4" in result.mission["failed_tasks"]  # communication still lost it
    assert all("4" in e.known_done for e in mission.executors.values())


@pytest.mark.parametrize(("placement", "heard_all_along"), [("virtual", True), ("base", False)])
def test_a_virtual_operator_is_never_out_of_range(
    placement: str, heard_all_along: bool, s1_resources: ScenarioResources
) -> None:
    # AH: the robots drive out of each other's (and the base's) range; a virtual
    # operator still hears every pose, one with the task assigner does not.
    mission = Mission(_config("ah", "nb", 0, 1), s1_resources, _plan(placement=placement))
    operator = mission.operator
    assert operator is not None
    oldest = 0.0
    while mission.now < 120:
        mission.step()
        if mission.now > 5:
            oldest = max(oldest, *(mission.now - p.stamp for p in operator.poses.values()))
    assert (oldest < 1.0) is heard_all_along


def test_the_operators_commands_are_stored_with_the_run(
    s1_resources: ScenarioResources, tmp_path: Path
) -> None:
    import json

    import duckdb

    from mrcomm.experiment.adhoc import store_result

    plan = _plan({"at": 15, "command": "reassign", "task": "7", "robot": "robot_3"})
    result = run_mission(_config("wlan", "nb", 0, 1), s1_resources, plan)
    db = tmp_path / "runs.duckdb"
    store_result(db, result, experiment="operator")
    with duckdb.connect(str(db), read_only=True) as con:
        rows = con.execute(
            "SELECT robot, t, label, data FROM events WHERE label IN "
            "('command_sent', 'operator_command') ORDER BY t, robot"
        ).fetchall()
    sent = [r for r in rows if r[0] == "operator"]
    assert len(sent) == 1 and sent[0][1] == 15.0
    data = json.loads(sent[0][3])
    assert data["command"] == "reassign" and data["task_id"] == "7" and data["finished_at"]
    assert {r[0] for r in rows if r[2] == "operator_command"} == {"robot_1", "robot_3"}


def test_runs_with_other_operator_commands_are_not_the_same_run(
    s1_resources: ScenarioResources, tmp_path: Path
) -> None:
    from mrcomm.experiment.adhoc import store_result

    db = tmp_path / "runs.duckdb"
    config = _config("wlan", "nb", 0, 1)
    plain = store_result(db, run_mission(config, s1_resources))
    plan = _plan({"at": 15, "command": "pause", "robot": "robot_3"},
                 {"at": 25, "command": "resume", "robot": "robot_3"})  # fmt: skip
    steered = store_result(db, run_mission(config, s1_resources, plan))
    again = store_result(db, run_mission(config, s1_resources, plan))
    assert plain.new and steered.new and steered.run_id != plain.run_id
    assert not again.new and again.run_id == steered.run_id  # the same plan: the same run
