"""Reference files change only through their logged ``--write`` (``rerecord.py``): each
file is what its last logged write wrote (a hand edit, or a write that bypassed the log,
fails here), every write states its reason, and a write that changes nothing or gives no
reason is refused without touching the file."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from . import rerecord
from .golden import GOLDEN_FILE
from .team_golden import TEAM_GOLDEN_FILE


@pytest.mark.parametrize("path", [GOLDEN_FILE, TEAM_GOLDEN_FILE], ids=lambda p: p.name)
def test_each_reference_file_is_its_last_logged_write(path: Path) -> None:
    entries = [e for e in rerecord.load_log() if e["file"] == path.name]
    assert entries, f"{path.name} has never been logged"
    assert entries[-1]["sha256"] == rerecord.file_sha256(path), (
        f"{path.name} differs from its last logged write: re-record it with "
        "`python -m tests.golden.<module> --write --why '...'`"
    )


def test_every_write_says_why() -> None:
    for entry in rerecord.load_log():
        assert len(entry["why"]) >= rerecord.MIN_WHY, entry


def test_a_change_without_a_reason_is_refused(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(rerecord, "LOG_FILE", tmp_path / "log.json")
    path = tmp_path / "ref.json"
    path.write_text(json.dumps({"a": {"mission": {"near_collisions": 3}}}))
    before = path.read_text()
    worse = {"a": {"mission": {"near_collisions": 5}}}
    with pytest.raises(SystemExit, match="--why"):
        rerecord.write_logged(worse, path, None)
    assert path.read_text() == before and not (tmp_path / "log.json").exists()
    rerecord.write_logged(worse, path, "collision radius grew 0.1 m, see the completion runs")
    (entry,) = json.loads((tmp_path / "log.json").read_text())
    assert entry["changed"] == {
        "a": {"before": {"near_collisions": 3}, "after": {"near_collisions": 5}}
    }
    assert entry["sha256"] == rerecord.file_sha256(path)
