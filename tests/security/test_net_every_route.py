"""Every route of the dashboard is under one policy, the routes added after the policy was written
(the first-run /api/setup, push-to, the sky chart's data) included: enumerated from the real
application, so a route added later cannot slip past it. Each command (POST) is refused to a
rebinding page (421), a page of another site (403), a machine that is not paired (401) and in
read-only mode (403), and changes nothing; each read is refused to a rebinding page."""

from __future__ import annotations

import asyncio

from scopelink.astro import Site
from scopelink.web import Dashboard
from scopelink.web.site_check import SiteStore
from tests.support.access import READ_ONLY, HttpAnswer, read_answer
from tests.support.alpaca import sim_mount

BODY = b'{"latitude_deg": 10, "longitude_deg": 10, "axis": "primary", "rate_deg_s": 1}'


class _Store:
    """A settings file that records what it was asked to save (none yet: first run)."""

    def __init__(self) -> None:
        self.saved_sites: list[Site] = []

    @property
    def saved(self) -> bool:
        return bool(self.saved_sites)

    @property
    def where(self) -> str:
        return "memory"

    def save(self, site: Site) -> None:
        self.saved_sites.append(site)


async def _ask(
    port: int, method: str, path: str, host: str, *, extra: str = "", body: bytes = BODY
) -> HttpAnswer:
    """One raw request to 127.0.0.1:``port`` naming ``host`` (the hostile names exist only in
    the headers)."""
    reader, writer = await asyncio.open_connection("127.0.0.1", port)
    try:
        sent = body if method == "POST" else b""
        head = (
            f"{method} {path} HTTP/1.1\r\nHost: {host}\r\n{extra}"
            f"Content-Type: application/json\r\nContent-Length: {len(sent)}\r\n"
            "Connection: close\r\n\r\n"
        )
        writer.write(head.encode() + sent)
        return await read_answer(reader)
    finally:
        writer.close()


def _routes(dashboard: Dashboard) -> tuple[list[str], list[str]]:
    app = dashboard.build_app()
    posts: set[str] = set()
    gets: set[str] = set()
    for route in app.router.routes():
        info = route.resource.get_info() if route.resource is not None else {}
        path = info.get("path") or info.get("formatter") or info.get("prefix")
        assert isinstance(path, str), info
        if "{" in path or route.method == "HEAD":
            continue
        (posts if route.method == "POST" else gets).add(path.rstrip("/") or "/")
    return sorted(posts), sorted(gets)


async def test_every_route_is_under_the_policy() -> None:
    mount = sim_mount()
    await mount.connect()
    store = _Store()
    _: SiteStore = store  # the protocol, checked by mypy
    site = mount.site
    try:
        async with (
            Dashboard(
                mount,
                port=0,
                trace=False,
                pairing_token="t0k3n",
                pairing_exempts_loopback=False,
                site_store=store,
            ) as paired,
            Dashboard(mount, port=0, trace=False, access=READ_ONLY, site_store=store) as read_only,
        ):
            posts, gets = _routes(paired)
            assert {"/api/setup", "/api/pushto", "/api/move"} <= set(posts)
            assert {"/api/setup", "/api/sky/deepsky", "/ws", "/static"} <= set(gets)
            here, evil = f"127.0.0.1:{paired.port}", f"evil.example:{paired.port}"
            for path in posts:
                for port, host, extra, wanted in (
                    (paired.port, evil, f"Origin: http://{evil}\r\n", 421),
                    (paired.port, here, "Origin: http://evil.example\r\n", 403),
                    (paired.port, here, "", 401),
                    (read_only.port, f"127.0.0.1:{read_only.port}", "", 403),
                ):
                    answer = await _ask(port, "POST", path, host, extra=extra)
                    assert answer.status == wanted, (path, answer)
                    assert "error" in answer.json()
            for path in gets:
                answer = await _ask(paired.port, "GET", path, evil)
                assert answer.status == 421, path
            # Nothing was done: no site set or saved, nothing moved, no push-to target.
            assert store.saved_sites == []
            assert mount.site == site
            state = await mount.refresh()
            assert not state.slewing
            assert paired.hub.panel.pushto.name is None
            # The pairing header opens the door the refusals closed.
            answer = await _ask(
                paired.port,
                "POST",
                "/api/pushto",
                here,
                extra="X-Scopelink-Pairing: t0k3n\r\n",
                body=b"{}",
            )
            assert answer.status == 200, answer
    finally:
        await mount.disconnect()
