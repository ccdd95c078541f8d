"""Byte links: serial ports, TCP, pseudo-terminals and in-memory pairs, with optional wire pacing.

Every link is a :class:`Link`: ``await read(n)``, ``await write(data)``, ``await close()``.
Set the ``scopelink.links.trace`` logger to DEBUG to see every byte in hex.
"""

from scopelink.links.base import (
    DEFAULT_BAUDRATE,
    Link,
    LinkClosedError,
    LinkError,
    LinkOpenError,
    LinkSpecError,
)
from scopelink.links.loops import (
    DEFAULT_EVENT_LOOP,
    EVENT_LOOP_CHOICES,
    EVENT_LOOP_ENV_VAR,
    EventLoopChoice,
    EventLoopChoiceError,
    choose_event_loop,
    describe_loop,
    serve_event_loop,
)
from scopelink.links.memory import MemoryLink, memory_pair
from scopelink.links.pacing import PacedLink, paced, precise_event_loop
from scopelink.links.pty import LineSettings, PtyLink, open_pty
from scopelink.links.serial import SerialLink, open_serial
from scopelink.links.tcp import ConnectionHandler, TcpLink, TcpServer, open_tcp, serve_tcp
from scopelink.links.tcp_client import TcpClientLink
from scopelink.links.url import open_link

__all__ = [
    "DEFAULT_BAUDRATE",
    "DEFAULT_EVENT_LOOP",
    "EVENT_LOOP_CHOICES",
    "EVENT_LOOP_ENV_VAR",
    "ConnectionHandler",
    "EventLoopChoice",
    "EventLoopChoiceError",
    "LineSettings",
    "Link",
    "LinkClosedError",
    "LinkError",
    "LinkOpenError",
    "LinkSpecError",
    "MemoryLink",
    "PacedLink",
    "PtyLink",
    "SerialLink",
    "TcpClientLink",
    "TcpLink",
    "TcpServer",
    "choose_event_loop",
    "describe_loop",
    "memory_pair",
    "open_link",
    "open_pty",
    "open_serial",
    "open_tcp",
    "paced",
    "precise_event_loop",
    "serve_event_loop",
    "serve_tcp",
]
