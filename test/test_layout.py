"""The package's layout rules, read from the source (``ast``, nothing imported): no import circle,
lower layers never import higher ones, only ``ros/`` and ``cli/`` import rclpy, no module over
400 lines, CONTRIBUTING.md's layout names every module, and every relative link in the README
and docs/ resolves."""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "a1_leg_fk"
MAX_LINES = 400

# Lowest first; a module may import its own layer and the ones before it.
LAYERS: tuple[tuple[str, ...], ...] = (
    ("a1_leg_fk.stop_signals", "a1_leg_fk.model", "a1_leg_fk.wire"),
    ("a1_leg_fk.kinematics",),
    ("a1_leg_fk.estimation", "a1_leg_fk.tracking"),
    (
        "a1_leg_fk.recording",
        "a1_leg_fk.gait",
        "a1_leg_fk.verify",
        "a1_leg_fk.plots",
        "a1_leg_fk.odometry_plot",
    ),
    ("a1_leg_fk.view",),  # the Rerun recording of the bag and odom pipelines' outputs
    ("a1_leg_fk.ros", "a1_leg_fk.cli"),
    ("a1_leg_fk",),  # the package's own __init__: the public API, re-exported lazily
)
ROS_IMPORTERS = ("a1_leg_fk.ros", "a1_leg_fk.cli")


def module_name(path: Path) -> str:
    parts = path.relative_to(ROOT).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


MODULES = {module_name(path): path for path in sorted(PACKAGE.rglob("*.py"))}


def imported(name: str) -> set[str]:
    """Every module of the package or third-party top name that ``name`` imports, anywhere in it
    (top level, functions, ``TYPE_CHECKING`` blocks)."""
    path = MODULES[name]
    found: set[str] = set()
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            found.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = package.split(".")[: len(package.split(".")) - node.level + 1]
                base = ".".join(anchor + ([base] if base else []))
            names = {f"{base}.{alias.name}" for alias in node.names}
            found.update(names)
            if not names <= MODULES.keys():  # a name from the module, not a submodule of it
                found.add(base)
    return found


def package_imports(name: str) -> set[str]:
    return {module for module in imported(name) if module in MODULES and module != name}


def layer(name: str) -> int:
    best = max(
        (prefix for group in LAYERS for prefix in group if (name + ".").startswith(prefix + ".")),
        key=len,
    )
    return next(rank for rank, group in enumerate(LAYERS) if best in group)


def test_no_import_circle() -> None:
    graph = {name: package_imports(name) for name in MODULES}
    state: dict[str, int] = {}  # 1 on the current path, 2 done
    path: list[str] = []

    def visit(name: str) -> None:
        state[name] = 1
        path.append(name)
        for child in sorted(graph[name]):
            if state.get(child) == 1:
                circle = [*path[path.index(child) :], child]
                pytest.fail("import circle: " + " -> ".join(circle))
            if child not in state:
                visit(child)
        path.pop()
        state[name] = 2

    for name in MODULES:
        if name not in state:
            visit(name)


@pytest.mark.parametrize("name", sorted(MODULES))
def test_lower_layers_never_import_higher_ones(name: str) -> None:
    higher = sorted(module for module in package_imports(name) if layer(module) > layer(name))
    assert not higher, f"{name} (layer {layer(name)}) imports {higher}"


@pytest.mark.parametrize("name", sorted(MODULES))
def test_only_ros_and_cli_import_rclpy(name: str) -> None:
    ros = {module for module in imported(name) if module.split(".")[0] == "rclpy"}
    if not name.startswith(ROS_IMPORTERS):
        assert not ros, f"{name} imports {sorted(ros)}"


@pytest.mark.parametrize("name", sorted(MODULES))
def test_modules_stay_under_the_line_cap(name: str) -> None:
    lines = len(MODULES[name].read_text().splitlines())
    assert lines <= MAX_LINES, f"{MODULES[name].relative_to(ROOT)}: {lines} lines"


def test_the_layer_table_knows_every_subpackage() -> None:
    tops = {".".join(name.split(".")[:2]) for name in MODULES}
    known = {prefix for group in LAYERS for prefix in group}
    assert tops <= known, f"not in LAYERS: {sorted(tops - known)}"


def test_contributing_names_every_module() -> None:
    """CONTRIBUTING.md's layout names each module of the package (by file name; ``cli/`` is
    "one module per command", ``__init__`` and ``__main__`` files go without saying)."""
    layout = (ROOT / "CONTRIBUTING.md").read_text()
    unnamed = [
        str(path.relative_to(PACKAGE))
        for path in MODULES.values()
        if not path.name.startswith("__")
        and path.parent.name != "cli"
        and not re.search(rf"(?<![\w/]){re.escape(path.name)}", layout)
    ]
    assert not unnamed, f"CONTRIBUTING.md's layout does not name: {unnamed}"


LINK = re.compile(r"\[[^\]]*\]\(([^)\s]+)\)")


def documents() -> list[Path]:
    return [ROOT / "README.md", ROOT / "CONTRIBUTING.md", *sorted((ROOT / "docs").glob("*.md"))]


def anchors(path: Path) -> set[str]:
    """GitHub's anchors of the headings in ``path``."""
    found = set()
    for line in path.read_text().splitlines():
        if line.startswith("#"):
            title = line.lstrip("#").strip().lower()
            found.add(re.sub(r"[^\w\- ]", "", title).replace(" ", "-"))
    return found


@pytest.mark.parametrize("document", documents(), ids=lambda path: path.name)
def test_every_relative_link_resolves(document: Path) -> None:
    broken = []
    for target in LINK.findall(document.read_text()):
        if re.match(r"[a-z]+:", target):
            continue  # http(s), mailto
        file_part, _, anchor = target.partition("#")
        linked = (document.parent / file_part).resolve() if file_part else document
        if not linked.exists() or (
            anchor and linked.suffix == ".md" and anchor not in anchors(linked)
        ):
            broken.append(target)
    assert not broken, f"{document.name}: broken links {broken}"
