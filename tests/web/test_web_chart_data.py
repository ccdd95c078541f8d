"""What the sky chart is fed, over real HTTP and WebSocket: the deep-sky list (from the catalogue
we ship, cached, compressed), the frame that turns J2000 into the sky of the moment (checked
against the sidereal time and the site), and the page's assets: at most 2 MB with the deep-sky
list, and no address of another host anywhere in them (the telescope has no internet)."""

from __future__ import annotations

import json
import math
import re
from pathlib import Path

from scopelink.astro import angular_separation_deg, lst_hours
from scopelink.astro.catalog.deepsky import load_deep_sky
from scopelink.astro.catalog.entries import Prominence
from scopelink.web.dashboard import static_dir
from scopelink.web.deepsky import (
    CHART_DEEP_SKY_CACHE_S,
    CHART_DEEP_SKY_MAGNITUDE,
    deep_sky_json,
)
from tests.support.web import served

DOC = Path(__file__).resolve().parents[2] / "docs" / "dashboard.md"
ASSET_BUDGET_BYTES = 2 * 1024 * 1024  # issue #17: the page within 2 MB
URL = re.compile(r"""(?:https?:)?//[a-z0-9.-]+\.[a-z]{2,}|url\(\s*['"]?(?:https?:)?//""", re.I)
COMMENT = re.compile(r"^\s*(?://|/\*|\*|<!--).*$|/\*.*?\*/", re.M)


async def test_deep_sky_list_and_sky_frame() -> None:
    async with served() as s:
        async with s.http.get("/api/sky/deepsky", headers={"Accept-Encoding": "gzip"}) as response:
            assert response.status == 200
            assert response.headers["Content-Encoding"] == "gzip"
            assert response.headers["Cache-Control"] == f"max-age={CHART_DEEP_SKY_CACHE_S}"
            reply = await response.json()
        at = {field: i for i, field in enumerate(reply["fields"])}
        rows = {row[at["name"]]: row for row in reply["objects"]}
        m31 = rows["M 31"]
        assert m31[at["type"]] == "galaxy"
        assert math.isclose(m31[at["ra_deg"]], 10.6847, abs_tol=0.01)
        assert math.isclose(m31[at["dec_deg"]], 41.2687, abs_tol=0.01)
        assert m31[at["major_arcmin"]] > 150
        assert m31[at["pa_deg"]] == 35
        assert rows["M 42"][at["type"]] == "cluster-nebula"
        assert rows["M 13"][at["type"]] == "globular"
        assert {row[at["type"]] for row in reply["objects"]} == {
            "galaxy",
            "open",
            "globular",
            "planetary",
            "nebula",
            "cluster-nebula",
        }
        # Faint objects only when named (Messier, Caldwell, a common name).
        for entry in load_deep_sky():
            faint = entry.magnitude is None or entry.magnitude > CHART_DEEP_SKY_MAGNITUDE
            if faint and entry.prominence > Prominence.CALDWELL:
                assert entry.name not in rows
        assert sum(name.startswith("M ") for name in rows) >= 105
        assert 1500 < len(rows) < 5000

        async with s.http.ws_connect("/ws") as socket:
            hello = json.loads((await socket.receive()).data)
        frame, site, now = hello["sky_frame"], s.mount.site, s.mount.now()
        # The zenith's J2000 position: Dec near the latitude, RA near the local sidereal time
        # (both within precession since 2000), the meridian point 45° below it to the north.
        zenith_ra, zenith_dec = frame["zenith"]
        assert abs(zenith_dec - site.latitude_deg) < 0.5
        lst_deg = lst_hours(now, site.longitude_deg) * 15.0
        assert abs((zenith_ra - lst_deg + 180.0) % 360.0 - 180.0) < 0.6
        assert math.isclose(
            angular_separation_deg(*frame["zenith"], *frame["north"]), 45.0, abs_tol=0.05
        )
        assert frame["north"][1] > zenith_dec  # towards the north celestial pole


def test_page_assets_fit_the_budget_and_name_no_other_host() -> None:
    files = [path for path in static_dir().rglob("*") if path.is_file()]
    assert {"chart.js", "d3-geo.min.js", "milkyway.json", "LICENSES"} <= {p.name for p in files}
    total = sum(path.stat().st_size for path in files) + len(deep_sky_json())
    print(f"page assets: {total / 1e6:.2f} MB ({len(files)} files and the deep-sky list)")
    assert total <= ASSET_BUDGET_BYTES
    for path in files:
        if path.suffix not in (".html", ".js", ".css"):
            continue
        code = COMMENT.sub("", path.read_text(encoding="utf-8"))
        assert URL.findall(code) == [], path.name


def js_constant(text: str, name: str) -> str:
    match = re.search(rf"export const {name} = ([^;]+);", text)
    assert match is not None, name
    return match.group(1)


def test_the_charts_defaults_are_the_documented_ones() -> None:
    doc = " ".join(DOC.read_text(encoding="utf-8").split())
    view = (static_dir() / "chart" / "view.js").read_text(encoding="utf-8")
    fov_min, fov_max = js_constant(view, "FOV_MIN"), js_constant(view, "FOV_MAX")
    assert (
        f"The field (across the canvas) goes from {fov_max}° (the whole sky) to {fov_min}°" in doc
    )
    field = js_constant(view, "DEFAULT_FIELD")
    width = re.search(r"width: ([0-9.]+)", field)
    assert width is not None
    assert f"width only (default {width.group(1)}°)" in doc
    assert f"of magnitude {CHART_DEEP_SKY_MAGNITUDE:g} or brighter" in doc
    assert f"`Cache-Control: max-age={CHART_DEEP_SKY_CACHE_S}`" in doc
