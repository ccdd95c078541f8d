"""The event loop of the long-running sessions (``links.loops``): uvloop where installed, asyncio's
default loop when told or where uvloop is absent, a bad setting refused in one line; a TCP exchange
and a ms-resolution timer on the loop each choice makes."""

from __future__ import annotations

import asyncio
import importlib.metadata
import re
import sys
import time
from pathlib import Path

import pytest

from scopelink.links import (
    DEFAULT_EVENT_LOOP,
    EVENT_LOOP_CHOICES,
    EVENT_LOOP_ENV_VAR,
    EventLoopChoiceError,
    Link,
    choose_event_loop,
    describe_loop,
    open_tcp,
    serve_event_loop,
    serve_tcp,
)

UVLOOP_VERSION = importlib.metadata.version("uvloop")
"""A runtime dependency on this platform (pyproject's marker: not Windows, CPython)."""


async def _echo_once_and_sleep() -> float:
    """A real TCP exchange through our links on the running loop, then how long a 5 ms
    ``asyncio.sleep`` took by the monotonic clock."""

    async def echo(link: Link) -> None:
        await link.write(await link.read_exactly(3))

    server = await serve_tcp(echo)
    try:
        async with await open_tcp("127.0.0.1", server.port) as link:
            await link.write(b"abc")
            assert await link.read_exactly(3) == b"abc"
    finally:
        await server.close()
    started = time.monotonic()
    await asyncio.sleep(0.005)
    return time.monotonic() - started


def _run(factory: object) -> tuple[str, float]:
    assert callable(factory)
    with asyncio.Runner(loop_factory=factory) as runner:
        kind = describe_loop(runner.get_loop())
        return kind, runner.run(_echo_once_and_sleep())


def test_each_choice_makes_its_loop_and_runs_our_links_on_it(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.delenv(EVENT_LOOP_ENV_VAR, raising=False)
    auto = choose_event_loop()
    assert (auto.name, auto.label) == ("uvloop", f"uvloop {UVLOOP_VERSION}")
    for setting in ("uvloop", " UVLoop ", "auto", ""):
        assert choose_event_loop(setting).label == auto.label
    kind, slept = _run(serve_event_loop)
    assert kind == f"uvloop {UVLOOP_VERSION}"
    # libuv's timers count whole milliseconds: a 5 ms sleep ends within a millisecond of it
    # either way (asyncio's default loop: never early), however late a busy machine makes it.
    assert slept >= 0.005 - 0.0015

    monkeypatch.setenv(EVENT_LOOP_ENV_VAR, "asyncio")
    told = choose_event_loop()
    assert told.label == f"asyncio ({EVENT_LOOP_ENV_VAR}=asyncio)"
    kind, slept = _run(serve_event_loop)
    assert kind == "asyncio (epoll)"
    assert slept >= 0.005 - 1e-6  # its clock's resolution, 1 ns


@pytest.mark.parametrize("setting", ["fast", "uv loop", "tokio", "asyncio,uvloop", "1"])
def test_a_bad_setting_is_refused_in_one_line(setting: str) -> None:
    with pytest.raises(EventLoopChoiceError) as raised:
        choose_event_loop(setting)
    message = str(raised.value)
    assert "\n" not in message
    assert message == (
        f"{EVENT_LOOP_ENV_VAR}={setting!r} is not one of {', '.join(EVENT_LOOP_CHOICES)}"
    )


def test_without_uvloop_auto_falls_back_and_uvloop_is_refused(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # As on Windows or PyPy, where the dependency's marker leaves uvloop out: its import fails.
    monkeypatch.setitem(sys.modules, "uvloop", None)
    fallback = choose_event_loop("auto")
    assert fallback.label == "asyncio (uvloop is not installed)"
    kind, _ = _run(fallback.factory)
    assert kind == "asyncio (epoll)"
    with pytest.raises(EventLoopChoiceError, match=r"^SCOPELINK_EVENT_LOOP=uvloop but uvloop "):
        choose_event_loop("uvloop")


def test_documented_default_is_the_code_s() -> None:
    root = Path(__file__).parents[2]
    serve = " ".join((root / "docs" / "serve.md").read_text().split())
    assert f"`{EVENT_LOOP_ENV_VAR}`" in serve
    assert f"default **{DEFAULT_EVENT_LOOP}**" in serve
    assert "`" + "`, `".join(EVENT_LOOP_CHOICES) + "`" in serve
    pyproject = (root / "pyproject.toml").read_text()
    assert re.search(r'"uvloop>=[0-9.]+,<1; sys_platform != .win32. and ', pyproject)
    readme = (root / "README.md").read_text()
    assert "| `uvloop` |" in readme
