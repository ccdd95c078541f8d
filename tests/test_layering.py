"""Imports point down the layer list only (docs/architecture.md)."""

from __future__ import annotations

import ast
import graphlib
from pathlib import Path

import pytest

PACKAGE_ROOT = Path(__file__).resolve().parent.parent / "src" / "scopelink"

# Lower number = lower layer. A module may import its own layer or any lower one.
LAYER_OF = {
    "protocol": 1,
    "astro": 2,
    "links": 3,
    "mount": 4,
    "decode": 3,
    "drivers": 5,
    "sim": 5,
    "servers": 6,
    "web": 7,
    "cli": 7,
    "testing": 7,
}
# What the sans-IO layer must never touch: it has no I/O and no clock.
FORBIDDEN_IN_PROTOCOL = {"asyncio", "socket", "time", "serial", "select", "threading", "os"}


def _modules() -> list[Path]:
    return sorted(p for p in PACKAGE_ROOT.rglob("*.py"))


def _subpackage(path: Path) -> str | None:
    rel = path.relative_to(PACKAGE_ROOT)
    if len(rel.parts) == 1:
        return None if rel.stem == "__init__" else rel.stem
    return rel.parts[0]


def _from_module(node: ast.ImportFrom, package_parts: list[str]) -> str:
    """The module a ``from ... import`` names, relative imports resolved in ``package_parts``."""
    if not node.level:
        return node.module or ""
    base = package_parts[: len(package_parts) - node.level + 1]
    return ".".join([*base, node.module] if node.module else base)


def _imported_names(tree: ast.AST, path: Path) -> list[tuple[int, str]]:
    names: list[tuple[int, str]] = []
    package_parts = ["scopelink", *path.relative_to(PACKAGE_ROOT).parent.parts]
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names.extend((node.lineno, alias.name) for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            names.append((node.lineno, _from_module(node, package_parts)))
    return names


def test_every_subpackage_has_a_layer() -> None:
    named = {name for p in _modules() if (name := _subpackage(p)) is not None}
    unknown = named - set(LAYER_OF) - {"__main__"}
    assert not unknown, f"add these to LAYER_OF and docs/architecture.md: {sorted(unknown)}"


@pytest.mark.parametrize("path", _modules(), ids=lambda p: str(p.relative_to(PACKAGE_ROOT)))
def test_imports_point_down(path: Path) -> None:
    own = _subpackage(path)
    if own is None or own == "__main__":
        return
    tree = ast.parse(path.read_text(), filename=str(path))
    for lineno, name in _imported_names(tree, path):
        parts = name.split(".")
        if parts[0] == "scopelink" and len(parts) > 1:
            target = parts[1]
            assert LAYER_OF.get(target, 99) <= LAYER_OF[own], (
                f"{path.name}:{lineno} ({own}) imports {name} from a higher layer"
            )
        if own == "protocol":
            assert parts[0] not in FORBIDDEN_IN_PROTOCOL, (
                f"{path.name}:{lineno}: the sans-IO protocol layer imports {name}"
            )


def _module_name(path: Path) -> str:
    parts = ["scopelink", *path.relative_to(PACKAGE_ROOT).with_suffix("").parts]
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _import_graph() -> dict[str, set[str]]:
    """Each module of ``src/scopelink`` and the package modules it imports, wherever the import
    stands (``TYPE_CHECKING`` blocks and functions included: a reader follows those too).
    ``from a.b import c`` counts as an import of ``a.b.c`` when that is a module, else of
    ``a.b``; a package's ``__init__`` is not counted as imported by its submodules' imports."""
    paths = {_module_name(p): p for p in _modules()}
    graph: dict[str, set[str]] = {}
    for name, path in paths.items():
        package_parts = ["scopelink", *path.relative_to(PACKAGE_ROOT).parent.parts]
        targets: set[str] = set()
        for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
            if isinstance(node, ast.Import):
                targets.update(alias.name for alias in node.names)
            elif isinstance(node, ast.ImportFrom):
                module = _from_module(node, package_parts)
                for alias in node.names:
                    sub = f"{module}.{alias.name}"
                    targets.add(sub if sub in paths else module)
        graph[name] = {t for t in targets if t in paths and t != name}
    return graph


def test_no_import_cycle() -> None:
    """No module of ``src/scopelink`` imports itself through others (decision and rules:
    docs/mount-api.md, "Guard and dead-man")."""
    try:
        tuple(graphlib.TopologicalSorter(_import_graph()).static_order())
    except graphlib.CycleError as error:
        cycle = error.args[1]
        pytest.fail(f"import cycle: {' -> '.join(cycle)}")


def test_the_cycle_check_finds_a_cycle() -> None:
    graph = _import_graph()
    graph["scopelink.mount.types"].add("scopelink.mount.base")  # base imports types already
    with pytest.raises(graphlib.CycleError):
        tuple(graphlib.TopologicalSorter(graph).static_order())


MAX_CLASS_LINES = 400
"""No class over this many lines (issue #13): one concern per class; a bigger one is split."""


@pytest.mark.parametrize(
    "path",
    sorted([*PACKAGE_ROOT.rglob("*.py"), *(PACKAGE_ROOT.parents[1] / "bench").rglob("*.py")]),
    ids=lambda p: p.relative_to(PACKAGE_ROOT.parents[1]).as_posix(),
)
def test_no_class_is_over_400_lines(path: Path) -> None:
    tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
    for node in ast.walk(tree):
        if isinstance(node, ast.ClassDef):
            assert node.end_lineno is not None
            lines = node.end_lineno - node.lineno + 1
            assert lines <= MAX_CLASS_LINES, f"{path.name}: {node.name} has {lines} lines"


# --- docs/architecture.md, "three hops": every name in the table exists ----------------------

HOPS_SECTION = "## From a seed command to its code: three hops"


def _hop_rows(family: str) -> list[list[str]]:
    """The table rows under the ``### family`` heading of the three-hop section, cells unquoted."""
    docs = (PACKAGE_ROOT.parents[1] / "docs" / "architecture.md").read_text(encoding="utf-8")
    section = docs[docs.index(HOPS_SECTION) :]
    table = section[section.index(f"### {family}") :].split("\n\n")[1]
    rows = [line.strip("|").split(" | ") for line in table.splitlines()[2:]]
    return [[cell.strip().strip("`") for cell in row] for row in rows]


def _has(packages: list[str], dotted: str) -> bool:
    """Whether ``Class.member`` (or ``Class``) is defined in one of ``packages``' modules."""
    import importlib
    import pkgutil

    class_name, _, member = dotted.partition(".")
    for package_name in packages:
        package = importlib.import_module(package_name)
        names = [package_name] + [
            f"{package_name}.{info.name}" for info in pkgutil.iter_modules(package.__path__)
        ]
        for name in names:
            owner = getattr(importlib.import_module(name), class_name, None)
            if owner is not None and (not member or hasattr(owner, member)):
                return True
    return False


@pytest.mark.parametrize(
    ("family", "codec", "drivers", "emulators"),
    [
        (
            "SynScan",
            "scopelink.protocol.synscan",
            ["scopelink.drivers.synscan"],
            ["scopelink.servers.synscan"],
        ),
        (
            "Sky Tracker",
            "scopelink.protocol.skytracker",
            ["scopelink.drivers.skytracker"],
            ["scopelink.servers.skytracker"],
        ),
    ],
)
def test_the_three_hop_table_names_code_that_exists_and_every_command(
    family: str, codec: str, drivers: list[str], emulators: list[str]
) -> None:
    import importlib

    rows = _hop_rows(family)
    codec_module = importlib.import_module(codec)
    for _, codec_class, driver_method, handler in rows:
        assert isinstance(getattr(codec_module, codec_class, None), type), codec_class
        if not driver_method.startswith("("):
            assert _has(drivers, driver_method), driver_method
        assert _has(emulators, handler), handler
    listed = {row[1] for row in rows}
    if family == "SynScan":
        commands = {command.__name__ for command in codec_module.COMMANDS}
    else:
        bases = (codec_module.TrackerCommand, codec_module.CommanderCommand)
        commands = {
            name
            for name, value in vars(codec_module).items()
            if isinstance(value, type) and issubclass(value, bases) and value not in bases
        }
    assert listed == commands
