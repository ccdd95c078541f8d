"""The horizon guard and the dead-man see the mount only through their narrow interface
(issue #13 part 2; docs/mount-api.md, "Guard and dead-man"): they import nothing of ``Mount``
and touch no private member of any object but themselves. (That no class is over 400 lines is
checked for the whole package by tests/test_layering.py.)"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

MOUNT = Path(__file__).resolve().parents[2] / "src" / "scopelink" / "mount"
NARROW = ["guard.py", "danger.py", "budget.py", "deadman.py", "guarded.py"]
"""The modules that must not know ``Mount``."""
WHOLE_MOUNT = {"scopelink.mount", "scopelink.mount.base", "scopelink.mount.cache"}
"""Modules that hold (or re-export) ``Mount`` or its state cache."""


def _tree(name: str) -> ast.Module:
    path = MOUNT / name
    return ast.parse(path.read_text(), filename=str(path))


def _imports(tree: ast.AST) -> set[str]:
    found: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module:
            found.add(node.module)
    return found


def _foreign_private_uses(tree: ast.AST) -> list[str]:
    """``x._name`` where ``x`` is not ``self`` or ``cls`` (dunders aside)."""
    uses = []
    for node in ast.walk(tree):
        if (
            isinstance(node, ast.Attribute)
            and node.attr.startswith("_")
            and not node.attr.startswith("__")
            and not (isinstance(node.value, ast.Name) and node.value.id in {"self", "cls"})
        ):
            uses.append(f"line {node.lineno}: {ast.unparse(node)}")
    return uses


@pytest.mark.parametrize("name", NARROW)
def test_the_guard_modules_do_not_import_the_mount(name: str) -> None:
    assert not (_imports(_tree(name)) & WHOLE_MOUNT), name


@pytest.mark.parametrize("name", NARROW)
def test_the_guard_modules_touch_no_private_member_of_another_object(name: str) -> None:
    assert _foreign_private_uses(_tree(name)) == []


def test_the_private_member_check_finds_one() -> None:
    tree = ast.parse("self._mount._publish(self._mount.state)\nmount._publish(state)\n")
    assert len(_foreign_private_uses(tree)) == 2
