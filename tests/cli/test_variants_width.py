"""``mrcomm variants`` on a narrow terminal: every parameter name (what users type after
``--set``) and every default is printed whole, on one line; the meanings wrap instead.
``--json`` is unchanged by the width."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

from tests.conftest import ROOT


def _variants(columns: int, *args: str) -> str:
    env = {**os.environ, "COLUMNS": str(columns)}
    proc = subprocess.run([sys.executable, "-m", "mrcomm", "variants", *args], cwd=ROOT,
                          env=env, capture_output=True, text=True, timeout=120)  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    return proc.stdout


@pytest.mark.parametrize("columns", [80, 100])
def test_every_parameter_name_is_whole(columns: int) -> None:
    params = [p for row in json.loads(_variants(columns, "--json")) for p in row["parameters"]]
    assert len(params) > 40
    shown = _variants(columns)
    lines = shown.splitlines()
    assert "…" not in shown
    for p in params:
        # The name and its default on one line, as typed: --set KEY=DEFAULT.
        assert any(line.split()[:2] == [p["key"], json.dumps(p["default"])]
                   for line in lines if line.strip()), p["key"]  # fmt: skip
    assert max(map(len, lines)) <= columns


def test_json_does_not_depend_on_the_width() -> None:
    assert _variants(80, "--json") == _variants(200, "--json")
