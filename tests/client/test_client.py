"""RobotClient: request/reply matching, events, timeouts, resets, reconnects, binary mode."""

from __future__ import annotations

import logging
import math
import time
from collections import deque
from collections.abc import Iterator

import pytest

from omnibot.client import (
    CommandRejected,
    ControllerReset,
    EmergencyStopLatched,
    ErrorEvent,
    Event,
    EventRecorder,
    IdleEvent,
    OutOfRange,
    QueueFull,
    RangeEvent,
    ResetEvent,
    RobotClient,
    Telemetry,
    Unexpected,
    WarnEvent,
    controller_error,
)
from omnibot.client.pending import Pending
from omnibot.client.views import Status
from omnibot.errors import ControllerError, LinkError, LinkTimeout, ProtocolError
from omnibot.firmware.config import build_config
from omnibot.firmware.controller import Controller
from omnibot.protocol import codes
from omnibot.protocol.messages import Hello, Malformed, Move, Ok, StatusReply, Stop, Vel
from omnibot.protocol.messages import Status as StatusCommand
from omnibot.protocol.messages import Telemetry as TelMessage
from omnibot.transport import FaultLink, LockstepLink, open_link

from .fakes import ScriptedLink, Silent, controller

STATUS_LINE = b"STATUS,1,0,16,0;POWER,0,0,0,0;MOVE,0,0,0,0\r\n"
TEXT_BITS = codes.MODE_CHECKED_TEXT | codes.MODE_SEQUENCED_TEXT  # the client sets them (tags are on)


@pytest.fixture
def sim() -> Iterator[RobotClient]:
    with RobotClient.open("sim://omni4?seed=1") as client:
        yield client


# ------------------------------------------------------------------ matching


def test_pipelined_replies_match_in_order() -> None:
    client = RobotClient(ScriptedLink(controller))
    pendings = [client.submit(c) for c in (StatusCommand(), Move(10, 40, 0, 0), Hello(), Stop())]
    pendings += client.submit_text("FOO")
    assert len(client.outstanding) == 5
    assert isinstance(pendings[0].result(), StatusReply)
    assert pendings[1].result() == Ok()
    assert pendings[2].result().keyword == "HELLO"
    assert pendings[3].done and pendings[3].reply == Ok()  # answered while waiting for the earlier ones
    with pytest.raises(CommandRejected) as info:
        pendings[4].result()
    assert (info.value.code, info.value.text) == (23, "unknown command")
    assert "command: FOO" in info.value.__notes__
    assert client.outstanding == []


def test_text_reply_of_another_kind_realigns() -> None:
    def lossy(line: bytes) -> bytes:  # the OK of MOVE is lost on the line
        return b"" if line.startswith(b"MOVE") else controller(line)

    client = RobotClient(ScriptedLink(lossy))
    move = client.submit(Move(10, 40, 0, 0))
    status = client.submit(StatusCommand())
    assert isinstance(status.result(), StatusReply)
    with pytest.raises(ProtocolError, match="no reply to MOVE"):
        move.result()


def test_timed_out_command_keeps_its_place() -> None:
    link = ScriptedLink()
    client = RobotClient(link, timeout=0.5, tags=False)  # untagged text: replies matched in order
    late = client.submit(Move(10, 40, 0, 0))
    with pytest.raises(LinkTimeout, match="no reply to MOVE,10,40,0,0"):
        late.result()
    assert link.clock.now() == pytest.approx(0.5)
    link.answer = controller
    link.feed(b"OK\r\n")  # the late reply of MOVE
    assert client.status().idle  # not taken for MOVE's OK
    assert late.reply == Ok()


def test_unasked_error_ok_and_garbage_become_events() -> None:
    link = ScriptedLink(controller)
    client = RobotClient(link)
    rec = EventRecorder()
    client.add_listener(rec)
    link.feed(b"ERROR,36,internal fault\r\nOK\r\n\xff\xfe\r\nWARN,11,speed reduced\r\nRANGE,1,42\r\nIDLE\r\n")
    client.pump(0)
    kinds = [type(e) for e in rec.events]
    assert kinds == [ErrorEvent, Unexpected, Unexpected, WarnEvent, RangeEvent, IdleEvent]
    assert rec.of(ErrorEvent)[0].code == 36
    assert rec.of(RangeEvent)[0].distance == pytest.approx(0.42)
    assert isinstance(rec.of(Unexpected)[1].message, Malformed)


def test_reset_fails_the_commands_waiting() -> None:
    link = ScriptedLink(controller)
    client = RobotClient(link)
    rec = EventRecorder()
    client.on_reset(rec)
    client.status()  # a reply matched: a later HELLO line is a reset
    link.answer = lambda line: b"HELLO,1,fake,4\r\n"  # reboots instead of answering
    with pytest.raises(ControllerReset):
        client.move(0.1, 0.4)
    (reset,) = rec.of(ResetEvent)
    assert reset.hello.name == "fake" and client.last_hello == reset.hello
    assert client.outstanding == [] and client.mode_bits is None


def test_greeting_at_start_is_not_an_answer() -> None:
    link = ScriptedLink(controller)
    link.feed(b"HELLO,1,fake,4\r\n")  # the controller booted as we connected
    client = RobotClient(link)
    rec = EventRecorder()
    client.add_listener(rec)
    client.move(0.1, 0.4)  # not failed by the greeting
    assert [type(e) for e in rec.events] == [ResetEvent]
    assert client.moving


def test_greeting_taken_for_the_hello_reply() -> None:
    link = ScriptedLink(controller)
    client = RobotClient(link)
    client.status()
    link.feed(b"HELLO,1,fake,4\r\n")  # a reset greeting arriving just before our HELLO's reply
    rec = EventRecorder()
    client.add_listener(rec)
    assert client.hello().name == "fake"
    client.move(0.1, 0.4)  # the real HELLO reply comes now: a reset is reported, MOVE is fine
    assert [type(e) for e in rec.events] == [ResetEvent]


# ------------------------------------------------------------------ events


class _Bytes:
    """A tracer that counts what it is handed, and raises from the ``fail``-th call on."""

    def __init__(self, fail: int = 0) -> None:
        self.calls = 0
        self.fail = fail

    def link_bytes(self, t: float, kind: str, data: bytes = b"", note: str = "") -> None:
        self.calls += 1
        if self.fail and self.calls >= self.fail:
            raise OSError(28, "No space left on device")

    def message(self, t: float, direction: str, message: object) -> None:
        self.link_bytes(t, direction)


def test_a_failing_tracer_is_dropped_with_one_traceback(caplog: pytest.LogCaptureFixture) -> None:
    """A tracer (a recorder on a full disk) that raises on every call is logged once and handed
    nothing more; the commands and the other tracers go on (issue 27: 6,456-17,239 tracebacks)."""
    with RobotClient.open("sim://omni4?seed=1") as client:
        broken, good = _Bytes(fail=3), _Bytes()
        client.add_tracer(broken)
        client.add_tracer(good)
        with caplog.at_level(logging.ERROR, "omnibot.client"):
            for _ in range(20):
                client.status()
    assert broken.calls == 3 and good.calls > 80
    assert len(caplog.records) == 1 and "failed; it is removed" in caplog.records[0].getMessage()


def test_listeners_filter_remove_and_survive_errors(caplog: pytest.LogCaptureFixture) -> None:
    link = ScriptedLink()
    client = RobotClient(link)
    everything, idle, warn = EventRecorder(), EventRecorder(), EventRecorder()

    def broken(event: Event) -> None:
        raise RuntimeError("listener bug")

    client.add_listener(everything)
    client.add_listener(broken, IdleEvent)
    client.on_idle(idle)
    client.on_warn(warn)
    client.add_listener(warn, ErrorEvent)
    link.feed(b"IDLE\r\nWARN,13,emergency stop by sonar\r\nERROR,36,x\r\n")
    with caplog.at_level(logging.ERROR, "omnibot.client"):
        assert client.pump(0) == 3
    assert "listener bug" in caplog.text
    assert len(everything.events) == 3 and len(idle.events) == 1
    assert [type(e) for e in warn.events] == [WarnEvent, ErrorEvent]
    client.remove_listener(warn)
    link.feed(b"WARN,11,x\r\n")
    client.pump(0)
    assert len(warn.events) == 2 and len(everything.events) == 4


def test_telemetry_in_si() -> None:
    tel = TelMessage(
        123456, (120, -120, 118, -119), (5012, -4990, 5033, -5007), (), -1250, 9000, 7400, (0, 2), (42, -1)
    )
    view = Telemetry.from_message(tel, 1.5)
    assert view.time == 1.5 and view.controller_time == pytest.approx(123.456)
    assert view.gyro_rate == pytest.approx(math.radians(-12.5))
    assert view.heading == pytest.approx(math.radians(90))
    assert view.battery == pytest.approx(7.4)
    assert (view.state, view.queued, view.ranges) == (0, 2, (0.42, None))
    assert Telemetry.from_message(TelMessage(5), 0.0).powers is None


def test_status_view() -> None:
    status = Status.from_reply(StatusReply(3, 2, 16, 5, (1, 2, 3, 4), (30000, 40, 90, -25)))
    assert status.estop and not status.moving and status.state_name == "estop"
    assert status.simulation and status.binary and not status.closed_loop
    assert status.move.distance == math.inf
    assert status.move.course == pytest.approx(math.pi / 2) and status.move.curvature == -2.5


def test_controller_error_classes() -> None:
    assert type(controller_error(21)) is QueueFull
    assert type(controller_error(40)) is EmergencyStopLatched
    assert type(controller_error(28)) is OutOfRange and controller_error(28).text == codes.TEXTS[28]
    assert type(controller_error(34)) is CommandRejected
    assert type(controller_error(99, "new")) is ControllerError
    for code in range(21, 41):
        if code != 26:
            assert isinstance(controller_error(code), ControllerError)


# ------------------------------------------------------------------ time


def test_timeouts_count_simulated_time() -> None:
    link = LockstepLink(Silent())
    client = RobotClient(link, timeout=20.0)
    wall = time.monotonic()
    with pytest.raises(LinkTimeout):
        client.status()
    assert link.clock.now() == pytest.approx(20.0, abs=0.01)
    assert time.monotonic() - wall < 10.0  # a wall-clock timeout would take 20 s
    client.close()


def test_a_long_line_is_waited_for_while_it_is_on_the_line(sim: RobotClient) -> None:
    """A reply cannot come before its command has arrived: 20 kB take 1.7 s at 115200 baud, more than
    the client's 1 s timeout, and the controller's "too long" is still the answer (it was "no reply")."""
    line = b"VEL," + b"1" * 20_000
    assert sim.link.line_time(len(line) + 2) == pytest.approx(20_006 * 10 / 115200)
    start = sim.clock.now()
    with pytest.raises(ControllerError, match="too long") as caught:
        sim.submit_raw(line + b"\r\n")[0].result()
    assert caught.value.code == 22
    assert sim.clock.now() - start > 1.7
    with pytest.raises(ControllerError, match="too long"):
        sim.submit_text(line.decode())[0].result()
    assert LockstepLink(Silent(), baud=0).line_time(1000) == 0.0


def test_wait_idle_and_sleep_on_sim(sim: RobotClient) -> None:
    idle = EventRecorder()
    sim.on_idle(idle)
    sim.submit(Move(20, 40, 0, 0))  # not waited for: wait_idle waits for its OK first
    sim.wait_idle(timeout=2)
    assert len(idle.events) == 1 and 0.5 <= sim.clock.now() <= 0.6
    now = sim.clock.now()
    sim.wait_idle(timeout=2)  # IDLE already came: returns at once
    assert sim.clock.now() == now
    sim.move(math.inf, 0.4)
    with pytest.raises(LinkTimeout, match="IDLE"):
        sim.wait_idle(timeout=3)
    # 3 s of the simulator's clock (a wall-clock wait would have let it run on, at its own pace:
    # test_timeouts_count_simulated_time bounds the wall clock, with room for a loaded machine)
    assert sim.clock.now() == pytest.approx(now + 3, abs=0.05)
    sim.stop()
    assert not sim.moving
    start = sim.clock.now()
    sim.sleep(0.25)
    assert sim.clock.now() == pytest.approx(start + 0.25, abs=0.002)


def test_values_checked_before_sending() -> None:
    link = ScriptedLink(controller)
    client = RobotClient(link, "omni4", tags=False)
    with pytest.raises(ValueError, match="speed"):
        client.move(1.0, 2.0)
    with pytest.raises(ValueError, match="use_binary"):
        client.mode(codes.MODE_BINARY)
    assert link.written == b""
    assert client.move(0.123, 0.456) == Move(12, 46, 0, 0)
    assert link.written == b"MOVE,12,46,0,0\n"


def test_set_mode_keeps_other_bits(sim: RobotClient) -> None:
    assert sim.mode_bits is None
    sim.mode(simulation=True)  # reads STATUS first
    checked = codes.MODE_CHECKED_TEXT | codes.MODE_SEQUENCED_TEXT  # set before the first command (tags)
    assert sim.mode_bits == codes.MODE_SIMULATION | checked
    sim.mode(closed_loop=True)
    assert sim.status().mode == 3 | checked
    sim.mode(simulation=False)
    assert sim.status().mode == codes.MODE_CLOSED_LOOP | checked


def test_submit_text() -> None:
    link = ScriptedLink(controller)
    client = RobotClient(link, tags=False)
    pendings = client.submit_text("move,1,40,0,0;;STATUS\r\n;foo")
    assert [p.line for p in pendings] == ["move,1,40,0,0", "STATUS", "foo"]
    assert link.written == b"move,1,40,0,0\nSTATUS\nfoo\n"  # sent as typed
    assert pendings[0].command == Move(1, 40, 0, 0) and pendings[2].command is None
    assert client.submit_text(";;\n") == []
    with pytest.raises(ProtocolError, match="ASCII"):
        client.submit_text("MOVE,1,40,0,0\u00b0")


# ------------------------------------------------------------------ binary


def test_binary_round_trip_on_sim(sim: RobotClient) -> None:
    rec = EventRecorder()
    sim.add_listener(rec)
    sim.mode(simulation=True)
    hello = sim.use_binary()
    assert (hello.version, hello.name, hello.motors) == (codes.VERSIONS[-1], "omni4", 4) and sim.binary
    assert sim.status().mode == codes.MODE_SIMULATION | codes.MODE_BINARY | TEXT_BITS  # kept
    pendings = [sim.submit(Move(10, 40, 0, 0)) for _ in range(6)]  # more than the window of 4
    for p in pendings:
        assert p.result() == Ok()
    assert len({p.seq for p in pendings}) == 6
    sim.wait_idle(timeout=3)
    assert rec.of(IdleEvent)
    with pytest.raises(OutOfRange):
        sim.execute(Move(0, 20, 0, 0))
    with pytest.raises(ProtocolError, match="binary"):
        sim.submit_text("FOO")
    assert len(sim.submit_text("STATUS;STATUS")) == 2
    sim.drain()
    sim.use_text()
    assert not sim.binary and sim.status().mode == codes.MODE_SIMULATION | TEXT_BITS


def test_binary_survives_a_noisy_line() -> None:
    link = FaultLink(open_link("sim://omni4?seed=1"), seed=7)
    client = RobotClient(link, "omni4")
    client.use_binary()
    link.corrupt = 0.003  # about one frame in twenty is damaged, both ways
    for _ in range(40):
        assert client.status().idle
    client.move(0.05, 0.4)
    client.wait_idle(timeout=5)
    stats = link.stats
    assert stats.tx_corrupted + stats.rx_corrupted > 0
    link.corrupt = 0.0
    client.use_text()
    client.close()


@pytest.mark.parametrize("late", [0.3, 2.5])
def test_binary_calls_outlast_a_stalled_line(late: float) -> None:
    """Replies held ``late`` seconds (a controller, line or host not scheduled for that long): the
    host's retransmissions turn patient after the fast ones (3.2 s in all) and a call waits for
    them, so no call fails for it."""
    link = FaultLink(open_link("sim://omni4?seed=1"), seed=3, direction="rx")
    client = RobotClient(link, "omni4")
    client.use_binary()
    link.delay = late
    start = client.clock.now()
    client.move(2.0, 0.4)  # 5 s long: still moving when the STATUS after it runs
    assert client.status().moving
    assert client.clock.now() - start >= 2 * late  # both replies were held
    client.wait_idle(timeout=10)
    link.delay = 0.0
    assert client.status().idle
    client.use_text()
    client.close()


def test_binary_controller_reset_returns_to_text(sim: RobotClient) -> None:
    sim.use_binary()
    rec = EventRecorder()
    sim.on_reset(rec)
    link = sim.link
    assert isinstance(link, LockstepLink)
    device = link.device
    device.controller = Controller(device.hal, build_config(device.robot))  # type: ignore[attr-defined]
    sim.sleep(0.05)
    assert not sim.binary and len(rec.events) == 1
    assert sim.status().mode == TEXT_BITS  # the restart cleared them, the client asked again


# ------------------------------------------------------------------ link failures


def test_reconnect_after_link_error() -> None:
    link = ScriptedLink(controller)
    client = RobotClient(link, reconnect=2.0)
    link.fail_reads = 1
    with pytest.raises(LinkError, match="unplugged"):
        client.status()
    assert link.reopens == 1
    assert client.status().idle  # the next call works


def test_reconnect_after_write_error() -> None:
    link = ScriptedLink(controller)
    client = RobotClient(link)
    link.broken = True
    with pytest.raises(LinkError, match="broken"):
        client.status()
    assert link.reopens == 1 and client.status().idle


def test_a_link_that_stays_broken_is_told_by_its_failure(monkeypatch: pytest.MonkeyPatch) -> None:
    """The port gone for good: later calls (a cleanup's STOP) name why the link broke, not only that
    the port cannot be opened now (which hid the failure behind "cannot open serial port")."""
    link = ScriptedLink(controller)
    client = RobotClient(link)

    def gone(retry: float | None = None) -> None:
        raise LinkError("cannot open the port: no such file")

    monkeypatch.setattr(link, "reopen", gone)
    link.fail_reads = 1
    with pytest.raises(LinkError, match="unplugged"):
        client.status()
    assert client.broken
    with pytest.raises(LinkError, match="fake link unplugged; reopening it failed: cannot open the port"):
        client.stop()
    assert client.broken


def test_no_reconnect_when_off() -> None:
    link = ScriptedLink(controller)
    client = RobotClient(link, reconnect=None)
    link.fail_reads = 1
    with pytest.raises(LinkError):
        client.status()
    with pytest.raises(LinkError, match="reconnecting is off"):
        client.status()
    assert link.reopens == 0


def test_closed_client() -> None:
    with RobotClient(ScriptedLink(controller)) as client:
        assert client.status().idle
    with pytest.raises(LinkError, match="closed"):
        client.status()
    assert "RobotClient" in repr(client)


def test_open_lets_the_power_up_greeting_settle() -> None:
    """sim:// greets at time 0; a HELLO sent right after opening gets its own reply, not the greeting."""
    resets: list[object] = []
    with RobotClient.open("sim://omni4") as client:
        client.on_reset(resets.append)
        hello = client.hello()
        client.sleep(0.1)
    assert hello.name == "omni4"
    assert resets == []  # the greeting was consumed while settling, and nothing else looked like one


def test_an_older_controller_takes_a_map_without_speed_terms(monkeypatch: pytest.MonkeyPatch) -> None:
    """A controller from before CAL table 7 (ERROR 38 for it): a map without speed terms uploads (it
    has none anyway), one with them fails in one line naming the firmware."""
    from omnibot.robot import MotorMapSpec, PiecewiseLinear, load_robot
    from omnibot.sim import SimDevice

    old_cal = Controller._cal

    def older(self: Controller, table: int, index: int, x: int, y: int) -> bool:
        return table != codes.CAL_SPEED and old_cal(self, table, index, x, y)

    monkeypatch.setattr(Controller, "_cal", older)
    robot = load_robot("omni4")
    spec = robot.calibration
    assert spec is not None
    with RobotClient(LockstepLink(SimDevice(robot)), robot) as client:
        assert any(c.table == codes.CAL_SPEED for c in client.upload_calibration(spec))
        flat = PiecewiseLinear(x=(0.0,), y=(1.0,))
        motors = MotorMapSpec(offset=(30.0,) * 4, gain=(flat,) * 4, speed=(5.0, 0.0, 0.0, -5.0))
        with pytest.raises(ControllerError, match="does not know the motor map's speed terms") as info:
            client.upload_calibration(spec.model_copy(update={"motors": motors}))
        assert info.value.code == codes.E_CALIBRATION and "\n" not in str(info.value)


def test_vel_carries_an_acceleration_only_to_a_controller_that_agreed_on_version_3() -> None:
    with RobotClient.open("sim://omni4?seed=1", timeout=0.5) as client:
        client.hello()  # a bare HELLO: version 2, what every host speaks
        assert not client.takes_vel_accel and not client.takes_vel_body_accel
        with pytest.raises(ValueError, match="does not take VEL's acceleration"):
            client.vel(0.3, 0.0, 0.0, 0.2, accel=1.4)
        with pytest.raises(ValueError, match="does not take VEL's body acceleration"):
            client.vel(0.3, 0.0, 0.0, 0.2, body_accel=(1.4, 0.0, 0.0))
        assert client.vel(0.3, 0.0, 0.0, 0.2) == Vel(30, 0, 0, 200)  # no acceleration: fine
        assert client.hello((2, 3)).version == codes.VEL_ACCEL_VERSION
        assert client.takes_vel_accel and not client.takes_vel_body_accel
        assert client.vel(0.3, 0.0, 0.0, 0.2, accel=1.4) == Vel(30, 0, 0, 200, 140)
        with pytest.raises(ValueError, match="does not take VEL's body acceleration"):
            client.vel(0.3, 0.0, 0.0, 0.2, body_accel=(1.4, 0.0, 0.0))
        assert client.hello(codes.VERSIONS).version == codes.VEL_BODY_ACCEL_VERSION
        assert client.takes_vel_accel and client.takes_vel_body_accel
        sent = client.vel(0.3, 0.1, 0.5, 0.2, body_accel=(1.4, -0.25, -2.0))
        assert sent == Vel(30, 10, 29, 200, body=(140, -25, -115))
        with pytest.raises(ValueError, match="not both"):
            client.vel(0.3, 0.0, 0.0, 0.2, accel=1.0, body_accel=(1.0, 0.0, 0.0))
        client.stop()


def test_a_binary_call_waits_for_the_retransmissions_of_its_frame() -> None:
    """A frame behind others in the send window gets its own retries only once it is the oldest, so
    it can outlive the call's first deadline; the call waits for the ARQ's verdict (its reply, or a
    give-up that says it may have run) and never fails by the clock while its frame may still be
    answered. At 5 % corrupted bytes both ways (seed 5) 4 of these 100 VELs failed by the clock
    before, and 24 more were given up behind them; now 1 is given up."""
    link = FaultLink(open_link("sim://omni4?seed=1"), seed=5)
    client = RobotClient(link, "omni4")
    client.use_binary()
    link.corrupt = 0.05
    waiting: deque[Pending] = deque()
    failures: list[str] = []

    def settle(pending: Pending) -> None:
        try:
            pending.result()
        except LinkTimeout as exc:
            failures.append(str(exc))

    for k in range(100):
        waiting.append(client.submit(Vel(k % 30 - 15, -20, 0, 100)))
        while len(waiting) >= 8:
            settle(waiting.popleft())
    while waiting:
        settle(waiting.popleft())
    link.corrupt = 0.0
    client.close()
    assert failures, "the line was meant to lose some frames for good"
    assert all("retries; it may or may not have run" in f for f in failures), failures
