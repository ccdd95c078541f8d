"""The dashboard's Sky Commander panel over real HTTP: a real dashboard in front of the real
Sky Commander driver on the Sky Commander emulator (TCP), the memory written through the API
landing in the emulated EEPROM, and push-to figures against the box's own offsets."""

from __future__ import annotations

from pathlib import Path

import pytest

from scopelink.protocol.skytracker import LoadObject
from scopelink.servers.skytracker.objects import StoredObject
from tests.support.skycommander_web import panel
from tests.support.web import served


async def test_upload_and_clear_through_the_dashboard_land_in_the_eeprom(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    async with panel(tmp_path, monkeypatch) as p:
        status, body = await p.get("/api/skycommander/slots")
        assert (status, body) == (200, {"available": True, "slots": []})
        status, body = await p.post("/api/skycommander/upload", {"name": "M 31"})
        assert status == 200, body
        assert body["written"][0]["slot"] == 0
        assert p.emulator.commander.store.get(0) == StoredObject(0.712, 41.269)
        status, body = await p.post(
            "/api/skycommander/upload",
            {"ra_hours": 18.2, "dec_deg": 20.9, "label": "C/2026 X1", "slot": 12},
        )
        assert status == 200, body
        assert p.emulator.commander.store.get(12) == StoredObject(18.2, 20.9)
        status, body = await p.get("/api/skycommander/slots")
        assert [(e["slot"], e["label"]) for e in body["slots"]] == [(0, "M 31"), (12, "C/2026 X1")]

        status, body = await p.post("/api/skycommander/clear", {"slot": 12})
        assert status == 200, body
        assert p.emulator.commander.store.get(12) == StoredObject(0.0, 90.0)
        assert [e["slot"] for e in body["slots"]] == [0]
        status, body = await p.post("/api/skycommander/clear", {})
        assert (status, body["cleared"], body["slots"]) == (200, [0], [])
        assert p.emulator.commander.store.get(0) == StoredObject(0.0, 90.0)


@pytest.mark.parametrize(
    ("request_body", "status", "words"),
    [
        ({"name": "Sun"}, 409, "from the Sun"),
        ({"name": "M 99999"}, 404, "no object named"),
        ({"name": "M 31", "slot": 59}, 400, "'slot' must lie in [0, 58]"),
        ({"name": "M 31", "slot": 3.5}, 400, "whole number"),
        ({"ra_hours": 25, "dec_deg": 0}, 400, "'ra_hours' must lie in"),
        ({}, 400, "give 'name'"),
    ],
)
async def test_bad_uploads_are_clear_errors_and_store_nothing(
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    request_body: dict[str, object],
    status: int,
    words: str,
) -> None:
    async with panel(tmp_path, monkeypatch) as p:
        got, body = await p.post("/api/skycommander/upload", request_body)
        assert got == status, body
        assert words in body["error"]
        assert p.emulator.commander.store.items() == {}


async def test_push_to_figures_match_the_sky_commanders_offsets(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    async with panel(tmp_path, monkeypatch) as p:
        status, body = await p.get("/api/pushto", ra_hours="5.5", dec_deg="20")
        assert status == 200, body
        p.emulator.commander.load(LoadObject.current(5.5, 20.0))
        box_up, box_ccw = p.emulator.commander.offsets_deg()
        assert body["up_deg"] == pytest.approx(box_up, abs=0.05)
        assert body["right_deg"] == pytest.approx(-box_ccw, abs=0.05)
        assert body["text"].startswith("RA 5.500 Dec +20.000: altitude ")
        status, body = await p.get("/api/pushto", name="Vega")
        assert status == 200, body
        assert body["target"] == "Vega"
        status, body = await p.get("/api/pushto", ra_hours="x", dec_deg="1")
        assert status == 400
        status, body = await p.get("/api/pushto", name="M 99999")
        assert status == 404


async def test_a_mount_without_a_sky_commander_hides_the_memory_but_pushes_to() -> None:
    async with served() as s:
        status, body = await s.get("/api/skycommander/slots")
        assert (status, body["available"]) == (200, False)
        status, body = await s.post("/api/skycommander/upload", {"name": "M 31"})
        assert status == 501
        status, body = await s.get("/api/pushto", name="Capella")
        assert status == 200, body
        assert body["distance_deg"] > 0
        async with s.http.get("/") as response:
            page = await response.text()
        assert 'id="skycommander-panel"' in page
        assert "/static/skycommander.js" in page
