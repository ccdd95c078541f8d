"""The dashboard's Unpark says what it did with the park record (docs/parking.md)."""

from __future__ import annotations

from pathlib import Path

from tests.support.web import served


async def test_unpark_answers_what_was_restored(tmp_path: Path) -> None:
    async with served() as s:
        s.mount.park_keeper.enable(tmp_path)
        status, body = await s.post("/api/park")
        assert status == 200, body
        await s.mount.wait_for(lambda state: state.parked, timeout_s=20)
        status, body = await s.post("/api/unpark")
        assert status == 200, body
        assert body["resume"] == "this mount keeps its own position: nothing to restore"
        status, body = await s.post("/api/unpark")
        assert body["resume"] == "no park record: nothing to restore"
