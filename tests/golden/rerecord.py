"""The log of every re-recording of a reference file (``rerecords.json``).

A reference output is re-recorded only for a stated behaviour change: ``--write`` on a
reference file that changes a case needs ``--why "what changed in the behaviour and why
the new results are right"``; the log keeps that reason with each changed case's
headline figures before and after (success, tasks, execution time, near collisions), so
a worse figure cannot be absorbed silently, and the file's SHA-256 after the write
(``test_rerecords.py`` fails when a reference file differs from its last logged write:
edited by hand, or written without the log).
"""

from __future__ import annotations

import datetime as dt
import hashlib
import json
from pathlib import Path
from typing import Any

LOG_FILE = Path(__file__).with_name("rerecords.json")
#: What the log shows of a changed case (from its summary's mission part, if it has one).
HEADLINE = ("successful", "tasks_completed", "execution_phase_time", "near_collisions",
            "sim_time_s")  # fmt: skip
MIN_WHY = 30


def headline(case: dict[str, Any]) -> dict[str, Any]:
    source = case.get("mission", case)
    return {key: source[key] for key in HEADLINE if key in source}


def file_sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def load_log() -> list[dict[str, Any]]:
    return json.loads(LOG_FILE.read_text()) if LOG_FILE.exists() else []


def write_logged(results: dict[str, Any], path: Path, why: str | None) -> None:
    """Write ``results`` into the reference file ``path`` and log what changed."""
    old = json.loads(path.read_text()) if path.exists() else {}
    changed = {
        key: {"before": headline(old[key]) if key in old else None, "after": headline(value)}
        for key, value in results.items()
        if old.get(key) != value
    }
    removed = sorted(set(old) - set(results))
    if not changed and not removed:
        print(f"{path.name}: every case as recorded; nothing written")
        return
    if why is None or len(why.strip()) < MIN_WHY:
        raise SystemExit(
            f"{path.name}: {len(changed)} case(s) change; re-record only for a stated behaviour "
            f'change: --why "what changed and why the new results are right" '
            f"(at least {MIN_WHY} characters)"
        )
    path.write_text(json.dumps(results, indent=1, sort_keys=True) + "\n")
    log = load_log()
    log.append({
        "date": dt.date.today().isoformat(),
        "file": path.name,
        "why": why.strip(),
        "changed": changed,
        "removed": removed,
        "sha256": file_sha256(path),
    })  # fmt: skip
    LOG_FILE.write_text(json.dumps(log, indent=1, ensure_ascii=False) + "\n")
    print(f"wrote {len(results)} cases to {path} ({len(changed)} changed; logged)")
