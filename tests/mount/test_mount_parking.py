"""The park record (scopelink.mount.parking, docs/parking.md): written once the mount arrives
parked, read back and consumed by unpark, a bad file reported in one line and never replaced."""

from __future__ import annotations

import json
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import pytest

from scopelink.astro import Site
from scopelink.mount import ParkPosition, PierSide
from scopelink.mount.parking import PARK_RECORD, ParkRecord, ParkRecordError
from scopelink.sim import EQ6, SimClock, SimulatedMount

SITE = Site(50.0, 10.0)
START = datetime(2026, 3, 1, 22, 0, tzinfo=UTC)


class CorrectedSim(SimulatedMount):
    """A mount that keeps a PC-side pointing correction (the hook issue #15 part 1 fills)."""

    correction: dict[str, Any] | None = None

    def pointing_correction_record(self) -> dict[str, Any] | None:
        return self.correction

    def restore_pointing_correction(self, record: dict[str, Any]) -> None:
        self.correction = record


def _records(directory: Path) -> list[Path]:
    return list(directory.rglob(f"{PARK_RECORD}.json"))


async def _parked(mount: SimulatedMount, state_dir: Path | None) -> None:
    if state_dir is not None:
        mount.park_keeper.enable(state_dir)
    await mount.connect()
    mount.park_position = ParkPosition(30.0, 200.0)
    await mount.park()
    mount.step(600.0)
    assert mount.state.parked


async def test_the_record_is_written_on_arrival_and_used_once(tmp_path: Path) -> None:
    mount = CorrectedSim(EQ6, site=SITE, clock=SimClock.stepped(START))
    mount.correction = {"terms": {"IH": 0.1}}
    mount.park_keeper.enable(tmp_path)
    await mount.connect()
    mount.park_position = ParkPosition(30.0, 200.0)
    await mount.park()
    assert not _records(tmp_path)  # on its way: nothing yet
    mount.step(600.0)
    [path] = _records(tmp_path)
    data = json.loads(path.read_text())
    assert (data["alt_deg"], data["az_deg"]) == pytest.approx((30.0, 200.0), abs=1e-6)
    assert data["correction"] == {"terms": {"IH": 0.1}}
    assert data["aligned"] is True

    mount.correction = None
    resume = await mount.unpark()
    assert resume.restored
    assert "keeps its own position" in resume.message
    assert mount.pointing_correction_record() == {"terms": {"IH": 0.1}}  # handed back
    assert not _records(tmp_path)
    assert (await mount.unpark()).message == "no park record: nothing to restore"


async def test_nothing_is_written_unless_enabled(tmp_path: Path) -> None:
    mount = SimulatedMount(EQ6, site=SITE, clock=SimClock.stepped(START))
    await _parked(mount, None)
    assert mount.park_keeper.memory_for(mount) is None
    assert (await mount.unpark()).message == "no park record: nothing to restore"


@pytest.mark.parametrize(
    ("content", "reason"),
    [
        ("{not json", "not readable JSON"),
        ('{"version": 1, "alt_deg": 30}', "not a park record"),
        ('{"version": 99}', "not a park record"),
    ],
)
async def test_a_bad_record_is_one_clear_error_and_kept(
    tmp_path: Path, content: str, reason: str
) -> None:
    mount = SimulatedMount(EQ6, site=SITE, clock=SimClock.stepped(START))
    await _parked(mount, tmp_path)
    [path] = _records(tmp_path)
    path.write_text(content)
    with pytest.raises(ParkRecordError, match=reason) as raised:
        await mount.unpark()
    assert str(path) in str(raised.value)
    assert "\n" not in str(raised.value)
    assert path.read_text() == content  # never silently replaced
    assert mount.state.parked  # and the mount stays parked


def test_a_record_with_an_infinite_value_is_refused(tmp_path: Path) -> None:
    record = ParkRecord(30.0, 200.0, PierSide.EAST, aligned=True, parked_at=START, axes_deg=(1, 2))
    data = record.to_json()
    assert ParkRecord.from_json(data, tmp_path / "park.json") == record
    data["axes_deg"] = [float("inf"), 2.0]
    with pytest.raises(ParkRecordError, match="not finite"):
        ParkRecord.from_json(data, tmp_path / "park.json")
