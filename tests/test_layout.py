"""The test suite's own layout (tests/README.md): tests by layer, shared code in tests/support/.

No test module imports another test module (conftest.py included) or the benchmarks under
``bench/``; every ``test_*.py`` file holds a test; code that holds no test lives in
``tests/support/`` (or a ``conftest.py``) under a name pytest does not collect.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

TESTS = Path(__file__).resolve().parent

BENCH_IMPORTS_LEFT = {
    "reliability/test_fuzz_parsers.py": "bench.fuzz's targets and generator under hypothesis",
    "safety/test_safety_noisy_link.py": "bench.safety_guard's noisy_rig and noisy_trial",
    "safety/test_safety_noisy_skytracker.py": "bench.safety_guard's noisy_skytracker rig",
    "safety/test_safety_sun_noisy.py": "bench.safety_sun.run_once",
    "security/test_security_access_flood.py": "bench.security_flood.measure and its rig",
}
"""Test modules outside ``tests/bench/`` that still import the benchmarks, each with what it
imports. (The tests in ``tests/bench/`` test the benchmarks themselves, their parsers and goal
lines, so they may import them.) The rig or parser is the benchmark's own code; it moves into
tests/support/ (and the benchmark imports it from there) or the test runs the benchmark as a
subprocess. This list may only shrink: a module that no longer imports ``bench`` must leave it."""


def _module_name(path: Path, root: Path) -> str:
    parts = path.relative_to(root.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def imported_modules(path: Path, root: Path) -> set[str]:
    """Every module ``path`` imports, anywhere in it (also inside functions), as absolute names;
    for ``from package import name`` both ``package`` and ``package.name``."""
    tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
    module = _module_name(path, root)
    package = module if path.name == "__init__.py" else module.rsplit(".", 1)[0]
    found: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = package.split(".")[: len(package.split(".")) - (node.level - 1)]
                base = ".".join([*anchor, base] if base else anchor)
            found.add(base)
            found.update(f"{base}.{alias.name}" for alias in node.names)
    return found


def _is_test_module(name: str) -> bool:
    parts = name.split(".")
    return parts[0] == "tests" and (parts[-1].startswith("test_") or parts[-1] == "conftest")


def imports_of_test_modules(root: Path) -> dict[str, list[str]]:
    """For every Python file under ``root``: the test modules (``test_*``, conftest) it imports."""
    found = {}
    for path in sorted(root.rglob("*.py")):
        bad = sorted(name for name in imported_modules(path, root) if _is_test_module(name))
        if bad:
            found[path.relative_to(root).as_posix()] = bad
    return found


def importers_of_bench(root: Path) -> set[str]:
    """The files under ``root`` that import the benchmarks (``bench`` or ``bench.*``)."""
    return {
        path.relative_to(root).as_posix()
        for path in sorted(root.rglob("*.py"))
        if any(name.split(".", maxsplit=1)[0] == "bench" for name in imported_modules(path, root))
    }


def _holds_a_test(tree: ast.Module) -> bool:
    functions = (ast.FunctionDef, ast.AsyncFunctionDef)
    for node in tree.body:
        if isinstance(node, functions) and node.name.startswith("test"):
            return True
        if (
            isinstance(node, ast.ClassDef)
            and node.name.startswith("Test")
            and any(isinstance(n, functions) and n.name.startswith("test") for n in node.body)
        ):
            return True
    return False


def files_without_tests(root: Path) -> list[str]:
    """The ``test_*.py`` files under ``root`` that define no test function or Test class."""
    return [
        path.relative_to(root).as_posix()
        for path in sorted(root.rglob("test_*.py"))
        if not _holds_a_test(ast.parse(path.read_text(encoding="utf-8")))
    ]


TOP_LEVEL_TESTS = {"test_ci_policy.py", "test_constants.py", "test_layering.py", "test_layout.py"}
"""The only test files above the layer directories: they test the suite and the package's shape."""


def misplaced_modules(root: Path) -> list[str]:
    """Python files outside ``support/`` that pytest would not collect and that are no
    ``conftest.py`` or ``__init__.py``; test files at the top that belong in a layer's directory;
    and test directories that are not packages."""
    wrong = []
    for path in sorted(root.rglob("*.py")):
        relative = path.relative_to(root)
        if relative.parts[0] == "support" or path.name in {"conftest.py", "__init__.py"}:
            continue
        if not path.name.startswith("test_"):
            wrong.append(relative.as_posix())
        elif len(relative.parts) == 1 and path.name not in TOP_LEVEL_TESTS:
            wrong.append(f"{relative.as_posix()} (belongs in a layer's directory)")
    for directory in sorted({path.parent for path in root.rglob("*.py")}):
        if directory.name != "__pycache__" and not (directory / "__init__.py").exists():
            wrong.append(f"{directory.relative_to(root).as_posix()}/ (no __init__.py)")
    return wrong


def test_no_test_module_imports_another() -> None:
    assert imports_of_test_modules(TESTS) == {}


def test_only_the_listed_test_modules_import_the_benchmarks() -> None:
    importers = {name for name in importers_of_bench(TESTS) if not name.startswith("bench/")}
    assert importers == set(BENCH_IMPORTS_LEFT)


def test_every_test_file_holds_a_test() -> None:
    assert files_without_tests(TESTS) == []


def test_shared_code_lives_in_support_and_every_directory_is_a_package() -> None:
    assert misplaced_modules(TESTS) == []


def _tree(root: Path, files: dict[str, str]) -> Path:
    for name, text in {"__init__.py": "", **files}.items():
        (root / name).parent.mkdir(parents=True, exist_ok=True)
        (root / name).write_text(text)
    return root


@pytest.mark.parametrize(
    "line",
    [
        "from tests.test_other import helper",
        "from tests.conftest import IN_CI",
        "from .test_other import helper",
        "from . import test_other",
        "import tests.drivers.test_other",
        "def test_x():\n    from tests.drivers.test_other import helper",
    ],
)
def test_the_checks_catch_a_test_module_importing_another(tmp_path: Path, line: str) -> None:
    root = _tree(
        tmp_path / "tests",
        {
            "drivers/__init__.py": "",
            "drivers/test_other.py": "def test_other(): pass\n",
            "drivers/test_one.py": f"{line}\n\ndef test_one(): pass\n",
        },
    )
    assert list(imports_of_test_modules(root)) == ["drivers/test_one.py"]
    assert misplaced_modules(root) == []


def test_the_checks_catch_bench_imports_empty_tests_and_stray_helpers(tmp_path: Path) -> None:
    root = _tree(
        tmp_path / "tests",
        {
            "web/test_bench.py": "def test_x():\n    import bench.fuzz\n",
            "web/test_helpers.py": "def helper(): pass\nclass Rig:\n    def test_not(self): pass\n",
            "web/helpers.py": "from tests.support.web import served\n",
            "support/web.py": "from tests.support import quick_bench\n",
            "sim/test_fine.py": "from benches import x\nclass TestAxis:\n    def test_a(self): ...",
            "test_flat.py": "def test_flat(): pass\n",
            "test_layout.py": "def test_layout(): pass\n",
        },
    )
    assert importers_of_bench(root) == {"web/test_bench.py"}
    assert files_without_tests(root) == ["web/test_helpers.py"]
    assert misplaced_modules(root) == [
        "test_flat.py (belongs in a layer's directory)",
        "web/helpers.py",
        "sim/ (no __init__.py)",
        "support/ (no __init__.py)",
        "web/ (no __init__.py)",
    ]
    assert imports_of_test_modules(root) == {}
