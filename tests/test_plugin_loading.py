"""A plugin that fails to load breaks no command that does not use it.

The plugins here are real installed distributions: a ``.dist-info`` folder with an
``entry_points.txt`` on ``PYTHONPATH``, found by ``importlib.metadata`` as pip's are.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from tests.conftest import S1_PATH


def install_plugin(where: Path, name: str, entry: str, module: str | None = None) -> None:
    """A distribution ``name`` registering ``entry`` (``behaviour.x = module:SPEC``),
    with ``module``'s source when given."""
    info = where / f"{name}-0.1.dist-info"
    info.mkdir(parents=True)
    (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {name}\nVersion: 0.1\n")
    (info / "entry_points.txt").write_text(f"[mrcomm.variants]\n{entry}\n")
    if module is not None:
        target, _, _ = entry.partition("=")[2].strip().partition(":")
        (where / f"{target}.py").write_text(module)


def mrcomm(path: Path, *args: str) -> subprocess.CompletedProcess[str]:
    env = {**os.environ, "PYTHONPATH": str(path)}
    code = "from mrcomm.cli.main import app; app()"
    return subprocess.run(
        [sys.executable, "-c", code, *args],
        capture_output=True,
        text=True,
        timeout=300,
        env=env,
    )


@pytest.fixture(scope="module")
def broken(tmp_path_factory: pytest.TempPathFactory) -> Path:
    where = tmp_path_factory.mktemp("plugins")
    install_plugin(where, "crashing_plugin", "behaviour.crash = crashing:SPEC", "1 / 0\n")
    install_plugin(where, "missing_plugin", "threshold.gone = no_such_module:SPEC")
    install_plugin(where, "odd_plugin", "utility.odd = odd:SPEC", "SPEC = 42\n")
    return where


def test_a_broken_plugin_is_skipped_with_one_warning_line(broken: Path) -> None:
    proc = mrcomm(broken, "variants", "behaviour")
    assert proc.returncode == 0, proc.stderr
    assert "nb" in proc.stdout and "lf" in proc.stdout
    warnings = [line for line in proc.stderr.splitlines() if line.startswith("warning:")]
    assert len(warnings) == 3, proc.stderr
    assert any("behaviour.crash" in w and "ZeroDivisionError" in w for w in warnings)
    assert any("threshold.gone" in w and "no_such_module" in w for w in warnings)
    assert any("utility.odd" in w and "not a VariantSpec" in w for w in warnings)
    assert "Traceback" not in proc.stderr


def test_a_run_that_does_not_use_it_runs(broken: Path) -> None:
    proc = mrcomm(
        broken, "run", str(S1_PATH), "--network", "wlan", "--max-time", "20", "--json",
        "--set", "behaviour.pose_period=0.5",
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    assert "--set" not in proc.stderr


def test_using_it_is_an_error_naming_it(broken: Path) -> None:
    proc = mrcomm(broken, "run", str(S1_PATH), "--behaviour", "crash", "--max-time", "5")
    assert proc.returncode == 2
    last = proc.stderr.strip().splitlines()[-1]
    assert "plugin behaviour.crash = crashing:SPEC (from crashing_plugin) failed to load" in last
    assert "Traceback" not in proc.stderr
