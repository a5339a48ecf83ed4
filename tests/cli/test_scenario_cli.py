"""``mrcomm scenario make | tasks | show`` from the command line: files made, bad input
in one line with exit status 2 and nothing written."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

from mrcomm.world.scenario import load_scenario


def mrcomm(capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch,
           *args: str) -> tuple[int, str, str]:  # fmt: skip
    from mrcomm.cli.main import app

    monkeypatch.setattr(sys, "argv", ["mrcomm", *args])
    capsys.readouterr()
    try:
        app()
        code = 0
    except SystemExit as done:
        code = done.code if isinstance(done.code, int) else 0
    out, err = capsys.readouterr()
    return code, out, err


def test_make_show_and_plot(capsys, monkeypatch, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    out = tmp_path / "w30"
    args = ["scenario", "make", "--map", "warehouse", "--size", "40x30", "--robots", "12",
            "--tasks", "24", "--start", "depots", "--assigner", "base",
            "--out", str(out)]  # fmt: skip
    code, stdout, err = mrcomm(capsys, monkeypatch, *args)
    assert code == 0, err
    scenario = load_scenario(out / "w30.yaml")
    assert len(scenario.robots) == 12 and scenario.assigner.kind == "base_station"
    figure = tmp_path / "w30.png"
    code, stdout, err = mrcomm(capsys, monkeypatch, "scenario", "show", str(out / "w30.yaml"),
                               "--plot", str(figure))  # fmt: skip
    assert code == 0, err
    assert "12 robots, 24 tasks" in stdout and figure.stat().st_size > 5000
    code, stdout, err = mrcomm(capsys, monkeypatch, "scenario", "show", str(out))
    assert code == 0 and "12 robots, 24 tasks" in stdout, err  # the directory will do


def test_a_directory_with_files_is_refused(capsys, monkeypatch, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    out = tmp_path / "mine"
    out.mkdir()
    (out / "notes.txt").write_text("keep")
    code, _, err = mrcomm(capsys, monkeypatch, "scenario", "make", "--size", "20x15",
                          "--out", str(out))  # fmt: skip
    assert code == 2 and len(err.strip().splitlines()) == 1, err
    assert "--out: exists and is not an empty directory" in err
    assert sorted(p.name for p in tmp_path.rglob("*")) == ["mine", "notes.txt"]


@pytest.mark.parametrize(
    ("args", "needle"),
    [
        (["--size", "10x"], "--size: expected WIDTHxHEIGHT"),
        (["--size", "nanxnan"], "--size"),
        (["--robots", "0"], "--robots: must be 1-"),
        (["--robots", "many"], "Invalid value for '--robots'"),
        (["--seed", "-1"], "--seed: must be 0 to 2**63-1"),
        (["--robots", "5000", "--size", "20x15"], "5000 robots do not fit"),
        (["--assigner", "robot_999"], "--assigner"),
        (["--map", "moon"], "--map: unknown map"),
    ],
)
def test_bad_make_options(capsys, monkeypatch, tmp_path: Path, args: list[str],  # type: ignore[no-untyped-def]
                          needle: str) -> None:  # fmt: skip
    code, _, err = mrcomm(capsys, monkeypatch, "scenario", "make", "--size", "30x20",
                          *args, "--out", str(tmp_path / "o"))  # fmt: skip
    assert code == 2 and len(err.strip().splitlines()) == 1 and needle in err, err
    assert list(tmp_path.iterdir()) == []


def test_tasks_from_locations_in_round_robin_order(capsys, monkeypatch, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    csv = tmp_path / "spots.csv"
    csv.write_text("x,y\n2.5,5.7\n43,2\n22.2,13.8\n")
    out = tmp_path / "tasks.yaml"
    code, stdout, err = mrcomm(capsys, monkeypatch, "scenario", "tasks", str(csv), "--out",
                               str(out), "--robots", "2")  # fmt: skip
    assert code == 0, err
    assert "robot_1: 1, 3\nrobot_2: 2\n" in stdout  # what the assigner's round robin does
    from mrcomm.world.scenario import load_tasks

    tasks = load_tasks(out)
    assert [(t.task_id, t.x, t.y) for t in tasks] == [
        ("1", 2.5, 5.7),
        ("2", 43.0, 2.0),
        ("3", 22.2, 13.8),
    ]
    bad = tmp_path / "bad.csv"
    bad.write_text("x,y\n1,nan\n")
    code, _, err = mrcomm(capsys, monkeypatch, "scenario", "tasks", str(bad), "--out",
                          str(tmp_path / "t2.yaml"))  # fmt: skip
    assert code == 2 and "location 1: coordinates must be finite" in err
    assert not (tmp_path / "t2.yaml").exists()
