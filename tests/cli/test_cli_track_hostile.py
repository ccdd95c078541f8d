"""``scopelink track`` given hostile arguments (issue #16, docs/tracking.md "Tried to break
it"): each refused in one line with no traceback, before anything moves."""

from __future__ import annotations

from pathlib import Path

from tests.support.cli import scopelink_here

_Q0_COMET = (
    "    CK23A030  2024 09 27.7405  0.000000  0.500000  308.4916   21.5585  139.1103  20240526"
    "   5.0  4.0  C/2023 A3 (Tsuchinshan-ATLAS)                            MPEC 2024-K71\n"
)


def _refused(config: Path, *args: str) -> str:
    status, out, err = scopelink_here(config, "track", *args, "--device", "sim")
    assert status != 0, out
    assert err.startswith("scopelink track: "), err
    assert "Traceback" not in err
    assert "following" not in out  # nothing started
    return err.splitlines()[0]


def test_hostile_track_arguments_are_refused_in_one_line(config: Path, tmp_path: Path) -> None:
    """``--duration inf`` and ``1e300`` raised OverflowError after the goto, ``--interval inf``
    ERFA's "unacceptable date"; a comet whose perihelion is 0 raised ZeroDivisionError."""
    for option, value in (
        ("--duration", "inf"),
        ("--duration", "1e300"),
        ("--interval", "inf"),
        ("--interval", "1e300"),
    ):
        line = _refused(config, "moon", option, value)
        assert f"{option} must be a number of seconds in (0, " in line, line
    elements = tmp_path / "q0.txt"
    elements.write_text(_Q0_COMET)
    line = _refused(config, "comet", "C/2023 A3", "--elements", str(elements))
    assert "line 1: not an MPC one-line or XEphem orbit (perihelion distance 0 au" in line
    line = _refused(config, "comet", "C/2023 A3", "--elements", str(tmp_path))
    assert "it is a directory" in line
    line = _refused(config, "satellite", "ISS", "--tle", str(tmp_path / "missing.tle"))
    assert "cannot read TLE file" in line
    assert "No such file or directory" in line
