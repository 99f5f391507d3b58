"""The dashboard under attack: DNS rebinding, cross-site websockets, hostile frames and floods.

Every attack is made against a served dashboard on 127.0.0.1 (``sim://omni4`` in the room, the robot
at rest) and asserts two things: the connection ends cleanly with the expected close code (or the
message gets an ``error`` frame), and the robot did not move. The server must never raise: no record
at ERROR level is logged while it is attacked. Every loop is bounded (a frame count or a deadline).
"""

from __future__ import annotations

import asyncio
import http.client
import json
import logging
import socket
import time
from collections.abc import Iterator
from typing import Any

import pytest
import websockets
from websockets.asyncio.client import ClientConnection

from omnibot.errors import ConfigError
from omnibot.web.access import HostPolicy, RateLimit, check_host_name
from omnibot.web.dashboard import Dashboard
from omnibot.web.inbox import INBOX_MAX
from omnibot.web.messages import MAX_DEPTH, MAX_FRAME
from omnibot.web.server import BURST, MAX_PAGES, RATE
from tests.web.conftest import ROOM

FORWARD = json.dumps({"type": "drive", "vx": 1, "vy": 0, "w": 0, "enable": True})


@pytest.fixture
def no_server_errors(caplog: pytest.LogCaptureFixture) -> Iterator[None]:
    """Fails the test if anything (uvicorn, the hub) logged an error or a traceback."""
    caplog.set_level(logging.WARNING)
    yield
    bad = [r.getMessage() for r in caplog.records if r.levelno >= logging.ERROR or r.exc_info]
    assert not bad, f"the server logged errors: {bad}"


def pose(dash: Dashboard) -> list[float]:
    state = dash.hub.latest
    assert state is not None and state["pose"] is not None
    return list(state["pose"])


def wait_for_state(dash: Dashboard, timeout: float = 30.0) -> None:
    end = time.monotonic() + timeout
    while dash.hub.latest is None:
        assert time.monotonic() < end, "no state frame from the dashboard"
        time.sleep(0.02)


def sim_time(dash: Dashboard) -> float:
    state = dash.hub.latest
    assert state is not None
    return float(state["t"])


def assert_still(dash: Dashboard, before: list[float], settle: float = 0.4) -> None:
    """The robot is where it was and the link never drove it, ``settle`` s of the simulator's time on:
    long enough for a VEL, had one been sent, to move the robot visibly (wall-clock time would not
    do: on a loaded machine the simulation gets less of it, and a drive could go unseen)."""
    start = sim_time(dash)
    end = time.monotonic() + 30.0
    while sim_time(dash) < start + settle:
        assert time.monotonic() < end, "the simulator's clock stood still"
        time.sleep(0.02)
    after = pose(dash)
    assert abs(after[0] - before[0]) + abs(after[1] - before[1]) < 0.002, (before, after)
    state = dash.hub.latest
    assert state is not None and state["drive"]["state"] == "idle" and state["drive"]["twist"] is None


def http_get(port: int, host: str | None, path: str = "/", address: str = "127.0.0.1") -> tuple[int, str]:
    """GET from address:port with this ``Host`` header (None: none at all)."""
    conn = http.client.HTTPConnection(address, port, timeout=5)
    try:
        conn.putrequest("GET", path, skip_host=True)
        if host is not None:
            conn.putheader("Host", host)
        conn.endheaders()
        response = conn.getresponse()
        return response.status, response.read().decode()
    finally:
        conn.close()


async def _open(port: int, host: str, origin: str | None, query: str = "") -> ClientConnection:
    """A websocket to 127.0.0.1:port that names ``host`` in its Host header (as a rebound name does)."""
    sock = socket.create_connection(("127.0.0.1", port), timeout=5)
    sock.setblocking(False)
    headers = {"Origin": origin} if origin else None
    return await websockets.connect(
        f"ws://{host}/ws{query}", sock=sock, additional_headers=headers, open_timeout=5, close_timeout=2
    )


async def _attack(port: int, frames: list[str | bytes], *, text_bytes: bool = False) -> dict[str, Any]:
    """Connect as a same-origin page, send ``frames`` and read until the server closes, every frame
    got its error or 10 s pass (a deadline for a loaded machine; the test ends as soon as one of the
    others happens): the close code (None: still open) and the error frames received."""
    host = f"127.0.0.1:{port}"
    ws = await _open(port, host, f"http://{host}")
    errors: list[str] = []
    code: int | None = None
    try:
        hello = [json.loads(await ws.recv()) for _ in range(2)]
        assert [f["type"] for f in hello] == ["scene", "trail"]
        for frame in frames:
            if text_bytes:
                await ws.send(frame, text=True)
            else:
                await ws.send(frame)
        end = time.monotonic() + 10.0
        for _ in range(1000):  # state frames arrive at 20 Hz besides the answers
            remaining = end - time.monotonic()
            if remaining <= 0:
                break
            try:
                message = json.loads(await asyncio.wait_for(ws.recv(), remaining))
            except TimeoutError:
                break
            except websockets.exceptions.ConnectionClosed as exc:
                code = exc.rcvd.code if exc.rcvd is not None else -1
                break
            if message["type"] == "error":
                errors.append(message["error"])
                if len(errors) == len(frames):
                    break
    finally:
        await ws.close()
    return {"code": code, "errors": errors}


def attack(dash: Dashboard, frames: list[str | bytes], **kw: Any) -> dict[str, Any]:
    return asyncio.run(_attack(dash.port, frames, **kw))


@pytest.fixture
def still(dashboard: Dashboard) -> Iterator[list[float]]:
    """The pose before the attack; after it the robot must not have moved."""
    wait_for_state(dashboard)
    before = pose(dashboard)
    yield before
    assert_still(dashboard, before)


# ---------------------------------------------------------------------------------------- Host


def test_host_policy_names() -> None:
    loop = HostPolicy.for_bind("127.0.0.1", 8080)
    for good in ("127.0.0.1:8080", "localhost:8080", "LOCALHOST:8080", "[::1]:8080"):
        assert loop.allows(good), good
    for bad in (
        "evil.example:8080",
        "127.0.0.1:8081",
        "127.0.0.1",
        "localhost.evil.example:8080",
        "192.168.1.5:8080",
        "",
        None,
        "127.0.0.1:80:80",
        "[::1:8080",
    ):
        assert not loop.allows(bad), bad
    assert HostPolicy.for_bind("127.0.0.1", 80).allows("localhost")  # port 80 may be left out

    one = HostPolicy.for_bind("192.168.1.5", 8080, ["Robot.Local"])
    assert one.allows("192.168.1.5:8080") and one.allows("robot.local:8080")
    assert not one.allows("localhost:8080") and not one.allows("10.0.0.1:8080")
    assert not one.allows("evil.example:8080")

    anywhere = HostPolicy.for_bind("0.0.0.0", 8080)
    assert anywhere.allows("10.0.0.7:8080") and anywhere.allows("[fe80::1]:8080")
    assert anywhere.allows("localhost:8080") and not anywhere.allows("evil.example:8080")

    v6 = HostPolicy.for_bind("::1", 9000)
    assert v6.allows("[::1]:9000") and v6.allows("[0:0:0:0:0:0:0:1]:9000") and v6.allows("localhost:9000")


@pytest.mark.parametrize("name", ["http://robot.local", "robot.local:8080", "a b", "", "robot..local"])
def test_allow_host_names_are_checked(name: str) -> None:
    with pytest.raises(ConfigError, match="--allow-host: expected a host name"):
        check_host_name(name)


def test_dns_rebinding_http_is_refused(dashboard: Dashboard, no_server_errors: None) -> None:
    port = dashboard.port
    for host in (f"evil.example:{port}", f"127.0.0.1.nip.io:{port}", f"127.0.0.1:{port + 1}"):
        status, body = http_get(port, host)
        assert status == 403 and "DNS rebinding" in body, host
        assert http_get(port, host, "/static/app.js")[0] == 403
    assert http_get(port, None)[0] in (400, 403)  # no Host at all
    for host in (f"127.0.0.1:{port}", f"localhost:{port}", f"[::1]:{port}"):
        status, body = http_get(port, host)
        assert status == 200 and "omnibot dashboard" in body, host


def test_dns_rebinding_websocket_is_refused_and_the_robot_does_not_move(
    dashboard: Dashboard, still: list[float], no_server_errors: None
) -> None:
    port = dashboard.port
    evil = f"evil.example:{port}"
    refused = dashboard.host_check.refused
    with pytest.raises(websockets.exceptions.InvalidStatus) as info:
        asyncio.run(_open(port, evil, f"http://{evil}"))
    assert info.value.response.status_code == 403
    assert dashboard.host_check.refused == refused + 1


def test_allowed_names_are_served() -> None:
    with Dashboard(ROOM, http_port=0, allow_hosts=["robot.local"]) as dash:
        assert http_get(dash.port, f"robot.local:{dash.port}")[0] == 200
        assert http_get(dash.port, f"evil.example:{dash.port}")[0] == 403
    with pytest.raises(ConfigError, match="--allow-host"):
        Dashboard(ROOM, http_port=0, allow_hosts=["http://robot.local/"])


# ---------------------------------------------------------------------------------------- CSWSH


def test_cross_site_websocket_is_refused(
    dashboard: Dashboard, still: list[float], no_server_errors: None
) -> None:
    port = dashboard.port
    own = f"127.0.0.1:{port}"
    for origin in (
        "http://evil.example",
        f"http://evil.example:{port}",
        "null",
        f"https://{own}.evil.example",
    ):
        with pytest.raises(websockets.exceptions.InvalidStatus):
            asyncio.run(_open(port, own, origin))


def test_token_is_still_required_behind_the_host_check(no_server_errors: None) -> None:
    with Dashboard(ROOM, http_port=0, token="s3cret-token") as dash:
        own = f"127.0.0.1:{dash.port}"

        async def visit() -> None:
            with pytest.raises(websockets.exceptions.InvalidStatus):
                await _open(dash.port, own, f"http://{own}", "?token=wrong-token")
            ws = await _open(dash.port, own, f"http://{own}", "?token=s3cret-token")
            assert json.loads(await ws.recv())["type"] == "scene"
            await ws.close()

        asyncio.run(visit())


# ---------------------------------------------------------------------------------------- frames


@pytest.mark.parametrize(
    ("frames", "code"),
    [
        ([b"\x00\x01binary"], 1003),
        ([FORWARD.encode()], 1003),  # a valid message, but binary: refused, not driven
        (["[" * (MAX_FRAME + 1)], 1009),
        (['{"type": "ping", "t": 1, "pad": "' + "x" * 60_000 + '"}'], 1009),  # over uvicorn's limit
        (["[" * 4000 + "]" * 4000], 1009),  # the nesting that raised RecursionError, at its full size
        (["\u00e9" * (MAX_FRAME + 1)], 1009),  # counted in characters, not bytes
    ],
    ids=["binary", "binary-drive", "over-max-frame", "huge", "deep-4000", "multibyte"],
)
def test_hostile_frames_close_the_connection(
    dashboard: Dashboard, still: list[float], no_server_errors: None, frames: list[str | bytes], code: int
) -> None:
    assert attack(dashboard, frames)["code"] == code


def test_text_that_is_not_utf8_closes_with_1007(
    dashboard: Dashboard, still: list[float], no_server_errors: None
) -> None:
    assert attack(dashboard, [b'{"type": "ping", "t": \xff}'], text_bytes=True)["code"] == 1007


@pytest.mark.parametrize(
    ("frame", "reason"),
    [
        ("[" * 2000 + "]" * 2000, "nested too deeply"),
        (
            '{"type": "drive", "vx": ' + "[" * (MAX_DEPTH + 1) + "]" * (MAX_DEPTH + 1) + "}",
            "nested too deeply",
        ),
        ('{"type": "drive", "vx": "1", "vy": 0, "w": 0}', "drive.vx: Input should be a valid number"),
        ('{"type": "drive", "vx": true, "vy": 0, "w": 0}', "drive.vx: Input should be a valid number"),
        ('{"type": "drive", "vx": NaN}', "NaN is not a number"),
        ('{"type": "drive", "vx": Infinity}', "Infinity is not a number"),
        ('{"type": "drive", "vx": 1e400}', "out of range"),
        ('{"type": "drive", "vx": 1.0000001}', "less than or equal to 1"),
        ('{"type": "drive", "vx": 1, "enable": "false"}', "drive.enable: Input should be a valid boolean"),
        ('{"type": "joy", "axes": [1], "buttons": [1], "extra": 1}', "unknown key"),
        ('{"type": "estop", "type": "drive", "vx": 5}', "less than or equal to 1"),
        ("\u0000", "not JSON"),
        ('"drive"', "a message is a JSON object"),
        ("", "not JSON"),
    ],
    ids=[
        "deep-array",
        "deep-value",
        "string-number",
        "bool-number",
        "nan",
        "infinity",
        "overflow",
        "out-of-range",
        "string-bool",
        "extra-key",
        "duplicate-type",
        "nul",
        "string",
        "empty",
    ],
)
def test_malformed_messages_get_an_error_and_never_drive(
    dashboard: Dashboard, still: list[float], no_server_errors: None, frame: str, reason: str
) -> None:
    result = attack(dashboard, [frame])
    assert result["code"] is None  # the page stays connected
    assert len(result["errors"]) == 1 and reason in result["errors"][0], result["errors"]


# ---------------------------------------------------------------------------------------- floods


def test_a_flooding_page_is_closed_and_the_others_keep_their_stream(
    dashboard: Dashboard, still: list[float], no_server_errors: None
) -> None:
    clock = [0.0]
    dashboard.hub.rate_limit = lambda: RateLimit(
        rate=5.0, burst=20, clock=lambda: clock[0]
    )  # time stands still
    flood = [json.dumps({"type": "ping", "t": n}) for n in range(60)] + [FORWARD] * 40
    result = attack(dashboard, list(flood))
    assert result["code"] == 1008
    assert dashboard.hub.closed[-1] == 1008
    # another page still gets its stream, and the link thread still runs (state frames keep coming)
    t0 = dashboard.hub.latest["t"] if dashboard.hub.latest else 0.0
    assert attack(dashboard, ['{"type": "fly"}'])["errors"] == [
        "message rejected: unknown message type 'fly'; expected one of: drive, joy, estop, resume, teach, ping"
    ]
    end = time.monotonic() + 30.0
    while sim_time(dashboard) <= t0:  # a state frame newer than the flood's
        assert time.monotonic() < end, "no state frame since the flood"
        time.sleep(0.02)


def test_the_real_rate_limit_allows_the_page_and_stops_a_flood() -> None:
    clock = [0.0]
    limit = RateLimit(rate=RATE, burst=BURST, clock=lambda: clock[0])
    for _ in range(20 * 60):  # the page for a minute: drive + joy at 20 Hz and a ping a second
        clock[0] += 0.05
        assert limit.take() and limit.take()
        if round(clock[0] / 0.05) % 20 == 0:
            assert limit.take()
    taken = sum(limit.take() for _ in range(1000))  # then 1,000 messages at once
    assert BURST - 5 <= taken <= BURST
    with pytest.raises(ValueError, match="rate > 0"):
        RateLimit(rate=0.0, burst=10)


def test_too_many_pages_are_refused(dashboard: Dashboard, no_server_errors: None) -> None:
    async def crowd() -> None:
        own = f"127.0.0.1:{dashboard.port}"
        pages = [await _open(dashboard.port, own, f"http://{own}") for _ in range(MAX_PAGES)]
        try:
            for ws in pages:
                await ws.recv()
            with pytest.raises(websockets.exceptions.InvalidStatus):
                await _open(dashboard.port, own, f"http://{own}")
        finally:
            for ws in pages:
                await ws.close()

    asyncio.run(crowd())


def test_a_full_inbox_drops_driving_but_never_the_emergency_stop() -> None:
    from omnibot.client import RobotClient
    from omnibot.robot import load_robot
    from omnibot.web.inbox import PageGone
    from omnibot.web.link import RobotLink
    from omnibot.web.messages import Drive, EStop

    client = RobotClient.open(ROOM, timeout=0.5)
    link = RobotLink(client, load_robot("omni4"))
    try:
        link.setup()
        drive = Drive(type="drive", vx=1.0)
        accepted = sum(link.submit(drive) for _ in range(INBOX_MAX + 50))
        assert accepted == INBOX_MAX and link.inbox.qsize() == INBOX_MAX
        assert link.submit(EStop(type="estop")) and link.submit(PageGone())  # flagged, not queued
        link.tick(client.clock.now())
        assert link.inbox.empty() and link.estop  # the stop came last and won
        frames = [link.outbox.get_nowait() for _ in range(link.outbox.qsize())]
        assert any("emergency stop" in f.get("text", "") for f in frames)
        assert frames[-1]["drive"]["state"] == "estop"
    finally:
        link.stop()


def test_a_name_given_to_host_is_served_with_the_address_it_resolved_to(no_server_errors: None) -> None:
    with Dashboard(ROOM, host="localhost", http_port=0) as dash:
        address = str(
            socket.getaddrinfo("localhost", dash.port, type=socket.SOCK_STREAM)[0][4][0]
        )  # as bind()
        for host in (f"localhost:{dash.port}", f"127.0.0.1:{dash.port}", f"[::1]:{dash.port}"):
            assert http_get(dash.port, host, address=address)[0] == 200
        assert http_get(dash.port, f"evil.example:{dash.port}", address=address)[0] == 403
