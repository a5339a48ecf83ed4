"""The package's shape: layers depend downwards only, and no import circles.

Read statically (``ast``) from ``src/mrcomm``: every ``import`` outside
``if TYPE_CHECKING:`` blocks counts, for the layering and for circles alike (an import
inside a function only postpones a circle to the first call).
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[2] / "src" / "mrcomm"

#: Rank of each top-level part of the package: a module may import only parts of a
#: lower or equal rank (equal: siblings that do not form circles).
RANKS = {
    "errors": 0,
    "fileio": 0,
    "output_paths": 0,
    "seeding": 0,
    "compiled": 0,  # numba or plain Python for the hot loops
    "specs": 0,
    "bundled": 0,  # where the bundled data is, and its names
    "ports": 2,  # the agents' ports speak in messages and poses
    "world": 1,
    "messaging": 2,
    "net": 2,
    "robot": 2,
    "metrics": 2,
    "agents": 3,
    "run": 4,
    "sim": 5,
    "live": 5,
    "ros2": 3,  # the Nav2 base and the world's ROS 2 robots (optional extra)
    "experiment": 6,
    "analysis": 6,
    "testing": 6,
    "console": 6,  # the operator console: a paced simulation and its web page
    "cli": 7,
    "__main__": 7,  # python -m mrcomm: the CLI
}


def module_name(path: Path, root: Path = SRC.parent) -> str:
    """``src/mrcomm/sim/mission.py`` -> ``mrcomm.sim.mission``."""
    parts = path.relative_to(root).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


MODULES: dict[str, Path] = {}


def part_of(module: str) -> str | None:
    pieces = module.split(".")
    return pieces[1] if len(pieces) > 1 and pieces[0] == "mrcomm" else None


def _is_type_checking(node: ast.If) -> bool:
    test = node.test
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING"
    )


def imports(path: Path, *, top_level_only: bool, root: Path = SRC.parent) -> set[str]:
    """The mrcomm modules ``path`` imports (``top_level_only``: not those inside
    functions, which run only when called)."""
    module = module_name(path, root)
    package = module if path.name == "__init__.py" else module.rsplit(".", 1)[0]
    found: set[str] = set()

    def add(base: str, names: list[str]) -> None:
        if not base.startswith("mrcomm"):
            return
        found.add(base)
        for name in names:  # `from mrcomm.x import y` may import the module mrcomm.x.y
            if f"{base}.{name}" in MODULES:
                found.add(f"{base}.{name}")

    def visit(node: ast.AST) -> None:
        if isinstance(node, ast.If) and _is_type_checking(node):
            for child in node.orelse:
                visit(child)
            return
        if top_level_only and isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
            return
        if isinstance(node, ast.Import):
            for alias in node.names:
                add(alias.name, [])
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = package.split(".")[: len(package.split(".")) - node.level + 1]
                base = ".".join([*anchor, *([base] if base else [])])
            add(base, [a.name for a in node.names])
        for child in ast.iter_child_nodes(node):
            visit(child)

    visit(ast.parse(path.read_text(encoding="utf-8")))
    return found


MODULES.update({module_name(p): p for p in sorted(SRC.rglob("*.py"))})


def test_the_import_reader_sees_imports() -> None:
    mission = imports(MODULES["mrcomm.sim.mission"], top_level_only=True)
    assert {"mrcomm.run.config", "mrcomm.run.wiring"} <= mission
    everything = imports(MODULES["mrcomm.cli.run_cmd"], top_level_only=False)
    assert "mrcomm.analysis.mission_plot" in everything  # imported inside a function
    assert "mrcomm.analysis.mission_plot" not in imports(
        MODULES["mrcomm.cli.run_cmd"], top_level_only=True
    )


def test_every_part_has_a_rank() -> None:
    parts = {part_of(m) for m in MODULES} - {None}
    assert parts <= set(RANKS), sorted(parts - set(RANKS))


@pytest.mark.parametrize("module", sorted(MODULES))
def test_layers_depend_downwards_only(module: str) -> None:
    own = part_of(module)
    if own is None:
        return
    upward = [
        target
        for target in sorted(imports(MODULES[module], top_level_only=False))
        if (part := part_of(target)) is not None and RANKS[part] > RANKS[own]
    ]
    assert not upward, f"{module} ({own}) imports upwards: {upward}"


def import_graph(modules: dict[str, Path], root: Path = SRC.parent) -> dict[str, set[str]]:
    """Module -> the modules of ``modules`` (under ``root``) it imports, at module
    level or inside a function."""
    return {
        m: {t for t in imports(p, top_level_only=False, root=root) if t in modules and t != m}
        for m, p in modules.items()
    }


def find_circle(graph: dict[str, set[str]]) -> list[str] | None:
    """One import circle of ``graph`` (its modules in order, the first again at the
    end), or None."""
    state: dict[str, int] = {}
    stack: list[str] = []

    def walk(node: str) -> list[str] | None:
        state[node] = 1
        stack.append(node)
        for nxt in sorted(graph[node]):
            if state.get(nxt) == 1:
                return [*stack[stack.index(nxt) :], nxt]
            if nxt not in state and (cycle := walk(nxt)):
                return cycle
        stack.pop()
        state[node] = 2
        return None

    for start in sorted(graph):
        if start not in state and (cycle := walk(start)):
            return cycle
    return None


def test_no_import_circles() -> None:
    cycle = find_circle(import_graph(MODULES))
    assert cycle is None, "import circle: " + " -> ".join(cycle or [])


def test_a_circle_through_a_function_level_import_is_found(tmp_path: Path) -> None:
    (tmp_path / "mrcomm").mkdir()
    first, second = tmp_path / "mrcomm" / "first.py", tmp_path / "mrcomm" / "second.py"
    first.write_text("from mrcomm.second import thing\n")
    second.write_text("def later():\n    from mrcomm.first import other\n")
    modules = {"mrcomm.first": first, "mrcomm.second": second}
    circle = ["mrcomm.first", "mrcomm.second", "mrcomm.first"]
    assert find_circle(import_graph(modules, tmp_path)) == circle
    second.write_text("def later():\n    return 1\n")
    assert find_circle(import_graph(modules, tmp_path)) is None


def test_no_module_over_600_lines() -> None:
    long = {m: n for m, p in MODULES.items() if (n := len(p.read_text().splitlines())) > 600}
    assert not long, long
