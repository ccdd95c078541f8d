"""Fault injection for device emulators: misbehave on purpose, the way real serial devices do.

A :class:`FaultInjector` holds :class:`Fault` rules. A server asks it, once per received command,
which fault (if any) applies (:meth:`FaultInjector.select`), then hands its reply bytes to
:meth:`FaultInjector.deliver`, which writes them faithfully or not. The kinds follow INDIGO's
NexStar simulator:

========== ==============================================================================
drop       the command gets no reply
short      the reply is cut short: every byte but the last is sent
malformed  the reply's first and last bytes get their top bit flipped (terminator lost)
delay      the reply is sent after ``seconds`` (default 6 s, beyond the spec's 5 s)
slow       the reply is sent byte by byte, ``seconds`` apart (default 0.1 s)
stall      no reply to this command nor to any later one until :meth:`FaultInjector.resume`;
           input is still read (and discarded)
halt       no reply, and the server stops reading until :meth:`FaultInjector.resume`;
           input piles up and is processed after resuming
close      the connection is closed instead of replying
========== ==============================================================================

Rules match one command key (the command's first byte as text, e.g. ``"e"``) or :data:`ANY`.
Each fires ``times`` times (``None``: without end), each time with ``probability``, drawn from a
seeded random generator so a run can be replayed. Rules are written on the command line as
``COMMAND:KIND[=SECONDS][:once|:always|:times=N][:p=P]`` (see :meth:`Fault.parse`).
"""

from __future__ import annotations

import asyncio
import enum
import logging
import math
import random
from collections.abc import Iterable
from dataclasses import dataclass

from scopelink.links import Link

__all__ = ["ANY", "Fault", "FaultInjector", "FaultKind", "FaultSpecError", "FiredFault"]

logger = logging.getLogger(__name__)

ANY = "any"
"""The command key that matches every command."""

_TOP_BIT = 0x80


class FaultKind(enum.StrEnum):
    """How a reply goes wrong."""

    DROP = "drop"
    SHORT = "short"
    MALFORMED = "malformed"
    DELAY = "delay"
    SLOW = "slow"
    STALL = "stall"
    HALT = "halt"
    CLOSE = "close"


_DEFAULT_SECONDS = {FaultKind.DELAY: 6.0, FaultKind.SLOW: 0.1}


class FaultSpecError(ValueError):
    """A fault written as text (``--fault``) does not parse; the message shows the syntax."""


_SYNTAX = "COMMAND:KIND[=SECONDS][:once|:always|:times=N][:p=P], e.g. e:drop or any:delay=6:p=0.1"


@dataclass(frozen=True, slots=True)
class Fault:
    """One rule: on ``command`` (or :data:`ANY`), misbehave as ``kind``.

    ``seconds`` is the delay (``delay``) or the gap between bytes (``slow``); other kinds ignore
    it. ``times`` is how often the rule fires (``None``: every time it is drawn); ``probability``
    is the chance it fires on each matching command.
    """

    kind: FaultKind
    command: str = ANY
    seconds: float | None = None
    times: int | None = 1
    probability: float = 1.0

    def __post_init__(self) -> None:
        if not self.command:
            raise ValueError("a fault needs a command key, or 'any'")
        if self.seconds is not None and not (math.isfinite(self.seconds) and self.seconds >= 0):
            raise ValueError(f"fault seconds must be a non-negative number, not {self.seconds}")
        if self.times is not None and self.times < 1:
            raise ValueError(f"a fault fires at least once, not {self.times} times")
        if not 0.0 < self.probability <= 1.0:
            raise ValueError(f"fault probability must lie in (0, 1], not {self.probability}")

    @property
    def duration(self) -> float:
        """``seconds``, or the kind's default (6 s delay, 0.1 s between slow bytes)."""
        if self.seconds is not None:
            return self.seconds
        return _DEFAULT_SECONDS.get(self.kind, 0.0)

    def matches(self, command: str) -> bool:
        """Whether this rule applies to a command with key ``command``."""
        return self.command in (ANY, command)

    @classmethod
    def parse(cls, text: str) -> Fault:
        """A fault from ``COMMAND:KIND[=SECONDS][:once|:always|:times=N][:p=P]``.

        ``COMMAND`` is a command key (its first byte, e.g. ``e``) or ``any``. Without a count the
        rule fires once, or (when ``p`` is given) without end.
        """
        parts = text.split(":")
        if len(parts) < 2:
            raise FaultSpecError(f"fault {text!r}: expected {_SYNTAX}")
        command, kind_text, *options = parts
        kind_name, _, seconds_text = kind_text.partition("=")
        try:
            kind = FaultKind(kind_name.strip().lower())
        except ValueError:
            kinds = ", ".join(k.value for k in FaultKind)
            raise FaultSpecError(f"fault {text!r}: unknown kind {kind_name!r} ({kinds})") from None
        seconds = _number(text, "seconds", seconds_text) if seconds_text else None
        times: int | None = 1
        count_given = False
        probability = 1.0
        for option in options:
            name, _, value = option.partition("=")
            match name.strip().lower(), value:
                case "once", "":
                    times, count_given = 1, True
                case "always", "":
                    times, count_given = None, True
                case "times", _ if value:
                    times, count_given = int(_number(text, "times", value)), True
                case "p", _ if value:
                    probability = _number(text, "p", value)
                case _:
                    raise FaultSpecError(f"fault {text!r}: unknown option {option!r}; {_SYNTAX}")
        if probability < 1.0 and not count_given:
            times = None
        try:
            return cls(kind, command.strip() or ANY, seconds, times, probability)
        except ValueError as error:
            raise FaultSpecError(f"fault {text!r}: {error}") from None

    def __str__(self) -> str:
        seconds = f"={self.seconds:g}" if self.seconds is not None else ""
        count = "always" if self.times is None else f"times={self.times}"
        chance = f":p={self.probability:g}" if self.probability < 1.0 else ""
        return f"{self.command}:{self.kind.value}{seconds}:{count}{chance}"


def _number(text: str, name: str, value: str) -> float:
    try:
        return float(value)
    except ValueError:
        raise FaultSpecError(f"fault {text!r}: {name} must be a number, not {value!r}") from None


@dataclass(frozen=True, slots=True)
class FiredFault:
    """A record of a fault that fired: which rule, on which command."""

    fault: Fault
    command: str


@dataclass(slots=True)
class _Rule:
    fault: Fault
    remaining: int | None


class FaultInjector:
    """The fault rules of one emulated device, and its stalled/halted state.

    Shared by every connection to that device. From tests: ``injector.add(Fault(...))``,
    ``injector.fired`` to see what fired, ``injector.resume()`` to end a stall or halt.
    ``seed`` makes probabilistic rules repeatable.
    """

    def __init__(self, faults: Iterable[Fault] = (), *, seed: int | None = None) -> None:
        self._rules: list[_Rule] = []
        self._random = random.Random(seed)
        self._stalled = False
        self._running: asyncio.Event | None = None
        self.fired: list[FiredFault] = []
        """Every fault that fired, oldest first."""
        for fault in faults:
            self.add(fault)

    @property
    def faults(self) -> tuple[Fault, ...]:
        """The rules that can still fire, in the order they are tried."""
        return tuple(rule.fault for rule in self._rules)

    @property
    def stalled(self) -> bool:
        """True while a ``stall`` fault holds every reply back."""
        return self._stalled

    @property
    def halted(self) -> bool:
        """True while a ``halt`` fault keeps the server from reading."""
        return self._running is not None and not self._running.is_set()

    def add(self, fault: Fault) -> Fault:
        """Add a rule (tried after the existing ones); returns it, for :meth:`remove`."""
        self._rules.append(_Rule(fault, fault.times))
        return fault

    def remove(self, fault: Fault) -> None:
        """Remove the first rule equal to ``fault`` (no error if it already fired out)."""
        for index, rule in enumerate(self._rules):
            if rule.fault == fault:
                del self._rules[index]
                return

    def clear(self) -> None:
        """Remove every rule and resume from a stall or halt."""
        self._rules.clear()
        self.resume()

    def resume(self) -> None:
        """End a stall or halt: the device reads and answers again."""
        self._stalled = False
        if self._running is not None:
            self._running.set()

    def select(self, command: str) -> Fault | None:
        """The fault that applies to the command with key ``command``, or None.

        Tries the rules in order; the first matching one that fires (by its probability) is used
        up once and returned. Stall and halt take effect here. While stalled, every command gets
        a ``stall`` fault (without using up any rule).
        """
        if self._stalled:
            return Fault(FaultKind.STALL, command, times=None)
        for index, rule in enumerate(self._rules):
            fault = rule.fault
            if not fault.matches(command):
                continue
            if fault.probability < 1.0 and self._random.random() >= fault.probability:
                continue
            if rule.remaining is not None:
                rule.remaining -= 1
                if rule.remaining == 0:
                    del self._rules[index]
            self._fire(fault, command)
            return fault
        return None

    def _fire(self, fault: Fault, command: str) -> None:
        logger.info("fault %s fires on %r", fault, command)
        self.fired.append(FiredFault(fault, command))
        if fault.kind is FaultKind.STALL:
            self._stalled = True
        elif fault.kind is FaultKind.HALT:
            if self._running is None:
                self._running = asyncio.Event()
            self._running.clear()

    async def wait_until_reading(self) -> None:
        """Return once the server may read (at once unless a ``halt`` fault is in force)."""
        if self._running is not None:
            await self._running.wait()

    async def deliver(self, link: Link, reply: bytes, fault: Fault | None) -> bool:
        """Write ``reply`` to ``link`` as ``fault`` (from :meth:`select`) dictates.

        Returns False when the fault closed the link (the server should stop serving it).
        """
        match None if fault is None else fault.kind:
            case None:
                await link.write(reply)
            case FaultKind.DROP | FaultKind.STALL | FaultKind.HALT:
                pass
            case FaultKind.SHORT:
                await link.write(reply[:-1])
            case FaultKind.MALFORMED:
                await link.write(corrupt(reply))
            case FaultKind.DELAY:
                assert fault is not None
                await asyncio.sleep(fault.duration)
                await link.write(reply)
            case FaultKind.SLOW:
                assert fault is not None
                for index in range(len(reply)):
                    if index:
                        await asyncio.sleep(fault.duration)
                    await link.write(reply[index : index + 1])
            case FaultKind.CLOSE:
                await link.close()
                return False
        return True


def corrupt(reply: bytes) -> bytes:
    """``reply`` with the top bit of its first and last bytes flipped.

    Every reply of both protocols is then wrong where a reader checks it: the first byte is no
    longer ASCII and the terminator is no longer what it was.
    """
    if not reply:
        return reply
    corrupted = bytearray(reply)
    corrupted[0] ^= _TOP_BIT
    if len(corrupted) > 1:
        corrupted[-1] ^= _TOP_BIT
    return bytes(corrupted)
