"""Copy a scenario's files into a directory of their own, to edit them: the scenario,
its task file, its map (YAML and image), side by side, the scenario's ``map`` and
``tasks`` (and the map's ``image``) rewritten to the copies. Comments are kept; the
copy is loaded and checked before it is moved into place."""

from __future__ import annotations

import re
import shutil
from pathlib import Path

from mrcomm.fileio import staged_directory
from mrcomm.world.scenario import load_scenario
from mrcomm.world.yamlfile import read_yaml


def copy_scenario(source: Path, out: Path) -> Path:
    """Copy the scenario file ``source`` and what it names into ``out`` (absent or
    empty); returns the copied scenario file."""
    scenario = load_scenario(source)  # a broken source fails here, before any copy
    map_file, tasks_file = scenario.map_path, scenario.tasks_path
    image_name = str(read_yaml(map_file)["image"])
    image_file = map_file.parent / image_name
    with staged_directory(out, "DIR") as staging:
        text = source.read_text(encoding="utf-8")
        text = _set_line(text, "map", map_file.name)
        text = _set_line(text, "tasks", tasks_file.name)
        (staging / source.name).write_text(text, encoding="utf-8")
        shutil.copyfile(tasks_file, staging / tasks_file.name)
        map_text = _set_line(map_file.read_text(encoding="utf-8"), "image", image_file.name)
        (staging / map_file.name).write_text(map_text, encoding="utf-8")
        shutil.copyfile(image_file, staging / image_file.name)
        copied = load_scenario(staging / source.name)
        assert copied.tasks == scenario.tasks and copied.robots == scenario.robots
    return out / source.name


def _set_line(text: str, key: str, value: str) -> str:
    """``text`` with its top-level ``key: ...`` line set to ``value``."""
    pattern = re.compile(rf"^{key}:.*$", re.MULTILINE)
    if not pattern.search(text):
        raise ValueError(f"no top-level '{key}:' line")
    return pattern.sub(f"{key}: {value}", text, count=1)
