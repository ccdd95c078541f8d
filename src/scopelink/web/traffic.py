"""The live traffic panel: lines of the ``scopelink.links.trace`` logger, each with the decoded
meaning of the messages it completes.

Every link gets its own annotating session (``scopelink.decode``), fed byte by byte as the trace
goes, so a reply split over several reads is decoded once it is whole. Which side of a link
this process is on decides who sent a byte: on the links a driver opens (a serial port,
``tcp host:port``) this process is the PC; on the links a device server accepts (the master side
of a pseudo-terminal, ``tcp peer on :port``) it is the device. Only the last ``capacity`` lines
are kept.
"""

from __future__ import annotations

import itertools
import logging
import re
import threading
import time
from collections import deque
from collections.abc import Callable, Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass

from scopelink.decode import Annotation, Direction, Protocol
from scopelink.decode.session import Session
from scopelink.decode.skytracker_session import SkyTrackerSession
from scopelink.decode.synscan_session import SynScanSession
from scopelink.links.trace import escape_text, trace_logger

__all__ = [
    "ProtocolChooser",
    "TrafficLine",
    "TrafficMonitor",
    "parse_trace_line",
    "protocol_by_port",
]

DEFAULT_CAPACITY = 200
MAX_DECODED_LINKS = 64
"""Links whose decoding state is kept; the least recently heard is forgotten beyond (every client
connection of a server is a new link: a long-running serve must not keep them all)."""

ProtocolChooser = Callable[[str], Protocol | None]
"""Which protocol a link (by its trace name) speaks; None: show its bytes undecoded."""

_LINE = re.compile(r"^(?P<link>.+) (?P<arrow>-->|<--) \d+ bytes?: (?P<hex>[0-9a-f ]*) \| ")


@dataclass(frozen=True, slots=True)
class TrafficLine:
    """One transfer as the panel shows it: what went which way, and what it meant."""

    seq: int
    at: float  # UNIX time of the transfer, for the browser's clock display
    link: str
    sender: Direction
    data: bytes
    meanings: tuple[tuple[str, str], ...]  # (kind, meaning) of each message completed here

    def as_json(self) -> dict[str, object]:
        return {
            "seq": self.seq,
            "at": self.at,
            "link": self.link,
            "from": self.sender.value,
            "hex": self.data.hex(" "),
            "text": escape_text(self.data),
            "meanings": [{"kind": kind, "text": text} for kind, text in self.meanings],
        }


def parse_trace_line(message: str) -> tuple[str, str, bytes] | None:
    """(link name, arrow, bytes) of a trace line as ``scopelink.links.trace`` writes it."""
    match = _LINE.match(message)
    if match is None:
        return None
    try:
        data = bytes.fromhex(match["hex"])
    except ValueError:
        return None
    return match["link"], match["arrow"], data


_ACCEPTED_ON_PORT = re.compile(r" on :(\d+)$")


def protocol_by_port(
    ports: Mapping[int, Protocol], others: Protocol | None = None
) -> ProtocolChooser:
    """A chooser for a process serving several protocols: connections accepted on a port of
    ``ports`` are decoded as its protocol, every other link as ``others`` (None: undecoded).

    ``scopelink serve`` with SynScan on 11880 and LX200 on 4030:
    ``protocol_by_port({11880: Protocol.SYNSCAN})``.
    """

    def choose(link_name: str) -> Protocol | None:
        match = _ACCEPTED_ON_PORT.search(link_name)
        if match is not None:
            return ports.get(int(match[1]))
        return others

    return choose


def this_process_is_device(link_name: str) -> bool:
    """Whether this process is the device end of the link (an emulator's pty or accepted TCP)."""
    return link_name.startswith("pty ") or " on :" in link_name


def _new_session(protocol: Protocol) -> Session:
    if protocol is Protocol.SYNSCAN:
        return SynScanSession()
    return SkyTrackerSession(behind_bus=protocol is Protocol.SKYTRACKER)


class _LinkDecoder:
    def __init__(self, protocol: Protocol | None) -> None:
        self._session = None if protocol is None else _new_session(protocol)
        self._offset = 0

    def feed(self, sender: Direction, data: bytes) -> list[Annotation]:
        session = self._session
        if session is None:
            return []
        for byte in data:
            if sender is Direction.PC:
                session.from_pc(byte, self._offset)
            else:
                session.from_device(byte, self._offset)
            self._offset += 1
        done = list(session.annotations)
        session.annotations.clear()  # only the new ones matter; the list would grow forever
        return done


class TrafficMonitor(logging.Handler):
    """A logging handler on ``scopelink.links.trace`` that keeps the last lines, decoded.

    :meth:`attached` installs it and makes the trace logger emit DEBUG records for as long as it
    is attached. If nobody else had asked for the trace, its records are kept from propagating
    to the root logger, so the console is not flooded; both settings are restored on exit.
    """

    def __init__(
        self, protocol: Protocol | ProtocolChooser, capacity: int = DEFAULT_CAPACITY
    ) -> None:
        super().__init__(logging.DEBUG)
        self.protocol_for: ProtocolChooser = (
            (lambda _link: protocol) if isinstance(protocol, Protocol) else protocol
        )
        self._lines: deque[TrafficLine] = deque(maxlen=capacity)
        self._lines_lock = threading.Lock()
        self._decoders: dict[str, _LinkDecoder] = {}
        self._seq = itertools.count(1)

    def emit(self, record: logging.LogRecord) -> None:
        try:
            parsed = parse_trace_line(record.getMessage())
        except Exception:  # a logging handler must never raise into the link that logged
            self.handleError(record)
            return
        if parsed is None:
            return
        link, arrow, data = parsed
        sent_by_us = arrow == "-->"
        we_are_device = this_process_is_device(link)
        sender = Direction.DEVICE if sent_by_us == we_are_device else Direction.PC
        decoder = self._decoders.pop(link, None)
        if decoder is None:
            if len(self._decoders) >= MAX_DECODED_LINKS:
                del self._decoders[next(iter(self._decoders))]  # the least recently used
            decoder = _LinkDecoder(self.protocol_for(link))
        self._decoders[link] = decoder  # the most recently used last
        try:
            annotations = decoder.feed(sender, data)
        except Exception:  # the decoder never raises by contract; keep the line if it does
            annotations = []
            self.handleError(record)
        line = TrafficLine(
            seq=next(self._seq),
            at=record.created or time.time(),
            link=link,
            sender=sender,
            data=data,
            meanings=tuple((a.kind.value, a.meaning) for a in annotations),
        )
        with self._lines_lock:
            self._lines.append(line)

    def since(self, seq: int) -> list[TrafficLine]:
        """The kept lines newer than ``seq`` (0: all of them), oldest first."""
        with self._lines_lock:  # emit() may run on another thread (a blocking facade's loop)
            return [line for line in self._lines if line.seq > seq]

    @contextmanager
    def attached(self) -> Iterator[TrafficMonitor]:
        """Receive the byte trace for the body of the ``with``."""
        previous_level = trace_logger.level
        previous_propagate = trace_logger.propagate
        someone_else_traces = trace_logger.isEnabledFor(logging.DEBUG)
        trace_logger.addHandler(self)
        if not someone_else_traces:
            trace_logger.setLevel(logging.DEBUG)
            trace_logger.propagate = False
        try:
            yield self
        finally:
            trace_logger.removeHandler(self)
            trace_logger.setLevel(previous_level)
            trace_logger.propagate = previous_propagate
