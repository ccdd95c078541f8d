"""Every ``python`` example in docs/testing-with-scopelink.md and docs/emulators.md runs, as its
own test module in a fresh directory, through the installed pytest plugin (as a user's would)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

# In-process pytester runs drop the modules they imported afterwards; numpy cannot be imported
# twice in one process, so what the examples import is imported here first, once.
import scopelink.drivers
import scopelink.testing.handle  # noqa: F401

DOCS = Path(__file__).resolve().parents[2] / "docs"
PAGES = ("testing-with-scopelink.md", "emulators.md")
FENCE = re.compile(r"^```python\n(.*?)^```", re.MULTILINE | re.DOTALL)


def examples(page: str) -> list[str]:
    """The ``python`` fenced blocks of ``docs/page``, in order."""
    return FENCE.findall((DOCS / page).read_text(encoding="utf-8"))


def test_every_python_example_in_the_docs_passes_as_a_test_module(
    pytester: pytest.Pytester,
) -> None:
    modules = {}
    for page in PAGES:
        blocks = examples(page)
        assert blocks, f"{page} has no python example"
        for number, block in enumerate(blocks, 1):
            name = f"test_{page.removesuffix('.md').replace('-', '_')}_{number}"
            modules[name] = block
    pytester.makepyfile(**modules)
    result = pytester.runpytest_inprocess(
        "-p", "no:cacheprovider", "-o", "asyncio_default_fixture_loop_scope=function"
    )
    outcomes = result.parseoutcomes()
    assert outcomes.get("failed", 0) == 0, result.stdout.str()
    assert outcomes.get("errors", 0) == 0, result.stdout.str()
    reports = result.stdout.str()
    for name in modules:  # each example holds a test, and it ran
        assert re.search(rf"^{name}\.py \.+", reports, re.MULTILINE), (name, reports)
