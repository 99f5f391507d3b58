"""The attack and fault suite (issue 27): what a fault, a full disk or a foreign page does, with a
"wrong" column per row that must read 0.

Run: ``python -m benchmarks.attack_suite [--quick] [--only FAMILY,...] [--json]``; re-run it on every
change that touches the protocol, a firmware, a link or a server. Families (fixed seeds, bounded
counts; ``--quick`` is the CI smoke size):

1. ``fuzz``: the fuzz targets of ``tests/fuzz/targets.py`` (text and binary input of the MicroPython
   firmware, checked against the host codec) on seeded random and mutated inputs; the UNO firmware in
   simavr fed random command lines and compared, verdict by verdict, with the MicroPython firmware
   (skipped, saying why, without simavr).
2. ``bits``: every single-bit error and a seeded sample of double-bit errors of checked text commands
   as the client sends them (``#tag*check``, MODE bit 4 set, as the client does after its tag probe;
   and without bit 4 for comparison), into the MicroPython firmware; and of the binary frames of
   ``tests/protocol/test_frame_errors.py``, through the firmware's and the host's decoders.
3. ``links``: ``benchmarks/link_faults.py``'s VEL stream through :class:`RobotClient` (default settings:
   text probes tags and so runs checked) and through binary, at 1 % and 5 % per byte of drop,
   corrupt, duplicate (a byte sent twice) and repeat (a whole write or read sent twice). The client's
   own setup MODE (bit 4) is taken off link_faults' "corrupted"; text lines the controller ran
   without a valid check while MODE bit 4 was clear are counted as wrong (the client's promise: a
   line cut before its check runs nothing). A call that failed with LinkTimeout for a command that
   ran is counted apart ("timed out, ran"): the client said it may or may not have run, which is
   true; "wrongly failed" is a call that said a command did not run (an ERROR) while it did.
4. ``logs``: ``omnibot follow --log`` on a full tmpfs, under ``ulimit -f``, into a read-only
   directory, against the same follow without a log (simulator truth); ``omnibot send --log`` killed
   with SIGKILL mid-run (``tests/logs/conftest.py``), then ``log recover``.
5. ``web``: a foreign Origin, ``null``, a rebinding Host, a missing or wrong token, against the
   dashboard and Foxglove live (with a token: every port the process listens on), and Teleop panel
   twists whose numbers are a string, a bool or NaN: the distance the simulated robot moved.
6. ``ros2``: the bridge as ``omnibot ros2`` runs it (benchmarks/ros2_latency.py's set-up) in a private
   network namespace, a cyclonedds peer publishing TwistStamped on ``cmd_vel`` with NaN and inf, with
   1e30 and 1e308, and a flood; a std_msgs/String publisher on ``cmd_vel``; malformed CDR (a struct
   named TwistStamped of another layout, with its own type information and with TwistStamped's, and
   TwistStamped's CDR cut short or garbage): the simulated robot's displacement and speed, and the
   bridge's exceptions. cyclonedds checks a sample's CDR against its type before it sends it, so
   malformed CDR never leaves a cyclonedds peer (counted as "refused by DDS"); a raw RTPS writer that
   sends it anyway is not covered.
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import io
import itertools
import json
import math
import os
import random
import shutil
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Iterator
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from benchmarks import link_faults
from omnibot.protocol import binary, codes, linecheck, text
from omnibot.protocol.messages import (
    Command,
    Delta,
    ErrorReply,
    Hello,
    HelloReply,
    Mode,
    Move,
    Power,
    Rotate,
    Sonar,
    Status,
    StatusReply,
    Stop,
    Telem,
    Vel,
)
from omnibot.transport import FaultLink
from omnibot.transport.faults import _Channel

REPO = Path(__file__).resolve().parents[1]
FAMILIES = ("fuzz", "bits", "links", "logs", "web", "ros2")


@dataclass
class Row:
    """One line of a family's table: ``counts`` are shown in order, ``wrong`` must be 0."""

    family: str
    name: str
    counts: dict[str, Any] = field(default_factory=dict)
    wrong: int = 0
    note: str = ""


# ------------------------------------------------------------------------------------------ 1. fuzz
TEXTY = b"MOVEDLTAPWRSHCIFNK,;#*+- \t\x0b\x0c\r\n0123456789abcdefINF"


def _fuzz_inputs(rng: random.Random, seeds: list[bytes], n: int, texty: bytes | None) -> Iterator[bytes]:
    """n inputs: a third random bytes, a third random over ``texty`` (or bytes), a third mutated seeds."""
    for k in range(n):
        kind = k % 3
        if kind == 0:
            yield rng.randbytes(rng.randrange(201))
        elif kind == 1 and texty is not None:
            yield bytes(rng.choice(texty) for _ in range(rng.randrange(121)))
        else:
            data = bytearray(b"".join(rng.choice(seeds) for _ in range(rng.randint(1, 4))))
            for _ in range(rng.randint(1, 4)):
                i = rng.randrange(len(data) + 1)
                op = rng.randrange(4)
                if op == 0 and data:
                    data[min(i, len(data) - 1)] ^= 1 << rng.randrange(8)
                elif op == 1 and data:
                    del data[min(i, len(data) - 1)]
                elif op == 2:
                    data.insert(i, rng.randrange(256))
                else:
                    data[i:i] = rng.choice(seeds)[: rng.randint(1, 12)]
            yield bytes(data)


def _text_seeds() -> list[bytes]:
    lines = [text.encode(c) for c in _commands(40)]
    lines += [text.encode(c, tag=k + 1) for k, c in enumerate(_commands(40))]
    return [*lines, b"MODE,16\n", b"STATUS;STOP;HELLO,2\r\n", b"MOVE,INF,60,0,0\n", b"VEL,0,0,-32768,1000\n"]


def _binary_seeds() -> list[bytes]:
    return [binary.encode(c, k % 255 + 1) for k, c in enumerate(_commands(60))]


def _run_target(target: Callable[[bytes], None], inputs: Iterator[bytes]) -> tuple[int, int, str]:
    """(inputs, failures, the first failure's input and error)."""
    count = bad = 0
    first = ""
    for data in inputs:
        count += 1
        try:
            target(data)
        except Exception as exc:  # an AssertionError is an invariant broken, anything else a crash
            bad += 1
            if not first:
                first = f"{data!r}: {type(exc).__name__}: {str(exc)[:120]}"
    return count, bad, first


def fuzz_micropython(n: int) -> list[Row]:
    from tests.fuzz import targets

    rows = []
    for name, target, seeds, texty in (
        ("MicroPython text input", targets.text_input, _text_seeds(), TEXTY),
        ("MicroPython binary input", targets.binary_input, _binary_seeds(), None),
    ):
        start = time.monotonic()
        count, bad, first = _run_target(
            target, _fuzz_inputs(random.Random(f"attack:{name}"), seeds, n, texty)
        )
        rows.append(
            Row(
                "fuzz",
                name,
                {"inputs": count, "seconds": round(time.monotonic() - start, 1)},
                bad,
                first or "invariants of tests/fuzz/targets.py",
            )
        )
    return rows


UNO_VALUES = [
    "0", "1", "-1", "29", "30", "40", "100", "101", "255", "256", "-255", "359", "360", "899", "900",
    "999", "1000", "30000", "-30000", "30001", "32767", "-32767", "-32768", "32768", "-32769", "65535",
    "99999", "INF", "-INF", "inf", "x", "", " 5", "+5", "-0", "1e3", "0x10",
]  # fmt: skip
UNO_KEYWORDS = [
    "MOVE",
    "ROTATE",
    "DELTA",
    "VEL",
    "POWER",
    "STOP",
    "STATUS",
    "SONAR",
    "TELEM",
    "HELLO",
    "FOO",
    "move",
]
UNO_MODES = ["0", "1", "2", "3", "8", "16", "17", "-32768", "32", "99999", "x"]  # none with bit 2 (binary)
SENTINEL_TAG = "9999"


def _uno_line(rng: random.Random) -> str:
    cmds = []
    for _ in range(rng.randint(1, 3)):
        if rng.random() < 0.08:
            cmd = "MODE," + rng.choice(UNO_MODES)
        else:
            fields = [rng.choice(UNO_KEYWORDS)]
            for _ in range(rng.choice((0, 1, 2, 4, 4, 5, 5, 6))):
                v = rng.choice(UNO_VALUES) if rng.random() < 0.7 else str(rng.randint(-40000, 40000))
                fields.append(v)
            cmd = ",".join(fields)
            if rng.random() < 0.05:
                cmd = cmd.replace(",", rng.choice((" , ", ",\t", ",,")), 1)
            if rng.random() < 0.03:
                cmd += "\x00"
        if rng.random() < 0.3:
            data = cmd.encode("latin-1")
            suffix = linecheck.suffix(data, str(rng.randrange(1000)).encode(), rng.random() < 0.9)
            if rng.random() < 0.1:  # a damaged check
                suffix = suffix[:-1] + (b"0" if suffix[-1:] != b"0" else b"1")
            cmd = (data + suffix).decode("latin-1")
        cmds.append(cmd)
    return ";".join(cmds)


NOMINAL = {
    "MOVE": [10, 40, 0, 0],
    "ROTATE": [90, 45],
    "DELTA": [0, 0, 10, 0, 1],
    "VEL": [10, 0, 0, 500],
    "POWER": [100, 10, 10, 10, 10],
    "SONAR": [1, 60, 0, 100, 20],
    "TELEM": [0, 0],
}


def _boundary_lines() -> list[str]:
    """Every field of every command with a parameter at an extreme of 16 bits, every two fields at
    -32768 or 32767 in each combination (two -32768s squared overflow a 32-bit sum), and NUL-ended
    keywords."""
    out = []
    for word, params in NOMINAL.items():
        for i in range(len(params)):
            for v in (-32768, -32767, 32767):
                p = list(params)
                p[i] = v
                out.append(",".join([word, *map(str, p)]))
        for i, j in itertools.combinations(range(len(params)), 2):
            for a, b in itertools.product((-32768, 32767), repeat=2):
                p = list(params)
                p[i], p[j] = a, b
                out.append(",".join([word, *map(str, p)]))
    return [*out, "STATUS\x00", "STOP\x00", "HELLO\x00,2"]


def _verdicts(lines: list[str]) -> list[str]:
    """The replies' verdicts (OK, ERROR,code, HELLO, STATUS, with their tags), events left out: on the
    UNO time runs, in the MicroPython reference it stands still."""
    out = []
    for line in lines:
        body, tag, _ = text.split_suffix(line.encode("latin-1"))
        word = body.split(b",")[0].decode("latin-1")
        if word in ("OK", "HELLO", "STATUS"):
            out.append(f"{word}#{tag}")
        elif word == "ERROR":
            fields = body.split(b",")
            code = int(fields[1]) if len(fields) > 1 and fields[1].isdigit() else -1
            if code in (codes.E_ESTOP,) or (tag is None and code in _EVENT_ERRORS):
                continue
            out.append(f"ERROR,{code}#{tag}")
    return out


_EVENT_ERRORS = {36}  # raised by motion/sensor logic while time runs (an internal fault event)


def fuzz_uno(n: int) -> list[Row]:
    from tests.firmware.fakehal import FakeHAL

    from omnibot.firmware.config import build_config
    from omnibot.firmware.controller import Controller
    from omnibot.robot import load_robot
    from omnibot.uno import UnoEmulator, UnoError, missing_tools

    reason = missing_tools()
    if reason:
        return [Row("fuzz", "UNO (simavr) text lines vs MicroPython", {"lines": 0}, 0, f"skipped: {reason}")]
    try:
        emu = UnoEmulator("omni4", range_cm=100)
    except UnoError as exc:
        return [Row("fuzz", "UNO (simavr) text lines vs MicroPython", {"lines": 0}, 0, f"skipped: {exc}")]
    config = build_config(load_robot("omni4"))
    hal = FakeHAL(config["motors"], len(config["sonar_period_min_ms"]))
    ctrl = Controller(hal, config)
    hal.lines()
    sentinel = (b"HELLO" + linecheck.suffix(b"HELLO", SENTINEL_TAG.encode(), True)).decode()
    stop = (b"STOP" + linecheck.suffix(b"STOP", b"9998", True)).decode()
    rng = random.Random("attack:uno")
    fd = os.open(emu.path, os.O_RDWR | os.O_NOCTTY)
    buf = b""
    differ = hangs = codes_differ = 0
    first = code_example = ""
    count = 0

    def uno_lines(timeout: float = 3.0) -> list[str] | None:
        nonlocal buf
        out: list[str] = []
        deadline = time.monotonic() + timeout
        import select

        while True:
            end = buf.find(b"\r\n")
            if end >= 0:
                line = buf[:end].decode("latin-1")
                buf = buf[end + 2 :]
                if line.startswith("HELLO,") and line.split("*")[0].endswith("#" + SENTINEL_TAG):
                    return out
                out.append(line)
                continue
            left = deadline - time.monotonic()
            if left <= 0:
                return None
            ready, _, _ = select.select([fd], [], [], left)
            if ready:
                buf += os.read(fd, 4096)

    try:
        assert uno_lines is not None
        os.write(fd, (sentinel + "\n").encode())
        uno_lines(5.0)
        lines = _boundary_lines() + [_uno_line(rng) for _ in range(n)]
        for line in lines:
            count += 1
            wire = f"{line}\n{stop}\n{sentinel}\n".encode("latin-1")
            hal.rx = wire
            ctrl.poll()
            ref = [ln for ln in hal.lines() if not ln.startswith("HELLO,") or "#" + SENTINEL_TAG not in ln]
            os.write(fd, wire)
            got = uno_lines()
            if got is None:
                hangs += 1
                first = first or f"no reply to {line!r}"
                break
            uno, mpy = _verdicts(got), _verdicts(ref)
            if uno != mpy:
                runs = len(uno) != len(mpy) or any(
                    u.startswith("OK") != m.startswith("OK") for u, m in zip(uno, mpy, strict=False)
                )
                if runs:
                    differ += 1
                    first = first or f"{line!r}: UNO {uno} MicroPython {mpy}"
                else:
                    codes_differ += 1
                    code_example = code_example or f"{line!r}: UNO {uno} MicroPython {mpy}"
    finally:
        os.close(fd)
        with contextlib.suppress(UnoError):
            emu.close()
    return [
        Row(
            "fuzz",
            "UNO (simavr) text lines vs MicroPython",
            {
                "lines": count,
                "ran on one, refused on the other": differ,
                "hangs": hangs,
                "other ERROR code": codes_differ,
            },
            differ + hangs,
            (first or "same verdict (OK or refused) for every command")
            + (f"; codes differ, e.g. {code_example}" if code_example else ""),
        )
    ]


# ------------------------------------------------------------------------------------------ 2. bits
def _commands(n: int, seed: int = 7) -> list[Command]:
    """n commands of every type a client sends, with seeded parameters inside the omni4's limits."""
    rng = random.Random(seed)
    makers: list[Callable[[], Command]] = [
        lambda: link_faults.vel(rng.randrange(3_000_000)),
        lambda: Move(rng.randint(1, 499), rng.randint(30, 100), rng.randint(-359, 359), rng.randint(-99, 99)),
        lambda: Rotate(rng.randint(-29999, 29999), rng.choice((-1, 1)) * rng.randint(1, 899)),
        lambda: Delta(rng.randint(-99, 99), rng.randint(-9, 9), rng.randint(-90, 90), 0, rng.randint(0, 40)),
        lambda: Power(rng.randint(1, 5000), tuple(rng.randint(-255, 255) for _ in range(4))),
        Stop,
        Status,
        lambda: Telem(rng.randint(0, 1000), rng.randint(0, 255)),
        lambda: Sonar(1, rng.randint(0, 400), 0, rng.randint(0, 1000), rng.randint(0, 100)),
        lambda: Mode(rng.choice((0, 1, 2, 3, 8, 9)) | codes.MODE_CHECKED_TEXT),
        lambda: Hello((codes.PROTOCOL_VERSION,)),
    ]
    return [makers[k % len(makers)]() if k % 3 else makers[0]() for k in range(n)]


class _Firmware:
    """The MicroPython firmware on a fake HAL, logging what it executed (link_faults.executed_log)."""

    def __init__(self, checked_only: bool) -> None:
        from tests.fuzz import targets

        self.hal, self.ctrl = targets._controller()
        self.ctrl.checked_only = checked_only
        self.log = link_faults.executed_log(self.ctrl)

    def feed(self, data: bytes) -> tuple[list[tuple[int, tuple[int, ...]]], bytes]:
        self.log.clear()
        self.hal.tx.clear()
        self.hal.rx = data
        self.ctrl.poll()
        ran = list(self.log)
        out = bytes(self.hal.tx)
        # back to rest: whatever ran is undone (STOP, mode and telemetry off), outside the log
        checked_only = self.ctrl.checked_only
        self.ctrl.execute(codes.STOP, [])
        self.ctrl.execute(codes.TELEM, [0, 0])
        self.ctrl.execute(codes.MODE, [codes.MODE_CHECKED_TEXT if checked_only else 0])
        self.ctrl.execute(codes.SONAR, [1, 0, 0, 0, 0])
        self.ctrl.checked_only = checked_only
        self.ctrl.latched = False
        self.hal.tx.clear()
        self.log.clear()
        return ran, out


def _said_ok(out: bytes, tag: int) -> bool:
    """The client (tags on) would take a success for ``tag`` from the controller's output."""
    from omnibot.client.wire import TextWire

    wire = TextWire(True)
    for packet in wire.feed(out):
        if (
            isinstance(packet, binary.Packet)
            and packet.seq == tag
            and not isinstance(packet.message, ErrorReply)
        ):
            return True
    return False


def _answered(out: bytes, tag: int, cmd: Command) -> bool:
    """A query (HELLO, STATUS: no OK to log) that got its own answer under its tag: it ran."""
    from omnibot.client.wire import TextWire

    want = {codes.HELLO: HelloReply, codes.STATUS: StatusReply}.get(cmd.TYPE)
    if want is None:
        return False
    return any(
        isinstance(p, binary.Packet) and p.seq == tag and isinstance(p.message, want)
        for p in TextWire(True).feed(out)
    )


def text_bit_errors(n_commands: int, double: int, checked_only: bool) -> Row:
    fw = _Firmware(checked_only)
    follow_cmd = Status()
    rng = random.Random("attack:bits:text")
    flips = ran_other = said_ok = 0
    example = ""
    commands = _commands(n_commands)
    for k, cmd in enumerate(commands):
        tag = k % text.TAG_MAX + 1
        wire = text.encode(cmd, tag=tag)
        after = text.encode(follow_cmd, tag=(tag % text.TAG_MAX) + 1)
        sent = (cmd.TYPE, cmd.params())
        bits = 8 * len(wire)
        pairs: list[tuple[int, ...]] = (
            [tuple(rng.sample(range(bits), 2)) for _ in range(double)]
            if double
            else [(b,) for b in range(bits)]
        )
        for flip in pairs:
            bad = bytearray(wire)
            for b in flip:
                bad[b >> 3] ^= 1 << (b & 7)
            ran, out = fw.feed(bytes(bad) + after)
            flips += 1
            other = [r for r in ran if r not in (sent, (follow_cmd.TYPE, ()))]
            if other:
                ran_other += 1
                example = example or f"{bytes(bad)!r} ran {other}"
            if sent not in ran and not _answered(out, tag, cmd) and _said_ok(out, tag):
                said_ok += 1
                example = example or f"{bytes(bad)!r} said OK, ran {ran}"
    what = "double-bit sample" if double else "every single bit"
    mode = "MODE bit 4 set (client default)" if checked_only else "MODE bit 4 clear (before)"
    return Row(
        "bits",
        f"checked text, {what}, {mode}",
        {
            "commands": n_commands,
            "errors tried": flips,
            "ran a command not sent": ran_other,
            "said OK, not run": said_ok,
        },
        ran_other + said_ok,
        example,
    )


def binary_bit_errors(double: int | None) -> Row:
    """The frames of tests/protocol/test_frame_errors.py between two good ones: every 1-bit error
    through the incremental decoders, or ``double`` 2-bit errors per frame (None: every one)."""
    from tests.protocol import test_frame_errors as fe

    rng = random.Random("attack:bits:binary")
    tried = changed = lost = 0
    example = ""
    for name, wire in fe.FRAMES:
        sent = fe.parse(wire)
        allowed = {fe.SENT_PREV, sent, fe.SENT_NEXT}
        known: dict[bytes, Any] = {fe.PREV[1:-1]: fe.SENT_PREV, fe.NEXT[1:-1]: fe.SENT_NEXT, wire[1:-1]: sent}
        bits = 8 * len(wire)
        if double is None:
            errors: Iterator[tuple[int, ...]] = ((a, b) for a in range(bits) for b in range(a + 1, bits))
        elif double:
            errors = iter([tuple(rng.sample(range(bits), 2)) for _ in range(double)])
        else:
            errors = ((b,) for b in range(bits))
        for flip in errors:
            stream = fe.PREV + fe.flip(wire, *flip) + fe.NEXT
            accepted = (
                fe.accepted_by_decoder(stream) if len(flip) == 1 else fe.accepted_by_split(stream, known)
            )
            tried += 1
            if any(k not in allowed for k in accepted):
                changed += 1
                example = example or f"{name}, bits {flip}: accepted {accepted}"
            if not accepted or accepted[-1] != fe.SENT_NEXT:
                lost += 1
                example = example or f"{name}, bits {flip}: the next frame was lost"
    what = (
        "every single bit" if double == 0 else "every double bit" if double is None else "double-bit sample"
    )
    return Row(
        "bits",
        f"binary frames ({len(fe.FRAMES)}), {what}",
        {
            "commands": len(fe.FRAMES),
            "errors tried": tried,
            "ran a command not sent": changed,
            "next frame lost": lost,
        },
        changed + lost,
        example or "accepted = a frame that parses; it must be one sent",
    )


def bits(quick: bool) -> list[Row]:
    n = 100 if quick else 2000
    pairs = 5 if quick else 25
    return [
        text_bit_errors(n, 0, True),
        text_bit_errors(n, pairs, True),
        text_bit_errors(n, 0, False),
        binary_bit_errors(0),
        binary_bit_errors(50 if quick else None),
    ]


# ----------------------------------------------------------------------------------------- 3. links
class _Doubles(_Channel):
    """A direction of the line that sends a byte twice (``duplicate``, rate per byte) or a whole
    write or read twice (``repeat``, rate per chunk)."""

    def __init__(self, name: str, seed: int, link: FaultLink, kind: str, rate: float) -> None:
        super().__init__(name, seed, link, True)
        self.kind = kind
        self.rate = rate
        self.events = random.Random(f"omnibot-doubles:{seed}:{name}")
        self.hits = 0

    def mangle(self, data: bytes) -> bytes:
        self.bytes += len(data)
        if not data:
            return data
        if self.kind == "repeat":
            if self.events.random() < self.rate:
                self.hits += 1
                return data + data
            return data
        out = bytearray()
        for byte in data:
            out.append(byte)
            if self.events.random() < self.rate:
                out.append(byte)
                self.hits += 1
        return bytes(out)


LINK_KINDS = ("drop", "corrupt", "duplicate", "repeat")
_fault_link = link_faults.fault_link


@dataclass
class _Watch:
    """What the controller of one link-fault scenario was handed: the client's own MODE that set bit 4
    (answered OK, so link_faults counts it as a command not sent: taken off "corrupted"), and the
    lines it ran (answered OK) without a valid check while bit 4 was clear: what the bit is there to
    refuse (a line with a check is verified whatever the bit; a refused line ran nothing)."""

    setup_modes: int = 0
    unguarded: int = 0
    example: bytes = b""


_watches: list[_Watch] = []


def _watch(controller: Any) -> _Watch:
    watch = _Watch()
    handle, answer_ok = controller.handle, controller._ok
    oks = [0]

    def ok() -> None:
        oks[0] += 1
        answer_ok()

    def watched(cmd: bytes | None) -> None:
        before, ran = controller.checked_only, oks[0]
        handle(cmd)
        if cmd is None or oks[0] == ran:
            return
        if not before and controller.checked_only and cmd.startswith(b"MODE"):
            watch.setup_modes += 1
        elif not before and linecheck.split(cmd)[3] != linecheck.CHECKED:
            watch.unguarded += 1
            watch.example = watch.example or cmd

    controller._ok = ok
    controller.handle = watched
    _watches.append(watch)
    return watch


def _more_faults(inner: Any, kind: str, rate: float, seed: int) -> FaultLink:
    _watch(inner.device.controller)
    if kind not in ("duplicate", "repeat"):
        return _fault_link(inner, kind, rate, seed)
    link = FaultLink(inner, seed=seed)
    link.tx = _Doubles("tx", seed, link, kind, rate)
    link.rx = _Doubles("rx", seed, link, kind, rate)
    return link


def links(quick: bool) -> list[Row]:
    n = 100 if quick else 1000
    rates = (0.01,) if quick else (0.01, 0.05)
    rows = []
    link_faults.fault_link = _more_faults  # run_one builds its link through this name
    try:
        for rate in rates:
            for kind in LINK_KINDS:
                for protocol in ("text", "binary"):
                    o = link_faults.run_one(protocol, kind, rate, n, clean_setup=False)
                    watch = _watches.pop()
                    corrupted = o.corrupted - watch.setup_modes
                    name = f"{'text, checked (client default)' if protocol == 'text' else 'binary'}, {kind} {100 * rate:g} %"
                    rows.append(
                        Row(
                            "links",
                            name,
                            {
                                "commands": n,
                                "faults": o.faults,
                                "corrupted executed": corrupted,
                                "lost but OK": o.lost_unseen,
                                "doubled": o.twice,
                                "wrongly failed": o.false_failures - o.timed_out_ran,
                                "timed out, ran": o.timed_out_ran,
                                "failed, not run": o.true_failures,
                                "lines taken without MODE bit 4": watch.unguarded
                                if protocol == "text"
                                else "-",
                            },
                            corrupted
                            + o.lost_unseen
                            + o.twice
                            + o.false_failures
                            - o.timed_out_ran
                            + (watch.unguarded if protocol == "text" else 0),
                            f"first line taken unchecked: {watch.example!r}"
                            if watch.example and protocol == "text"
                            else "",
                        )
                    )
    finally:
        link_faults.fault_link = _fault_link
    return rows


# ------------------------------------------------------------------------------------------ 4. logs
LOG_LIMIT = 64 * 1024
"""Bytes the log's file may grow to (tmpfs size, ulimit -f): a few chunks, well before the path's end."""
FOLLOW_KEYS = ("rms_cross_track_m", "max_cross_track_m", "final_error_m", "duration_s")
PATH_TOLERANCE = 0.002  # m (and s for the duration): the same run, to the simulator's determinism


def _follow(
    work: Path, name: str, log: str | None, wrap: list[str], preexec: Callable[[], None] | None = None
) -> dict[str, Any]:
    """``omnibot follow`` of a 0.5 m circle at 0.4 m/s in a subprocess: its report, status, stderr."""
    from omnibot.control import standard_path, write_path

    path_file = work / "circle.csv"
    if not path_file.exists():
        write_path(standard_path("circle", size=0.5), path_file)
    report = work / f"{name}.json"
    argv = ["follow", str(path_file), "--speed", "0.4", "--report", str(report)]
    if log is not None:
        argv += ["--log", log]
    env = {**os.environ, "PYTHONPATH": str(REPO / "src")}
    proc = subprocess.run(
        [*wrap, sys.executable, "-m", "omnibot", *argv],
        capture_output=True,
        text=True,
        env=env,
        preexec_fn=preexec,
        timeout=600,
        check=False,
    )
    data = json.loads(report.read_text()) if report.exists() else {}
    return {"status": proc.returncode, "report": data, "stderr": proc.stderr}


def _recoverable(log: Path, work: Path) -> bool:
    from omnibot.cli import main as cli

    out = work / (log.stem + ".recovered.mcap")
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        status = cli(["log", "recover", str(log), "-o", str(out)])
    return status == 0 and out.exists() and out.stat().st_size > 0


def _log_row(name: str, plain: dict[str, Any], run: dict[str, Any], log: Path | None, work: Path) -> Row:
    rep, ref = run["report"], plain["report"]
    moved_off = max((abs(rep[k] - ref[k]) for k in FOLLOW_KEYS), default=0.0) if rep else None
    completed = bool(rep.get("completed"))
    tracebacks = run["stderr"].count("Traceback")
    recover = log is not None and log.exists() and log.stat().st_size > 0
    recovered = _recoverable(log, work) if recover and log is not None else None
    refused_before = not rep and run["status"] == 2  # said so before the robot moved
    off = 0 if refused_before else int(not completed or moved_off is None or moved_off > PATH_TOLERANCE)
    wrong = off + tracebacks + int(recovered is False)
    warn = [ln for ln in run["stderr"].splitlines() if "warning" in ln or "error" in ln]
    return Row(
        "logs",
        name,
        {
            "exit": run["status"],
            "completed": completed if rep else "refused before driving" if refused_before else False,
            "path vs no log (max diff)": "-" if moved_off is None else f"{1000 * moved_off:.1f} mm",
            "tracebacks": tracebacks,
            "log recovered": "-" if recovered is None else recovered,
        },
        wrong,
        (warn[0][:140] if warn else ""),
    )


def logs(quick: bool) -> list[Row]:
    import resource

    rows = []
    with tempfile.TemporaryDirectory(prefix="omnibot-attack-") as tmp:
        work = Path(tmp)
        plain = _follow(work, "plain", None, [])
        ref_ok = bool(plain["report"].get("completed"))
        rows.append(
            Row(
                "logs",
                "follow without --log (reference)",
                {"exit": plain["status"], "completed": ref_ok},
                int(not ref_ok),
            )
        )

        def limit() -> None:
            resource.setrlimit(resource.RLIMIT_FSIZE, (LOG_LIMIT, LOG_LIMIT))

        log = work / "ulimit.mcap"
        rows.append(
            _log_row("ulimit -f 64 KiB", plain, _follow(work, "ulimit", str(log), [], limit), log, work)
        )
        can_mount = os.geteuid() == 0 and shutil.which("unshare") is not None
        if can_mount:
            full = work / "full"
            full.mkdir()
            log = full / "run.mcap"
            wrap = [
                "unshare",
                "-m",
                "sh",
                "-c",
                f'mount -t tmpfs -o size={LOG_LIMIT} tmpfs {full} && exec "$@"',
                "sh",
            ]
            run = _follow(work, "tmpfs", str(log), wrap)
            # the tmpfs is gone with its namespace: what it held is lost, so only the run is judged
            rows.append(_log_row("tmpfs of 64 KiB fills up", plain, run, None, work))
            ro = work / "ro"
            ro.mkdir()
            wrap = [
                "unshare",
                "-m",
                "sh",
                "-c",
                f'mount --bind {ro} {ro} && mount -o remount,bind,ro {ro} && exec "$@"',
                "sh",
            ]
            rows.append(
                _log_row(
                    "read-only directory", plain, _follow(work, "ro", str(ro / "run.mcap"), wrap), None, work
                )
            )
        else:
            rows.append(
                Row("logs", "tmpfs full, read-only directory", {}, 0, "skipped: needs root and unshare -m")
            )
        if not quick:
            from tests.logs.conftest import kill_mid_run, readable_tels

            log = work / "killed.mcap"
            try:
                kill_mid_run(log)
                tels = readable_tels(log)
                ok = _recoverable(log, work)
                rows.append(
                    Row(
                        "logs",
                        "SIGKILL mid-recording (send --log)",
                        {"TEL readable": tels, "log recovered": ok},
                        int(not ok or tels < 100),
                    )
                )
            except AssertionError as exc:
                rows.append(
                    Row("logs", "SIGKILL mid-recording (send --log)", {}, 1, f"harness failed: {exc}")
                )
    return rows


# ------------------------------------------------------------------------------------------- 5. web
MOVED = 0.002  # m: a drive attempt that moved the robot more than this got through
DRIVE_SECONDS = 1.0  # wall-clock seconds a page that got in keeps driving


async def _dashboard_attempt(port: int, host: str, origin: str | None, query: str) -> str:
    """Open the dashboard's websocket as (host, origin, query) and drive forward for DRIVE_SECONDS:
    "refused" (the handshake was), "closed" (the server closed it) or "open"."""
    import websockets
    from tests.web.test_security import FORWARD, _open

    try:
        ws = await _open(port, host, origin, query)
    except (websockets.exceptions.InvalidStatus, websockets.exceptions.InvalidHandshake, OSError):
        return "refused"
    try:
        end = time.monotonic() + DRIVE_SECONDS
        while time.monotonic() < end:
            await ws.send(FORWARD)
            await asyncio.sleep(0.05)
        return "open"
    except websockets.exceptions.ConnectionClosed:
        return "closed"
    finally:
        await ws.close()


def _dashboard_case(
    name: str, token: str | None, host: str, origin: str | None, query: str, expect_drive: bool
) -> Row:

    from tests.web.conftest import ROOM
    from tests.web.test_security import pose, sim_time, wait_for_state

    from omnibot.web import Dashboard

    with Dashboard(ROOM, http_port=0, token=token) as dash:
        port = dash.port
        wait_for_state(dash)
        before = pose(dash)
        verdict = asyncio.run(
            _dashboard_attempt(port, host.format(port=port), origin and origin.format(port=port), query)
        )
        start = sim_time(dash)
        end = time.monotonic() + 30.0
        while sim_time(dash) < start + 0.5 and time.monotonic() < end:  # simulated time for a VEL to show
            time.sleep(0.02)
        after = pose(dash)
    moved = math.hypot(after[0] - before[0], after[1] - before[1])
    wrong = int(moved > MOVED) if not expect_drive else 0
    return Row(
        "web",
        name,
        {"connection": verdict, "robot moved": f"{1000 * moved:.1f} mm"},
        wrong,
        "control: the page's own origin must drive" if expect_drive else "",
    )


def dashboard_rows() -> list[Row]:
    own, evil = "127.0.0.1:{port}", "evil.example:{port}"
    token = "s3cret-token-1234"
    return [
        _dashboard_case(
            "dashboard: own origin, no token set (control)", None, own, "http://" + own, "", True
        ),
        _dashboard_case("dashboard: foreign Origin", None, own, "http://evil.example", "", False),
        _dashboard_case("dashboard: Origin null", None, own, "null", "", False),
        _dashboard_case("dashboard: rebinding Host", None, evil, "http://" + evil, "", False),
        _dashboard_case("dashboard: token set, none given", token, own, "http://" + own, "", False),
        _dashboard_case(
            "dashboard: token set, wrong one", token, own, "http://" + own, "?token=wrong-token-123", False
        ),
    ]


def _foxglove_case(name: str, token: str | None, expect_drive: bool, **how: Any) -> Row:
    """One attempt of ``tests/logs/test_live_access.py`` (``how``: host, origin, query, twist,
    protocol; ``every_port``: against each port the process listens on) against a fresh server."""
    from tests.logs.test_live_access import listening_ports, moved_after

    from omnibot.logs.live import FoxgloveLive

    every_port = how.pop("every_port", False)
    live = FoxgloveLive(0, token=token)
    try:
        ports = sorted(listening_ports()) if every_port else [live.port]
        results = []
        for port in ports:
            fmt = {k: v.format(port=port) if isinstance(v, str) else v for k, v in how.items()}
            results.append(moved_after(live, port, **fmt))
    finally:
        live.close()
    verdicts = sorted({verdict for verdict, _, _ in results})
    moved = max(m for _, m, _ in results)
    notices = [s["message"] for _, _, statuses in results for s in statuses]
    counts = {"connection": "/".join(verdicts), "robot moved": f"{1000 * moved:.1f} mm"}
    if every_port:
        counts["ports tried"] = str(len(ports))
    note = "control: must drive" if expect_drive else (f"notice: {notices[0]}" if notices else "")
    return Row("web", name, counts, int(moved <= MOVED) if expect_drive else int(moved > MOVED), note)


def foxglove_rows() -> list[Row]:
    own, evil = "127.0.0.1:{port}", "evil.example:{port}"
    token = "live-token-12345"
    ahead = {"linear": {"x": 0.4, "y": 0.0, "z": 0.0}, "angular": {"x": 0.0, "y": 0.0, "z": 0.0}}
    return [
        _foxglove_case("Foxglove: no Origin, no token set (control)", None, True),
        _foxglove_case(
            "Foxglove: old subprotocol foxglove.websocket.v1 (control)",
            None,
            True,
            protocol="foxglove.websocket.v1",
        ),
        _foxglove_case(
            "Foxglove: Foxglove's web app origin (control)", None, True, origin="https://app.foxglove.dev"
        ),
        _foxglove_case("Foxglove: foreign Origin, no token set", None, False, origin="http://evil.example"),
        _foxglove_case("Foxglove: Origin null, no token set", None, False, origin="null"),
        _foxglove_case(
            "Foxglove: rebinding Host, no token set", None, False, host=evil, origin="http://" + evil
        ),
        _foxglove_case(
            "Foxglove: token set, with it (control)", token, True, host=own, query=f"?token={token}"
        ),
        _foxglove_case(
            "Foxglove: token set, none given, every port of the process", token, False, every_port=True
        ),
        _foxglove_case(
            "Foxglove: token set, wrong one, every port of the process",
            token,
            False,
            every_port=True,
            query="?token=wrong-token-123",
        ),
        _foxglove_case(
            'Foxglove: panel twist with "0.3" (a string)',
            None,
            False,
            twist={**ahead, "linear": {"x": "0.3", "y": 0.0, "z": 0.0}},
        ),
        _foxglove_case(
            "Foxglove: panel twist with true (a bool)",
            None,
            False,
            twist={**ahead, "linear": {"x": True, "y": 0.0, "z": 0.0}},
        ),
        _foxglove_case(
            "Foxglove: panel twist with NaN",
            None,
            False,
            twist={**ahead, "linear": {"x": float("nan"), "y": 0.0, "z": 0.0}},
        ),
    ]


def web(quick: bool) -> list[Row]:
    return [*dashboard_rows(), *foxglove_rows()]


# ------------------------------------------------------------------------------------------ 6. ros2
ROS2_PEER = r"""
import math, sys, time
from omnibot.logs import schemas
from omnibot.logs.rosmsg import header, twist
from omnibot.ros2.dds import DEFAULT, Node, qos, topic_name
from omnibot.ros2.types import dds_name, dds_type, to_dds

TS = "geometry_msgs/msg/TwistStamped"
case, count = sys.argv[1], int(sys.argv[2])
node = Node()


def matched(writer, wait=10.0):
    end = time.monotonic() + wait
    while writer.get_publication_matched_status().current_count < 1 and time.monotonic() < end:
        time.sleep(0.01)
    time.sleep(0.2)
    return writer.get_publication_matched_status().current_count


def ahead(vx=0.4):
    return to_dds(schemas.new(TS, header=header(0, "base_link"), twist=twist(vx, 0, 0)), TS)


if case == "wrongtype":  # a std_msgs/String on cmd_vel saying "0.4"
    writer = node.writer("cmd_vel", "std_msgs/msg/String")
    matched(writer, 3.0)
    for k in range(count):
        writer.write(to_dds(schemas.new("std_msgs/msg/String", data="0.4"), "std_msgs/msg/String"))
        time.sleep(0.02)
    print(f"{count} written")
    raise SystemExit
if case == "malformed":
    # 1. a type named TwistStamped of another layout (a byte blob), its own type information
    # 2. the same claiming TwistStamped's type information (a lying peer)
    # 3. TwistStamped itself, its CDR cut short or replaced by garbage
    from cyclonedds.idl import make_idl_struct, types as idl
    from cyclonedds.pub import DataWriter
    from cyclonedds.topic import Topic

    written = refused = unmatched = 0
    real = dds_type(TS)
    real.__idl__.fill_type_data()
    for lying in (False, True):
        blob_type = make_idl_struct("Blob_", dds_name(TS), {"blob": idl.sequence[idl.uint8]})
        blob_type.__idl_annotations__["extensibility"] = "final"
        blob_type.__idl__.populate()
        if lying:
            blob_type.__idl__._xt_data = real.__idl__._xt_data
            blob_type.__idl__._xt_bytedata = real.__idl__._xt_bytedata
        peer = Node()  # a participant of its own: one topic name, one type
        topic = Topic(peer.participant, topic_name("cmd_vel"), blob_type, qos=qos(DEFAULT, TS))
        writer = DataWriter(peer.participant, topic, qos=qos(DEFAULT, TS))
        if not matched(writer, 3.0):
            unmatched += count
            peer.close()
            continue
        good = ahead().serialize()
        for k in range(count):
            try:
                writer.write(blob_type(blob=list(good[4 : 4 + k % len(good)])))
                written += 1
            except Exception:
                refused += 1
            time.sleep(0.02)
        peer.close()
    writer = node.writer("cmd_vel", TS)
    matched(writer)
    good = ahead().serialize()
    cuts = [good[:n] for n in range(4, len(good), 4)] + [good[:4] + bytes(range(200, 256))] * 4
    serialize = real.serialize
    for k in range(count):
        real.serialize = lambda self, _b=cuts[k % len(cuts)], **kw: _b
        try:
            writer.write(ahead())
            written += 1
        except Exception:
            refused += 1
        time.sleep(0.02)
    real.serialize = serialize
    print(f"{written} written, {refused} refused by DDS, {unmatched} never matched")
    raise SystemExit
writer = node.writer("cmd_vel", TS)
matched(writer)
nan, inf = math.nan, math.inf
values = {
    "nonfinite": [(nan, 0, 0), (inf, 0, 0), (0, -inf, 0), (0, 0, nan), (nan, nan, nan), (0, 0, inf)],
    "huge": [(1e30, 0, 0), (0, -1e30, 0), (0, 0, 1e30), (1e308, 1e308, -1e308)],
    "flood": [(0.1, 0, 0)],
    "steady": [(0.1, 0, 0)],
}[case]
sent = 0
for k in range(count):
    vx, vy, w = values[k % len(values)]
    writer.write(to_dds(schemas.new(TS, header=header(0, "base_link"), twist=twist(vx, vy, w)), TS))
    sent += 1
    if case != "flood":
        time.sleep(0.02)
print(sent)
"""
ROS2_CASES = {
    # case: (messages, what must hold)
    "nonfinite": (120, "NaN and inf in linear.x/y, angular.z at 50 Hz: must not move"),
    "huge": (80, "1e30 and 1e308 at 50 Hz: speed within the robot's limits"),
    "wrongtype": (100, 'a std_msgs/String publisher on cmd_vel ("0.4") at 50 Hz: must not move'),
    "malformed": (
        60,
        "malformed CDR (a TwistStamped-named blob, with and without TwistStamped's type information; "
        "TwistStamped's CDR cut short or garbage) at 50 Hz: must not move",
    ),
    "steady": (100, "0.1 m/s at 50 Hz (control: the robot's top speed beside a flood's)"),
    "flood": (
        20_000,
        "20,000 TwistStamped (0.1 m/s) as fast as one peer writes: no VEL faster than published, stopped 1 s after",
    ),
}
FLOOD_SPEED = 0.1  # m/s, what the flood and its control publish
VEL_ROUNDING = 0.005  # m/s: a VEL's parts are whole cm/s


class _SentVels:
    """A client tracer: the fastest translation any VEL sent asked for, m/s."""

    def __init__(self) -> None:
        self.top = 0.0

    def link_bytes(self, t: float, kind: str, data: bytes = b"", note: str = "") -> None:
        pass

    def message(self, t: float, direction: str, message: Any) -> None:
        if direction == "command" and isinstance(message, Vel):
            self.top = max(self.top, 0.01 * math.hypot(message.vx, message.vy))


def _ros2_case(case: str, quick: bool, control_top: float | None = None) -> Row:
    from tests.teleop.fakes import truth

    from omnibot.client import robot_session
    from omnibot.protocol import codes
    from omnibot.ros2 import attach
    from omnibot.runtime import Cycle, Runtime
    from omnibot.teleop import Pacer

    count, what = ROS2_CASES[case]
    if quick:  # the control keeps its 2 s: the top speed it sets comes after the first second
        count = min(count, 2000 if case == "flood" else 100 if case == "steady" else 30)
    if case == "malformed":  # three attempts of count each
        count = count // 3
    speeds: list[float] = []
    errors: list[str] = []
    vels = _SentVels()
    with robot_session("sim://omni4", "omni4", timeout=0.5) as session:
        client, robot = session.client, session.robot
        client.add_tracer(vels)
        sim = truth(client)

        def watch(cycle: Cycle) -> None:
            tw = sim.twist
            speeds.append(max(math.hypot(tw.vx, tw.vy), 0.0))

        runtime = Runtime(client, period=0.02)
        runtime.add_sink(watch)
        node = attach(runtime, robot)
        env = dict(os.environ, PYTHONPATH=os.pathsep.join([p for p in sys.path if p]))
        with tempfile.TemporaryFile("w+") as out:
            peer = subprocess.Popen([sys.executable, "-c", ROS2_PEER, case, str(count)], stdout=out, env=env)
            p0 = sim.pose
            try:
                runtime.start()
                client.telemetry(0.02, codes.TEL_MASK)
                runtime.pacer = Pacer(client, 0.02)
                runtime.run(until=lambda: peer.poll() is not None, duration=120)
                during = len(speeds)
                runtime.run(duration=1.0)  # the cmd_vel timeout (0.5 s) passes: the robot stops
            except Exception as exc:  # the bridge must survive whatever arrives
                errors.append(f"{type(exc).__name__}: {exc}")
                during = len(speeds)
            finally:
                runtime.close()
                node.close()
                if peer.poll() is None:
                    peer.kill()
                peer.wait()
            out.seek(0)
            sent = out.read().strip()
        p1 = sim.pose
        limit = robot.limits.speed_max
    moved = math.hypot(p1.x - p0.x, p1.y - p0.y)
    top = max(speeds[:during], default=0.0)
    end_speed = speeds[-1] if speeds else 0.0
    if case in ("nonfinite", "wrongtype", "malformed"):
        wrong = int(moved > MOVED)
    elif case == "huge":
        wrong = int(top > 1.05 * limit)
    elif case == "steady":
        wrong = int(end_speed > 0.01)
    else:
        # the robot's top speed overshoots 0.1 m/s by 16-29 % on the wheel-speed loop and varies by
        # 0.01 m/s between runs of the control alone (wall-clock paced): what a flood could add is
        # in the VELs the bridge sends, so those are judged; the robot's top speed is shown beside
        # the control's
        wrong = int(vels.top > FLOOD_SPEED + VEL_ROUNDING) + int(end_speed > 0.01)
    wrong += len(errors)
    return Row(
        "ros2",
        f"cmd_vel: {what}",
        {
            "published": sent or "?",
            "robot moved": f"{1000 * moved:.1f} mm",
            "top speed": f"{top:.3f} m/s"
            + (f" (control {control_top:.3f})" if control_top is not None else ""),
            "fastest VEL sent": f"{vels.top:.3f} m/s",
            "speed 1 s after": f"{end_speed:.3f} m/s",
        },
        wrong,
        "; ".join(errors) or f"robot's speed_max {limit:g} m/s",
    )


def _ros2_here(quick: bool) -> list[Row]:
    rows = [_ros2_case(case, quick) for case in ROS2_CASES if case != "flood"]
    control = float(rows[-1].counts["top speed"].split()[0])
    return [*rows, _ros2_case("flood", quick, control)]


def ros2(quick: bool) -> list[Row]:
    """In a private network namespace (``unshare -n``, ``lo`` up) made for a child run of this family,
    as benchmarks/netns.py does; skipped, saying why, where none can be made."""
    import importlib.util

    from omnibot.ros2.netns import in_private_namespace

    if in_private_namespace():
        os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
        return _ros2_here(quick)
    why = None
    if importlib.util.find_spec("cyclonedds") is None:
        why = "cyclonedds is not installed (pip install 'omnibot[ros2]')"
    elif shutil.which("unshare") is None or shutil.which("ip") is None:
        why = "unshare or ip is missing (no private network namespace for DDS)"
    if why is None:
        argv = ["--only", "ros2", "--json", *(["--quick"] if quick else [])]
        command = 'ip link set lo up && exec "$0" -m benchmarks.attack_suite "$@"'
        env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(REPO / "src"), str(REPO)]))
        proc = subprocess.run(
            ["unshare", "-n", "sh", "-c", command, sys.executable, *argv],
            capture_output=True,
            text=True,
            env=env,
            cwd=REPO,
            timeout=900,
            check=False,
        )
        try:
            return [Row(**r) for r in json.loads(proc.stdout.strip().splitlines()[-1])]
        except (ValueError, IndexError, TypeError):
            why = f"the namespaced run failed (exit {proc.returncode}): {proc.stderr.strip()[-300:]}"
    return [Row("ros2", "cmd_vel floods and malformed messages", {}, 0, f"not covered: {why}")]


# ---------------------------------------------------------------------------------------- the suite
def fuzz(quick: bool) -> list[Row]:
    return [*fuzz_micropython(300 if quick else 20_000), *fuzz_uno(30 if quick else 2000)]


RUNNERS: dict[str, Callable[[bool], list[Row]]] = {
    "fuzz": fuzz,
    "bits": bits,
    "links": links,
    "logs": logs,
    "web": web,
    "ros2": ros2,
}
TITLES = {
    "fuzz": "1. Fuzzing both firmwares",
    "bits": "2. Bit errors of checked text commands and binary frames",
    "links": "3. Link faults (VEL stream through RobotClient, per scenario)",
    "logs": "4. Recording under a full disk, a read-only directory, SIGKILL",
    "web": "5. A foreign page against the dashboard and Foxglove live",
    "ros2": "6. ROS 2 cmd_vel floods and malformed messages",
}


def report(rows: list[Row]) -> str:
    out: list[str] = []
    for family in FAMILIES:
        mine = [r for r in rows if r.family == family]
        if not mine:
            continue
        keys: list[str] = []
        for r in mine:
            keys += [k for k in r.counts if k not in keys]
        out += ["", f"**{TITLES[family]}**", ""]
        out.append("| " + " | ".join(["case", *keys, "wrong", "note"]) + " |")
        out.append("|---" * (len(keys) + 3) + "|")
        for r in mine:
            cells = [str(r.counts.get(k, "")) for k in keys]
            note = r.note.replace("|", "\\|").replace("\n", " ")
            out.append("| " + " | ".join([r.name, *cells, f"**{r.wrong}**", note]) + " |")
    return "\n".join(out)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description="the attack and fault suite: every 'wrong' column must be 0")
    parser.add_argument("--quick", action="store_true", help="small counts, 1 %% faults only, no SIGKILL run")
    parser.add_argument(
        "--only", default=",".join(FAMILIES), help=f"families, comma-separated ({','.join(FAMILIES)})"
    )
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args(argv)
    chosen = [f.strip() for f in args.only.split(",") if f.strip()]
    unknown = [f for f in chosen if f not in RUNNERS]
    if unknown:
        parser.error(
            f"--only: unknown famil{'y' if len(unknown) == 1 else 'ies'} {', '.join(unknown)} (of {', '.join(FAMILIES)})"
        )
    start = time.monotonic()
    rows: list[Row] = []
    for family in FAMILIES:
        if family in chosen:
            rows += RUNNERS[family](args.quick)
    if args.json:
        print(json.dumps([asdict(r) for r in rows]))
    else:
        print(report(rows))
        wrong = sum(r.wrong for r in rows)
        print(f"\n({len(rows)} rows, {wrong} wrong in all, {time.monotonic() - start:.0f} s wall)")
    return 1 if any(r.wrong for r in rows) else 0


if __name__ == "__main__":
    raise SystemExit(main())
