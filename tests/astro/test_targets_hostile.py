"""Hostile elements and TLE files (issue #16, docs/tracking.md "Tried to break it"): orbits
PyEphem never returns from, orbits that give no number, files that never end; each refused in
one line when read, before any place is computed."""

from __future__ import annotations

import os
import subprocess
import sys
from datetime import UTC, datetime
from pathlib import Path

import pytest

from scopelink.astro import Site
from scopelink.astro.targets import TargetError, orbit_target, satellite_target

SITE = Site(51.48, 0.0)
T0 = datetime(2026, 3, 3, 21, tzinfo=UTC)

_MPC_COMET = (
    "    CK23A030  2024 09 27.7405  {q}  {e}  308.4916   21.5585  139.1103  20240526   5.0  4.0"
    "  C/2023 A3 (Tsuchinshan-ATLAS)                            MPEC 2024-K71"
)

HANGING = {
    # PyEphem's Kepler solver never returns (nor lets Ctrl-C in) for these.
    "infinite orbit": "X,e,10,80,73,inf,0.2,0.07,145,10/17/2024,2000,H3,0.1",
    "orbit of size 0": "X,e,10,80,73,0,0.2,0.07,145,10/17/2024,2000,H3,0.1",
    "parabola through the Sun": "X,p,10/17/2024,10,80,0,73,2000,3,4",
    "parabola grazing the Sun's centre": "X,p,10/17/2024,10,80,1e-9,73,2000,3,4",
    "MPC parabola through the Sun": _MPC_COMET.format(q="0.000000", e="1.000000"),
}

_PROBE = """
import sys
from datetime import UTC, datetime
from pathlib import Path
from scopelink.astro import Site
from scopelink.astro.targets import TargetError, orbit_target
for path in sys.argv[1:]:
    try:
        orbit_target("X", Path(path), Site(51.48, 0.0)).position(datetime(2026, 3, 3, tzinfo=UTC))
        print("accepted", path)
    except TargetError as error:
        print("refused", error)
"""


def test_orbits_pyephem_never_returns_from_and_endless_files_are_refused(tmp_path: Path) -> None:
    """In a subprocess: before this fix it hung here (the first line, and a FIFO nobody writes
    to blocked the read; /dev/zero filled the memory)."""
    paths = []
    for index, line in enumerate(HANGING.values()):
        path = tmp_path / f"hang{index}.txt"
        path.write_text(line + "\n")
        paths.append(str(path))
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)
    paths.append(str(fifo))
    answer = subprocess.run(
        [sys.executable, "-c", _PROBE, *paths],
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )
    lines = answer.stdout.splitlines()
    assert len(lines) == len(paths), answer.stdout + answer.stderr
    assert all(line.startswith("refused") for line in lines), answer.stdout
    assert "perihelion distance 0 au must lie within 0.001-1e+06 au" in answer.stdout
    assert lines[-1].endswith("fifo: not a regular file")
    with pytest.raises(TargetError, match="not a regular file"):
        satellite_target("ISS", Path("/dev/zero"), SITE)


@pytest.mark.parametrize(
    ("line", "message"),
    [
        (_MPC_COMET.format(q="0.000000", e="0.500000"), "perihelion distance 0 au"),  # 1/0
        (_MPC_COMET.format(q="     nan", e="     nan"), "hold 'nan', not a number"),
        ("X,e,10,80,73,2.7,0.2,1.5,145,10/17/2024,2000,H3,0.1", "eccentricity in \\[0, 1\\)"),
        ("X,h,10/17/2024,10,80,73,0.5,0.5,2000,3,4", "eccentricity above 1"),
        ("X,f,10:00:00,20:00:00,3,2000", "FixedBody is no orbit"),
        ("X,e,10,80,73,2.7,,0.9999999,145,10/17/2024,2000,H3,0.1", "perihelion distance 2.7e-07"),
    ],
)
def test_orbits_without_a_place_are_refused_in_one_line(
    tmp_path: Path, line: str, message: str
) -> None:
    """These gave ZeroDivisionError, NaN places (driving the follower's clamp to the mount's
    largest rate), an AttributeError or PyEphem's RuntimeError: tracebacks, not one line."""
    path = tmp_path / "bad.txt"
    path.write_text(line + "\n")
    name = "C/2023 A3" if "C/2023" in line else "X"
    with pytest.raises(TargetError, match=message) as refused:
        orbit_target(name, path, SITE).position(T0)
    assert "line 1" in str(refused.value)
    assert "\n" not in str(refused.value)


def test_the_tracking_page_states_the_file_and_orbit_limits() -> None:
    from scopelink.astro.targets.base import MAX_FILE_BYTES
    from scopelink.astro.targets.elements import MAX_ORBIT_AU, MIN_PERIHELION_AU
    from scopelink.mount.follow import MAX_DURATION_S, MAX_INTERVAL_S
    from scopelink.mount.follow_plan import MAX_TLE_AGE_DAYS

    docs = Path(__file__).resolve().parents[2] / "docs" / "tracking.md"
    text = " ".join(docs.read_text(encoding="utf-8").split())
    assert f"`MIN_PERIHELION_AU` = {MIN_PERIHELION_AU:g} au" in text
    assert f"`MAX_ORBIT_AU` = {MAX_ORBIT_AU:g} au" in text
    assert f"`MAX_FILE_BYTES` = {MAX_FILE_BYTES // 2**20} MiB" in text
    assert f"`MAX_INTERVAL_S` = {MAX_INTERVAL_S:g} s" in text
    assert f"`MAX_DURATION_S` = {MAX_DURATION_S / 86400:g} days" in text
    assert f"`MAX_TLE_AGE_DAYS` = {MAX_TLE_AGE_DAYS:g} days" in text
