"""The ``mrcomm`` command itself: ``--version``, a ``--help`` that imports no command
(so it answers at once: the wall time is measured in benchmarks/cli_help.py), every
listed command loads and has help, and Ctrl-C ends a command with one line."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

import mrcomm
from mrcomm.cli.main import COMMANDS, LazyGroup, cli
from tests.cli.test_report_cli import in_process

PROBE = """
import json, sys
from mrcomm.cli.main import app
sys.argv = ["mrcomm", *sys.argv[1:]]
try:
    app()
except SystemExit:
    pass
heavy = [m for m in ("numpy", "scipy", "pandas", "matplotlib", "duckdb", "zenoh", "pydantic")
         if m in sys.modules]
print(json.dumps(heavy), file=sys.stderr)
"""


def test_version(capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch) -> None:
    out = in_process(capsys, monkeypatch, "--version")
    assert out.returncode == 0 and out.stdout == f"mrcomm {mrcomm.__version__}\n"


@pytest.mark.parametrize("args", [["--help"], ["--version"], []])
def test_top_level_help_imports_no_command(args: list[str]) -> None:
    proc = subprocess.run(
        [sys.executable, "-c", PROBE, *args], capture_output=True, text=True, timeout=60
    )
    heavy = json.loads(proc.stderr.strip().splitlines()[-1])
    assert heavy == [], f"mrcomm {' '.join(args)} imported {heavy}"
    if args != ["--version"]:
        for name, entry in COMMANDS.items():
            assert f"  {name} " in proc.stdout and entry.summary in proc.stdout


def test_every_listed_command_loads_with_help(
    capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    group = typer_group()
    for name in COMMANDS:
        assert group.get_command(None, name) is not None, name
        out = in_process(capsys, monkeypatch, name, "--help")
        assert out.returncode == 0 and f"Usage: mrcomm {name}" in out.stdout, name
        assert "<bool>" not in out.stdout  # flags show no value placeholder


def typer_group() -> LazyGroup:
    import typer

    group = typer.main.get_command(cli)
    assert isinstance(group, LazyGroup)
    return group


def test_ctrl_c_ends_with_one_line(
    capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    import mrcomm.cli.run_cmd

    def interrupted(*_: object, **__: object) -> None:
        raise KeyboardInterrupt

    monkeypatch.setattr(mrcomm.cli.run_cmd, "run_mission", interrupted)
    out = in_process(capsys, monkeypatch, "run", "data/scenarios/s1.yaml")
    assert out.returncode == 130 and out.stderr == "mrcomm: interrupted\n"
