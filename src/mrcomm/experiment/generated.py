"""Team size as a factor: an experiment whose scenario is a generator spec.

::

    scenario:
      generate: {map: warehouse, size: 80x50, start: scattered, assigner: base, seed: 1}
      robots: [3, 10, 30]          # one scenario per team size
      tasks_per_robot: 2           # or tasks: 60 (the same for every size)

expands into one generated scenario per team size (``mrcomm scenario make`` with these
options), so a study can ask how behaviours scale. The scenarios are made once into
``generated/`` next to the schema file, one directory per size named by its options,
and reused afterwards: the same options give the same bytes, and a directory whose
command differs from the spec, or whose files were changed since they were made (their
SHA-256 against the ``MANIFEST`` written with them), is refused rather than silently
used: runs of two different scenarios would be stored under one configuration id.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import pydantic
from pydantic import BaseModel, ConfigDict, Field

from mrcomm.errors import InputError
from mrcomm.fileio import atomic_write_text
from mrcomm.run.provenance import file_hash
from mrcomm.run.resources import checked_scenario, planning_reach
from mrcomm.world.generate.make import Request, make_scenario, parse_size
from mrcomm.world.yamlfile import validation_error

GENERATED_DIR = "generated"
#: The file that records the SHA-256 of every file of a generated scenario.
MANIFEST = "MANIFEST.sha256"


class Generate(BaseModel):
    """``generate:`` — the options of ``mrcomm scenario make`` but the team size."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    map: str = "warehouse"
    size: str = "60x40"
    start: str = "scattered"
    assigner: str = "base"
    seed: int = Field(1, ge=0, lt=1 << 63)


class GeneratedScenarios(BaseModel):
    """The ``scenario:`` mapping of a team-size experiment."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    generate: Generate
    robots: list[int] = Field(min_length=1)
    tasks_per_robot: float | None = Field(None, gt=0, le=1000)
    tasks: int | None = Field(None, ge=1)


def generated_scenarios(raw: dict[str, Any], schema: Path) -> list[Path]:
    """The scenario file of each team size, made on first use, each checked as
    :func:`~mrcomm.run.resources.checked_scenario` does (one-line errors)."""
    try:
        spec = GeneratedScenarios.model_validate(raw)
    except pydantic.ValidationError as err:
        raise validation_error(err, file=schema, root=GeneratedScenarios) from None
    if (spec.tasks is None) == (spec.tasks_per_robot is None):
        raise InputError("give tasks or tasks_per_robot", file=schema, field="scenario")
    if len(set(spec.robots)) != len(spec.robots):
        raise InputError("a team size is given twice", file=schema, field="scenario.robots")
    g = spec.generate
    width, height = parse_size(g.size)
    paths = []
    for n in spec.robots:
        tasks = spec.tasks if spec.tasks is not None else math.ceil(n * (spec.tasks_per_robot or 0))
        name = f"{g.map}-n{n}"
        request = Request(g.map, width, height, n, tasks, g.start, g.assigner, g.seed, name)
        folder = (
            schema.parent
            / GENERATED_DIR
            / (f"{g.map}-{width:g}x{height:g}-{g.start}-{g.assigner}-seed{g.seed}-n{n}-t{tasks}")
        )
        scenario = folder / f"{name}.yaml"
        if not folder.exists():
            try:
                folder.parent.mkdir(exist_ok=True)
            except OSError as err:
                raise InputError(
                    f"cannot make {folder.parent}: {err.strerror}", file=schema, field="scenario"
                ) from None
            try:
                make_scenario(request, folder, checked_scenario, reach=planning_reach)
            except InputError as err:
                raise InputError(f"team size {n}: {err.one_line()}", file=schema,
                                 field="scenario") from None  # fmt: skip
            atomic_write_text(folder / MANIFEST, _manifest(folder))
        elif not _made_by(scenario, request):
            raise InputError(
                f"{folder} holds another scenario than the spec makes; remove it",
                file=schema,
                field="scenario",
            )
        elif _manifest_of(folder) != _manifest(folder):
            raise InputError(
                f"{folder} was changed since it was made (its files differ from its "
                f"{MANIFEST}); remove it to make it again",
                file=schema,
                field="scenario",
            )
        else:
            try:  # made by an earlier sweep: checked as a new one is before it is kept
                checked_scenario(scenario)
            except InputError as err:
                raise InputError(f"team size {n}: {err.one_line()}", file=schema,
                                 field="scenario") from None  # fmt: skip
        paths.append(scenario)
    return paths


def _made_by(scenario: Path, request: Request) -> bool:
    """Whether ``scenario`` is headed by the command ``request`` spells."""
    try:
        first = scenario.read_text(encoding="utf-8").splitlines()[0]
    except (OSError, IndexError, UnicodeDecodeError):
        return False
    return first == f"# Generated by: {request.command()}"


def _manifest(folder: Path) -> str:
    """``<sha256 (16 digits)>  <name>`` of every file of a generated scenario but the
    manifest (``run.provenance.file_hash``, the hash runs record of their inputs)."""
    lines = []
    for path in sorted(p for p in folder.rglob("*") if p.is_file() and p.name != MANIFEST):
        lines.append(f"{file_hash(path)}  {path.relative_to(folder).as_posix()}\n")
    return "".join(lines)


def _manifest_of(folder: Path) -> str | None:
    """The manifest written when the scenario was made (None: none, or unreadable)."""
    try:
        return (folder / MANIFEST).read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError):
        return None
