"""How the command line shows a mount's state: rows for a table, and a JSON form for scripts."""

from __future__ import annotations

from typing import Any

from rich.table import Table

from scopelink.astro import format_degrees, format_hours
from scopelink.mount import Mount, MountState, PierSide

__all__ = ["position_text", "state_json", "state_rows", "state_table"]

_PIER_SIDES = {PierSide.EAST: "east", PierSide.WEST: "west", PierSide.UNKNOWN: "unknown"}
_UNKNOWN = "-"


def _hours(value: float | None) -> str:
    return _UNKNOWN if value is None else format_hours(value, decimals=1)


def _degrees(value: float | None, width: int = 2) -> str:
    return _UNKNOWN if value is None else format_degrees(value, decimals=0, width=width)


def _azimuth(value: float | None) -> str:
    """Azimuth in [0, 360) as shown: 359.99999° rounds to 000°00'00", not 360°."""
    if value is None:
        return _UNKNOWN
    wrapped = value % 360.0
    if round(wrapped * 3600.0) >= 360 * 3600:
        wrapped = 0.0
    return format_degrees(wrapped, decimals=0, width=3)


def _yes_no(value: bool) -> str:
    return "yes" if value else "no"


def state_rows(state: MountState) -> list[tuple[str, str]]:
    """Label and value of every line of the status table."""
    rows = [
        ("RA / Dec J2000", f"{_hours(state.ra_j2000_hours)}  {_degrees(state.dec_j2000_deg)}"),
        (
            "RA / Dec of date",
            f"{_hours(state.ra_of_date_hours)}  {_degrees(state.dec_of_date_deg)}",
        ),
        ("Alt / Az", f"{_degrees(state.alt_deg)}  {_azimuth(state.az_deg)}"),
        ("pier side", _PIER_SIDES.get(state.pier_side, str(state.pier_side))),
        ("slewing", _yes_no(state.slewing)),
        ("tracking", state.tracking.value),
        ("parked", _yes_no(state.parked)),
        ("read at", state.read_at.strftime("%Y-%m-%d %H:%M:%S UTC")),
        ("reading age", f"{state.position_age_s():.1f} s"),
    ]
    if not state.connected:
        rows.append(("connected", "no"))
    rows.extend(("problem", problem) for problem in state.problems)
    return rows


def state_table(mount: Mount, state: MountState) -> Table:
    """The status table, titled with who the mount is."""
    identity = mount.identity
    title = " ".join(part for part in (identity.model, identity.firmware) if part)
    table = Table(title=f"{title} on {identity.link}", show_header=False, title_justify="left")
    table.add_column("what", style="bold")
    table.add_column("value")
    for label, value in state_rows(state):
        table.add_row(label, value)
    return table


def position_text(state: MountState) -> str:
    """One line: where the mount points."""
    return (
        f"RA {_hours(state.ra_j2000_hours)} Dec {_degrees(state.dec_j2000_deg)} (J2000), "
        f"Alt {_degrees(state.alt_deg)} Az {_azimuth(state.az_deg)}"
    )


def state_json(state: MountState) -> dict[str, Any]:
    """The state as plain JSON values (degrees and hours as numbers)."""
    return {
        "read_at": state.read_at.isoformat(),
        "age_s": round(state.position_age_s(), 3),
        "connected": state.connected,
        "ra_j2000_hours": state.ra_j2000_hours,
        "dec_j2000_deg": state.dec_j2000_deg,
        "ra_of_date_hours": state.ra_of_date_hours,
        "dec_of_date_deg": state.dec_of_date_deg,
        "alt_deg": state.alt_deg,
        "az_deg": state.az_deg,
        "pier_side": _PIER_SIDES.get(state.pier_side, str(state.pier_side)),
        "slewing": state.slewing,
        "tracking": state.tracking.value,
        "parked": state.parked,
        "aligned": state.aligned,
        "pulse_guiding": state.pulse_guiding,
        "problems": list(state.problems),
    }
