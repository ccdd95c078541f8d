"""A small INDI client for tests: runs an INDI driver binary and speaks INDI's XML on its pipes.

An INDI driver reads client XML on stdin and writes property definitions and updates on stdout,
so no ``indiserver`` (and no network port) is needed. Usage::

    async with IndiDriver.start("indi_synscan_telescope", home=tmp_path) as driver:
        await driver.get_properties()
        await driver.set_text("DEVICE_PORT", {"PORT": "/dev/pts/5"})
        await driver.set_switch("CONNECTION", {"CONNECT": True})
        coords = await driver.wait_for("EQUATORIAL_EOD_COORD", lambda p: p.state == "Ok")

``home`` points the driver's ``HOME`` at a scratch directory, so it loads no saved configuration.
"""

from __future__ import annotations

import asyncio
import contextlib
import os
import shutil
import time
import xml.etree.ElementTree as ET
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from types import TracebackType
from typing import cast
from xml.sax.saxutils import escape, quoteattr

__all__ = ["IndiDriver", "IndiError", "IndiProperty", "parse_indi_number"]

_ONE_OF = ("def", "set")
_KINDS = ("Number", "Switch", "Text", "Light", "BLOB")


class IndiError(Exception):
    """The driver did not do what the test waited for; the message carries its recent log."""


def parse_indi_number(text: str) -> float:
    """An INDI number: decimal, or sexagesimal ``D:M:S`` / ``D M S`` (sign on the first field)."""
    text = text.strip()
    fields = text.replace(":", " ").split()
    if len(fields) == 1:
        return float(fields[0])
    sign = -1.0 if fields[0].startswith("-") else 1.0
    value = 0.0
    for power, part in enumerate(fields):
        value += abs(float(part)) / 60.0**power
    return sign * value


@dataclass(slots=True)
class IndiProperty:
    """The latest definition and values of one property vector."""

    device: str
    name: str
    kind: str  # Number, Switch, Text, Light or BLOB
    state: str  # Idle, Ok, Busy or Alert
    values: dict[str, str] = field(default_factory=dict)
    updated_at: float = 0.0

    def number(self, member: str) -> float:
        """A Number member's value."""
        return parse_indi_number(self.values[member])

    def switch(self, member: str) -> bool:
        """A Switch member's state."""
        return self.values[member].strip() == "On"

    def text(self, member: str) -> str:
        return self.values[member].strip()


class IndiDriver:
    """A running INDI driver process and the properties it has announced."""

    def __init__(self, process: asyncio.subprocess.Process, device: str | None) -> None:
        self._process = process
        self.device = device
        self.properties: dict[str, IndiProperty] = {}
        self.messages: list[str] = []
        self._changed = asyncio.Event()
        self._parser: ET.XMLPullParser[ET.Element] = ET.XMLPullParser(events=("start", "end"))
        self._parser.feed("<indi>")
        self._depth = 0
        self._reader = asyncio.create_task(self._read_stdout())
        self._stderr: list[str] = []
        self._stderr_reader = asyncio.create_task(self._read_stderr())

    @classmethod
    def start(
        cls, binary: str, *, home: Path, device: str | None = None, env: Mapping[str, str] = {}
    ) -> _Starting:
        """Start ``binary`` (found on PATH); use as ``async with IndiDriver.start(...) as d``."""
        return _Starting(cls, binary, home, device, env)

    @classmethod
    async def launch(
        cls, binary: str, *, home: Path, device: str | None = None, env: Mapping[str, str] = {}
    ) -> IndiDriver:
        """Start ``binary`` now; call :meth:`close` when done."""
        path = shutil.which(binary)
        if path is None:
            raise IndiError(f"INDI driver {binary!r} not found: install Debian's indi-bin")
        process = await asyncio.create_subprocess_exec(
            path,
            stdin=asyncio.subprocess.PIPE,
            stdout=asyncio.subprocess.PIPE,
            stderr=asyncio.subprocess.PIPE,
            env={**os.environ, "HOME": str(home), **env},
        )
        return cls(process, device)

    # --- sending ------------------------------------------------------------------------------

    async def send(self, xml: str) -> None:
        """Write raw XML to the driver's stdin."""
        assert self._process.stdin is not None
        self._process.stdin.write(xml.encode() + b"\n")
        await self._process.stdin.drain()

    async def get_properties(self) -> None:
        """Ask the driver to define all its properties."""
        await self.send('<getProperties version="1.7"/>')

    async def set_number(self, name: str, values: Mapping[str, float]) -> None:
        """Send newNumberVector."""
        await self._send_new("Number", name, {k: f"{v:.10g}" for k, v in values.items()})

    async def set_switch(self, name: str, values: Mapping[str, bool]) -> None:
        """Send newSwitchVector."""
        await self._send_new("Switch", name, {k: "On" if v else "Off" for k, v in values.items()})

    async def set_text(self, name: str, values: Mapping[str, str]) -> None:
        """Send newTextVector."""
        await self._send_new("Text", name, dict(values))

    async def _send_new(self, kind: str, name: str, values: Mapping[str, str]) -> None:
        device = self._device_for(name)
        members = "".join(
            f"<one{kind} name={quoteattr(member)}>{escape(value)}</one{kind}>"
            for member, value in values.items()
        )
        await self.send(
            f"<new{kind}Vector device={quoteattr(device)} name={quoteattr(name)}>"
            f"{members}</new{kind}Vector>"
        )

    def _device_for(self, name: str) -> str:
        known = self.properties.get(name)
        if known is not None:
            return known.device
        if self.device is None:
            raise IndiError(f"property {name} not defined yet and no device name given")
        return self.device

    # --- waiting --------------------------------------------------------------------------------

    async def wait_for(
        self,
        name: str,
        predicate: Callable[[IndiProperty], bool] = lambda _: True,
        *,
        seconds: float = 10.0,
        after: float = 0.0,
    ) -> IndiProperty:
        """The property ``name`` once it exists, satisfies ``predicate`` and (if ``after`` is
        given) was updated after that ``time.monotonic()`` instant."""
        try:
            async with asyncio.timeout(seconds):
                while True:
                    prop = self.properties.get(name)
                    if prop is not None and prop.updated_at > after and predicate(prop):
                        return prop
                    if self._reader.done():
                        raise IndiError(f"driver exited while waiting for {name}{self._log()}")
                    self._changed.clear()
                    await self._changed.wait()
        except TimeoutError:
            current = self.properties.get(name)
            raise IndiError(
                f"timed out after {seconds:g} s waiting for {name} (now {current}){self._log()}"
            ) from None

    async def wait_for_message(self, fragment: str, *, seconds: float = 10.0) -> str:
        """The first driver message containing ``fragment``."""
        try:
            async with asyncio.timeout(seconds):
                while True:
                    for message in self.messages:
                        if fragment in message:
                            return message
                    self._changed.clear()
                    await self._changed.wait()
        except TimeoutError:
            raise IndiError(f"no message with {fragment!r}{self._log()}") from None

    def _log(self) -> str:
        recent = self.messages[-15:] + self._stderr[-10:]
        return "\nrecent driver output:\n  " + "\n  ".join(recent) if recent else ""

    # --- reading -------------------------------------------------------------------------------

    async def _read_stdout(self) -> None:
        assert self._process.stdout is not None
        pending = b""
        while chunk := await self._process.stdout.read(65536):
            text, pending = _without_declarations(pending + chunk)
            self._parser.feed(text)
            events = cast("Iterator[tuple[str, ET.Element]]", self._parser.read_events())
            for kind, element in events:
                self._handle(kind, element)
            self._changed.set()
        self._changed.set()

    async def _read_stderr(self) -> None:
        assert self._process.stderr is not None
        while line := await self._process.stderr.readline():
            self._stderr.append(line.decode(errors="replace").rstrip())

    def _handle(self, event: str, element: ET.Element) -> None:
        if event == "start":
            self._depth += 1
            return
        self._depth -= 1
        if self._depth != 1:
            return
        tag = element.tag
        if tag == "message":
            self.messages.append(element.get("message", ""))
        elif tag == "delProperty":
            name = element.get("name")
            if name is None:
                self.properties.clear()
            else:
                self.properties.pop(name, None)
        else:
            self._update(tag, element)
        message = element.get("message")
        if message and tag != "message":
            self.messages.append(message)
        element.clear()

    def _update(self, tag: str, element: ET.Element) -> None:
        for prefix in _ONE_OF:
            for kind in _KINDS:
                if tag == f"{prefix}{kind}Vector":
                    name = element.get("name", "")
                    prop = self.properties.get(name)
                    if prop is None or prefix == "def":
                        prop = IndiProperty(element.get("device", ""), name, kind, "Idle")
                        self.properties[name] = prop
                    prop.state = element.get("state", prop.state)
                    for member in element:
                        member_name = member.get("name")
                        if member_name is not None:
                            prop.values[member_name] = (member.text or "").strip()
                    prop.updated_at = time.monotonic()
                    return

    # --- lifetime -------------------------------------------------------------------------------

    async def close(self) -> None:
        """Stop the driver (closing stdin ends it; kill it if it lingers)."""
        if self._process.returncode is None:
            if self._process.stdin is not None:
                self._process.stdin.close()
            try:
                async with asyncio.timeout(3.0):
                    await self._process.wait()
            except TimeoutError:
                self._process.kill()
                await self._process.wait()
        for task in (self._reader, self._stderr_reader):
            task.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await task


def _without_declarations(data: bytes) -> tuple[bytes, bytes]:
    """``data`` without ``<?xml ...?>`` declarations (drivers may write one per message), and an
    incomplete one at its end kept back for the next chunk."""
    kept = bytearray()
    while (start := data.find(b"<?")) >= 0:
        end = data.find(b"?>", start)
        if end < 0:
            return bytes(kept + data[:start]), data[start:]
        kept += data[:start]
        data = data[end + 2 :]
    if data.endswith(b"<"):
        return bytes(kept + data[:-1]), b"<"
    return bytes(kept + data), b""


class _Starting:
    def __init__(
        self,
        cls: type[IndiDriver],
        binary: str,
        home: Path,
        device: str | None,
        env: Mapping[str, str],
    ) -> None:
        self._args = (cls, binary, home, device, env)
        self._driver: IndiDriver | None = None

    async def __aenter__(self) -> IndiDriver:
        cls, binary, home, device, env = self._args
        self._driver = await cls.launch(binary, home=home, device=device, env=env)
        return self._driver

    async def __aexit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        traceback: TracebackType | None,
    ) -> None:
        if self._driver is not None:
            await self._driver.close()
