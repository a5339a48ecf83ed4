"""Provenance of a run: which MRComm (version, and git commit when it runs from a
checkout), which input files (SHA-256 of the scenario, its map YAML and image, its
task file, and every file a variant parameter names: signal model, RSSI trace) and
which machine produced it. Stored with every run and shown by the report, so a number
in a paper can be traced to the code and the data that made it.

A run's *fingerprint* identifies what determines a simulated result: its configuration
id, seed and input hashes. The same fingerprint means the same result, so a second
copy is not stored (see :mod:`mrcomm.experiment.adhoc`).
"""

from __future__ import annotations

import functools
import hashlib
import json
import os
import platform
import subprocess
from pathlib import Path
from typing import Any

import yaml

import mrcomm
from mrcomm.run.config import RUN_KINDS, RunConfig

#: Hex digits kept of each SHA-256 (64 bits: collisions are not a concern here).
HASH_DIGITS = 16


@functools.lru_cache(maxsize=256)
def _file_hash(path: str, size: int, mtime_ns: int) -> str:
    digest = hashlib.sha256()
    with open(path, "rb") as stream:
        for block in iter(lambda: stream.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()[:HASH_DIGITS]


def file_hash(path: Path) -> str:
    """SHA-256 (first 16 hex digits) of a file; cached while its size and time stay."""
    info = path.stat()
    return _file_hash(str(path.resolve()), info.st_size, info.st_mtime_ns)


def input_files(config: RunConfig) -> dict[str, Path]:
    """Every file a run reads, by role: scenario, map (YAML and image), tasks, and
    the files named by variant parameters (``threshold.model`` ...)."""
    files: dict[str, Path] = {"scenario": Path(config.scenario)}
    try:
        scenario = yaml.safe_load(Path(config.scenario).read_text()) or {}
        map_yaml = _near(config.scenario, str(scenario["map"]))
        files["map"] = map_yaml
        files["tasks"] = _near(config.scenario, str(scenario["tasks"]))
        image = (yaml.safe_load(map_yaml.read_text()) or {}).get("image")
        if image:
            files["map_image"] = _near(map_yaml, str(image))
    except (OSError, KeyError, TypeError, yaml.YAMLError):
        pass  # a scenario that loaded for the run is well-formed; nothing more to add
    for kind in RUN_KINDS:
        params = config.variant_params(kind)
        for key, value in params.model_dump().items():
            if isinstance(value, Path):
                files[f"{kind}.{key}"] = value
        # Files a parameter names indirectly (a radio profile given by name).
        named = getattr(params, "input_files", None)
        if callable(named):
            files.update({f"{kind}.{key}": path for key, path in named().items()})
    return files


def _near(base: Path | str, name: str) -> Path:
    path = Path(name).expanduser()
    return path if path.is_absolute() else Path(os.path.normpath(Path(base).parent / path))


def input_hashes(config: RunConfig) -> dict[str, str]:
    """Role -> SHA-256 prefix of each input file ("missing" if it cannot be read)."""
    out = {}
    for role, path in input_files(config).items():
        try:
            out[role] = file_hash(path)
        except OSError:
            out[role] = "missing"
    return out


@functools.lru_cache(maxsize=1)
def git_commit() -> str:
    """The commit of the checkout MRComm runs from ("+dirty" with local changes);
    empty when installed from a package."""
    source = Path(mrcomm.__file__).resolve().parent
    try:
        top = subprocess.run(
            ["git", "-C", str(source), "rev-parse", "--show-toplevel", "HEAD"],
            capture_output=True,
            text=True,
            timeout=10,
            check=True,
        ).stdout.split()
        if len(top) != 2 or not (source.is_relative_to(top[0])):
            return ""
        dirty = subprocess.run(
            ["git", "-C", top[0], "status", "--porcelain", "--untracked-files=no"],
            capture_output=True,
            text=True,
            timeout=10,
            check=True,
        ).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        return ""
    return top[1] + ("+dirty" if dirty else "")


@functools.lru_cache(maxsize=1)
def machine() -> str:
    """Host name, OS and processor count of the machine running this process."""
    return f"{platform.node()} ({platform.system()} {platform.machine()}, {os.cpu_count()} CPUs)"


def provenance(config: RunConfig) -> dict[str, Any]:
    """What is stored with each run (see the module docstring)."""
    return {
        "mrcomm_version": mrcomm.__version__,
        "git_commit": git_commit(),
        "machine": machine(),
        "input_hashes": input_hashes(config),
    }


def fingerprint(config_id: str, seed: int, hashes: dict[str, str]) -> str:
    """What determines a simulated run's result (configuration id, seed, inputs)."""
    content = json.dumps([config_id, seed, sorted(hashes.items())], separators=(",", ":"))
    return hashlib.sha256(content.encode()).hexdigest()[:HASH_DIGITS]
