"""The pytest plugin in a user's suite (one pytester run, in a fresh directory, through the
installed plugin as a user's would): every ``python`` example in docs/testing-with-scopelink.md
and docs/emulators.md passes as its own test module; the closest marker wins; nonsense fails the
test's setup with one line and no traceback."""

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


USER_TESTS = """
import pytest

pytestmark = pytest.mark.scopelink_emulator(transport="pty", pacing=False)


def test_the_module_marker_applies(synscan_emulator):
    assert synscan_emulator.path.startswith("/dev/")


@pytest.mark.scopelink_emulator(transport="tcp")
def test_the_closest_marker_wins(synscan_emulator, scopelink_emulator_factory):
    assert synscan_emulator.port > 0
    second = scopelink_emulator_factory("skycommander")
    assert (second.spec.transport, second.spec.pacing) == ("tcp", False)


@pytest.mark.scopelink_emulator(model="EQ6")
def test_an_eq6_behind_a_sky_tracker(skytracker_emulator):
    pass


@pytest.mark.scopelink_emulator(modle="EQ6")
def test_a_typo(synscan_emulator):
    pass


@pytest.mark.scopelink_emulator(firmware="4.39.05")
def test_firmware_for_a_sky_commander(skycommander_emulator):
    pass


@pytest.mark.parametrize("synscan_emulator", ["pty"], indirect=True)
def test_a_parameter_that_is_no_dict(synscan_emulator):
    pass


def test_the_factory_refuses_too(scopelink_emulator_factory):
    scopelink_emulator_factory("skytracker", model="heq5")
"""

ONE_LINE_REFUSALS = (
    "skytracker emulator: the Sky Tracker works on an alt-azimuth telescope only, not the EQ6 "
    "(german polar): use an alt-az preset such as SKY_TRACKER",
    "scopelink_emulator: no option 'modle' (did you mean 'model'?)",
    "skycommander emulator: firmware is the SynScan hand control's; the skycommander has its own",
    "synscan_emulator: parametrize it with a dict, not 'pty'",
    "skytracker emulator: the Sky Tracker works on an alt-azimuth telescope only, not the HEQ5",
)


def examples(page: str) -> list[str]:
    """The ``python`` fenced blocks of ``docs/page``, in order."""
    return FENCE.findall((DOCS / page).read_text(encoding="utf-8"))


def test_the_docs_examples_pass_and_nonsense_fails_in_one_line(pytester: pytest.Pytester) -> None:
    modules = {"test_user": USER_TESTS}
    for page in PAGES:
        blocks = examples(page)
        assert blocks, f"{page} has no python example"
        for number, block in enumerate(blocks, 1):
            modules[f"test_{page.removesuffix('.md').replace('-', '_')}_{number}"] = block
    pytester.makepyfile(**modules)
    result = pytester.runpytest_inprocess(
        "-p", "no:cacheprovider", "-rfE", "-o", "asyncio_default_fixture_loop_scope=function"
    )
    output = result.stdout.str()
    for name in modules:  # each example holds a test, and it ran and passed
        if name != "test_user":
            assert re.search(rf"^{name}\.py \.+ +\[ *\d+%\]$", output, re.MULTILINE), (name, output)
    assert re.search(r"^test_user\.py \.\.EEEEF +\[ *\d+%\]$", output, re.MULTILINE), output
    for refusal in ONE_LINE_REFUSALS:
        assert refusal in output
    assert "Traceback" not in output
    assert "scopelink/testing" not in output  # no frame of ours is shown
