"""Stops the hand control may not have received: owed until the link works again.

When a motion command or a stop fails on a broken link (a timeout the retry did not cure, a hung
hand control, a closed port), the driver cannot tell whether the hand control carried it out: a
goto may be running, an axis may still turn at a rate the user meant to stop, a guide pulse may
never end. The user was told the command failed, so the safe state to return to is a stopped
mount. The same holds when the polls fail while an axis turns at a rate: the motion runs blind,
and nobody could stop it in time. :class:`OwedStops` remembers what to send (``M`` for a goto,
rate 0 per axis) until the driver has sent it successfully, before anything else, on the next
exchange that gets through. Decisions: ``docs/reliability-faults-synscan.md``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from scopelink.mount import MountAxis

__all__ = ["OwedStops"]


@dataclass(slots=True)
class OwedStops:
    """What must still be stopped, and the failure that left it so."""

    cancel_goto: bool = False
    axes: set[MountAxis] = field(default_factory=set)
    cause: str = ""

    def __bool__(self) -> bool:
        return self.cancel_goto or bool(self.axes)

    def owe(self, *, cancel_goto: bool, axes: set[MountAxis], cause: str) -> None:
        """Add stops that the failure ``cause`` left unconfirmed."""
        self.cancel_goto |= cancel_goto
        self.axes |= axes
        self.cause = cause

    def clear(self) -> None:
        self.cancel_goto = False
        self.axes.clear()
        self.cause = ""

    def describe(self) -> str:
        """What is owed, for ``problems`` and logs."""
        parts = ["the goto"] if self.cancel_goto else []
        parts += [f"the {axis.name.lower()} axis" for axis in sorted(self.axes, key=_order)]
        return (
            f"stop of {' and '.join(parts)} not confirmed ({self.cause}): it is sent again as "
            "soon as the hand control answers"
        )


def _order(axis: MountAxis) -> int:
    return axis.value
