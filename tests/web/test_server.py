"""The server without a browser: access token, same-origin websockets, binding, shutdown."""

from __future__ import annotations

import asyncio
import json
import socket
import urllib.error
import urllib.request
from typing import Any

import pytest
import websockets

from omnibot.errors import ConfigError
from omnibot.web.access import access_token, is_loopback
from omnibot.web.dashboard import Dashboard, bind
from tests.web.conftest import ROOM


def get(url: str) -> tuple[int, str]:
    try:
        with urllib.request.urlopen(url, timeout=5) as r:
            return r.status, r.read().decode()
    except urllib.error.HTTPError as exc:
        with exc:
            return exc.code, exc.read().decode()


async def first_frames(url: str, origin: str | None = None, n: int = 2) -> list[dict[str, Any]]:
    headers = {"Origin": origin} if origin else None
    async with websockets.connect(url, additional_headers=headers, open_timeout=5, close_timeout=1) as ws:
        return [json.loads(await ws.recv()) for _ in range(n)]


def ws_url(dash: Dashboard, token: str | None = None) -> str:
    query = f"?token={token}" if token else ""
    return f"ws://127.0.0.1:{dash.port}/ws{query}"


def test_loopback_needs_no_token(dashboard: Dashboard) -> None:
    assert dashboard.token is None and dashboard.url == f"http://127.0.0.1:{dashboard.port}/"
    status, html = get(dashboard.url)
    assert status == 200 and "omnibot dashboard" in html
    assert get(dashboard.url + "static/app.js")[0] == 200
    frames = asyncio.run(first_frames(ws_url(dashboard)))
    assert [f["type"] for f in frames] == ["scene", "trail"]
    assert frames[0]["world"]["name"] == "room"


def test_token_is_required_when_given() -> None:
    with Dashboard(ROOM, http_port=0, token="s3cret-token") as dash:
        assert dash.url.endswith("/?token=s3cret-token")
        assert get(dash.url)[0] == 200
        status, html = get(f"http://127.0.0.1:{dash.port}/?token=wrong-token")
        assert status == 401 and "access token" in html
        assert get(f"http://127.0.0.1:{dash.port}/")[0] == 401
        with pytest.raises(websockets.exceptions.InvalidStatus):
            asyncio.run(first_frames(ws_url(dash)))
        assert asyncio.run(first_frames(ws_url(dash, "s3cret-token")))[0]["type"] == "scene"


def test_websocket_from_another_site_is_refused(dashboard: Dashboard) -> None:
    with pytest.raises(websockets.exceptions.InvalidStatus):
        asyncio.run(first_frames(ws_url(dashboard), origin="http://evil.example"))
    own = f"http://127.0.0.1:{dashboard.port}"
    assert asyncio.run(first_frames(ws_url(dashboard), origin=own))[0]["type"] == "scene"


def test_tokens_off_loopback() -> None:
    assert is_loopback("127.0.0.1") and is_loopback("::1") and is_loopback("localhost")
    assert not is_loopback("0.0.0.0") and not is_loopback("192.168.1.5") and not is_loopback("robot.local")
    assert access_token("127.0.0.1", None) is None
    made = access_token("0.0.0.0", None)
    assert made is not None and len(made) >= 20
    assert access_token("0.0.0.0", "given-token") == "given-token"
    with pytest.raises(ConfigError, match="at least 8 characters"):
        access_token("127.0.0.1", "short")


def test_bind_errors_are_clear() -> None:
    taken = bind("127.0.0.1", 0)
    try:
        port = taken.getsockname()[1]
        with pytest.raises(ConfigError, match=rf"--http-port: cannot listen on 127\.0\.0\.1:{port}"):
            bind("127.0.0.1", port)
    finally:
        taken.close()
    with pytest.raises(ConfigError, match=r"expected a port 0\.\.65535"):
        bind("127.0.0.1", 70000)


def test_a_dashboard_that_fails_to_construct_leaves_nothing_open() -> None:
    blocker = socket.socket()
    blocker.bind(("127.0.0.1", 0))
    blocker.listen()
    try:
        with pytest.raises(ConfigError, match="cannot listen"):
            Dashboard(ROOM, http_port=blocker.getsockname()[1])
    finally:
        blocker.close()


def test_stop_stops_the_robot() -> None:
    dash = Dashboard(ROOM, http_port=0)
    dash.start()
    client = dash.link.client
    dash.stop()
    assert client.link.closed and not dash.link.alive
    dash.stop()  # idempotent
