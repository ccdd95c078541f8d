"""The other end of `Command.dispatch`: whatever answers SynScan commands (an emulated hand
control) implements one method per command class, named after the class in snake case
(`GetRaDec` -> ``get_ra_dec``). A new command class adds a method here, so a type checker finds
every handler that does not answer it yet."""

from __future__ import annotations

from typing import Protocol, TypeVar

from scopelink.protocol.synscan.commands import (
    CancelGoto,
    Echo,
    GetAzAlt,
    GetLocation,
    GetModel,
    GetPointingState,
    GetRaDec,
    GetTime,
    GetTrackingMode,
    GetVersion,
    GotoAzAlt,
    GotoRaDec,
    IsAligned,
    IsGotoInProgress,
    SetLocation,
    SetTime,
    SetTrackingMode,
    SyncRaDec,
)
from scopelink.protocol.synscan.passthrough import (
    FixedRateSlew,
    GetDeviceVersion,
    Passthrough,
    SetAxisPosition,
    SlowGoto,
    VariableRateSlew,
)

T_co = TypeVar("T_co", covariant=True)


class CommandHandler(Protocol[T_co]):
    """Answers each SynScan command; ``T_co`` is what an answer is (e.g. an awaitable reply)."""

    def get_ra_dec(self, command: GetRaDec, /) -> T_co: ...

    def get_az_alt(self, command: GetAzAlt, /) -> T_co: ...

    def goto_ra_dec(self, command: GotoRaDec, /) -> T_co: ...

    def goto_az_alt(self, command: GotoAzAlt, /) -> T_co: ...

    def sync_ra_dec(self, command: SyncRaDec, /) -> T_co: ...

    def get_tracking_mode(self, command: GetTrackingMode, /) -> T_co: ...

    def set_tracking_mode(self, command: SetTrackingMode, /) -> T_co: ...

    def variable_rate_slew(self, command: VariableRateSlew, /) -> T_co: ...

    def fixed_rate_slew(self, command: FixedRateSlew, /) -> T_co: ...

    def get_device_version(self, command: GetDeviceVersion, /) -> T_co: ...

    def slow_goto(self, command: SlowGoto, /) -> T_co: ...

    def set_axis_position(self, command: SetAxisPosition, /) -> T_co: ...

    def passthrough(self, command: Passthrough, /) -> T_co: ...

    def get_location(self, command: GetLocation, /) -> T_co: ...

    def set_location(self, command: SetLocation, /) -> T_co: ...

    def get_time(self, command: GetTime, /) -> T_co: ...

    def set_time(self, command: SetTime, /) -> T_co: ...

    def get_version(self, command: GetVersion, /) -> T_co: ...

    def get_model(self, command: GetModel, /) -> T_co: ...

    def echo(self, command: Echo, /) -> T_co: ...

    def is_aligned(self, command: IsAligned, /) -> T_co: ...

    def is_goto_in_progress(self, command: IsGotoInProgress, /) -> T_co: ...

    def cancel_goto(self, command: CancelGoto, /) -> T_co: ...

    def get_pointing_state(self, command: GetPointingState, /) -> T_co: ...
