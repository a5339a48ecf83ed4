"""The data that ships with MRComm, and the names users give it.

The bundled data — the scenarios (S1–S4, campus1000) with their maps and tasks, the office
map, the SSD signal model and its calibration set, the ESD RSSI trace, the reference
experiments and the Foxglove layout — is one tree: the repository's ``data/`` directory,
which the wheel carries as the package's ``mrcomm/data``. :func:`data_root` finds it in
either place, so a source checkout, an editable install and an installed wheel read the
same files.

Bundled scenarios, experiments and traces can be named instead of given as paths
(``mrcomm run s1``, ``mrcomm sweep demo``, ``--rssi-trace s1_synthetic_esd``): a
name that is not an existing file or directory and names a bundled one is that one.
"""

from __future__ import annotations

from pathlib import Path

import mrcomm
from mrcomm.errors import InputError

#: The kinds of bundled files that can be named, and the folder each is in.
FOLDERS = {"scenario": "scenarios", "experiment": "experiments", "trace": "traces"}


def data_root() -> Path:
    """The bundled data's directory: the installed package's ``data`` (a wheel), else
    the source checkout's ``data/`` (a checkout or an editable install)."""
    package = Path(mrcomm.__file__).resolve().parent
    for candidate in (package / "data", package.parents[1] / "data"):
        if (candidate / "scenarios").is_dir():
            return candidate
    raise InputError(
        "MRComm's bundled data is missing from this installation (reinstall the package)",
        file=package / "data",
    )


def data_file(relpath: str | Path) -> Path:
    """A bundled file by its path inside the data tree (``signal/default_model.json``)."""
    path = data_root() / relpath
    if not path.is_file():
        raise InputError("bundled file not found in this installation", file=path)
    return path


def bundled(kind: str) -> dict[str, Path]:
    """Name → file of the bundled scenarios, experiments or traces. A scenario is a
    YAML at the top of ``scenarios/`` (``s1``) or the one named after its directory
    (``s2/s2.yaml``); task files and maps are not scenarios."""
    folder = data_root() / FOLDERS[kind]
    if kind == "scenario":
        files = [p for p in folder.glob("*.yaml") if not p.stem.endswith("_tasks")]
        named = [d / f"{d.name}.yaml" for d in folder.iterdir() if d.is_dir()]
        files += [p for p in named if p.is_file()]
    elif kind == "experiment":
        files = list(folder.glob("*.yaml"))
    else:
        files = list(folder.glob("*.csv"))
    return {p.stem: p for p in sorted(files, key=lambda p: p.stem)}


def resolve(given: Path, kind: str) -> Path:
    """``given`` itself when it exists or looks like a path; the bundled file when it
    is a bundled name (``s1``); otherwise ``given`` (its loader reports it missing)."""
    if given.exists() or len(given.parts) != 1 or given.suffix:
        return given
    return bundled(kind).get(str(given), given)
