"""The dashboard's page, script and style ship in the wheel and are served from an installed copy
(not only from the source tree): the wheel is built with hatchling as ``pip install .`` would,
unpacked, and run in a fresh interpreter."""

from __future__ import annotations

import subprocess
import sys
import zipfile
from pathlib import Path

from tests.support.wheel import scopelink_wheel

STATIC = (
    "index.html",
    "app.js",
    "chart.js",
    "chart.css",
    "chart/sphere.js",
    "vendor/d3-geo.min.js",
    "vendor/LICENSES",
    "sky/milkyway.json",
    "skycommander.js",
    "style.css",
)

SERVE_FROM_INSTALLED_COPY = """
import asyncio, sys
import aiohttp
import scopelink
from scopelink.astro import Site
from scopelink.sim import SimulatedMount
from scopelink.web import Dashboard

assert scopelink.__file__.startswith(sys.argv[1]), scopelink.__file__

async def main() -> None:
    mount = SimulatedMount(site=Site(45.0, 7.0))
    await mount.connect()
    async with Dashboard(mount, port=0, trace=False) as dashboard:
        async with aiohttp.ClientSession(base_url=dashboard.url) as http:
            for path in ("/", "/static/app.js", "/static/style.css"):
                async with http.get(path) as response:
                    body = await response.read()
                    print(path, response.status, len(body))
    await mount.disconnect()

asyncio.run(main())
"""


def test_the_wheel_carries_the_static_files_and_an_installed_copy_serves_them(
    tmp_path: Path,
) -> None:
    with zipfile.ZipFile(scopelink_wheel()) as archive:
        names = set(archive.namelist())
        for name in STATIC:
            assert f"scopelink/web/static/{name}" in names
        installed = tmp_path / "site"
        archive.extractall(installed)
    result = subprocess.run(
        [sys.executable, "-c", SERVE_FROM_INSTALLED_COPY, str(installed)],
        env={"PYTHONPATH": str(installed), "PATH": "/usr/bin:/bin"},
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )
    assert result.returncode == 0, result.stderr
    served = {line.split()[0]: line.split()[1:] for line in result.stdout.splitlines()}
    for path in ("/", "/static/app.js", "/static/style.css"):
        status, length = served[path]
        assert status == "200"
        assert int(length) > 1000
