"""One ITelescopeV4 member: the vocabulary of the member table.

Each member group (``common``, ``capabilities``, ``position``, ``tracking``, ``slewing``,
``parking``, ``motion``, ``site``) returns a ``dict`` from the member's lower-case URL name to a
:class:`Member`; :class:`~scopelink.servers.alpaca.telescope.device.TelescopeDevice` joins them.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Callable
from dataclasses import dataclass

from scopelink.servers.alpaca.errors import AlpacaError, ErrorNumber
from scopelink.servers.alpaca.params import Params
from scopelink.servers.alpaca.telescope.session import TelescopeSession

__all__ = ["Handler", "Member", "MemberGroup", "fixed", "not_implemented"]

Handler = Callable[[Params], object]
"""Takes the request's parameters; returns the Value (or an awaitable of it), None for none."""


@dataclass(frozen=True, slots=True)
class Member:
    """One ITelescopeV4 member: its GET and PUT handlers and whether it needs a connection."""

    get: Handler | None = None
    put: Handler | None = None
    needs_connection: bool = True


class MemberGroup(ABC):
    """One ASCOM group of members over the shared ``session``."""

    def __init__(self, session: TelescopeSession) -> None:
        self.session = session

    @abstractmethod
    def members(self) -> dict[str, Member]:
        """The group's members, keyed by lower-case URL name."""


def fixed(value: object) -> Member:
    """A read-only member whose value never changes (answered without a connection)."""
    return Member(get=lambda _: value, needs_connection=False)


def not_implemented(what: str) -> Handler:
    """A handler that answers NotImplemented (0x400) naming ``what``."""

    def handler(_: Params) -> object:
        raise AlpacaError(ErrorNumber.NOT_IMPLEMENTED, f"{what} is not implemented by this mount")

    return handler
