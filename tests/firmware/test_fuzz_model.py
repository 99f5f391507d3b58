"""Property test: the firmware's reply to any one command line matches a model of docs/protocol.md.

The model below is written from the protocol pages (input rules, the command table and its limits,
the tag/check suffix), not from the firmware: it does not import the parser or the limit checks.
Robot limits come from the robot's config (data, not logic). Each example sends one line to a fresh
controller and compares the reply's kind (none, OK, STATUS, HELLO, ERROR) and ERROR code.
"""

from __future__ import annotations

import binascii
import math
import re

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from omnibot.firmware.config import build_config
from omnibot.protocol import codes
from omnibot.robot import load_robot
from tests.firmware.conftest import Rig

CONFIG = build_config(load_robot("omni4"))
MOTORS = int(CONFIG["motors"])
L_MAX = float(CONFIG["distance_max_cm"])
V_MIN, V_MAX = float(CONFIG["speed_min_cms"]), float(CONFIG["speed_max_cms"])
C_MAX = float(CONFIG["curvature_max"])
F_MAX = float(CONFIG["rate_max_dps"])
SONAR_MIN = [max(60, int(p)) for p in CONFIG["sonar_period_min_ms"]]
ENCODERS = all(int(c) > 0 for c in CONFIG["encoder_cpr"])

INF = 30000
KEYWORDS = [
    "MOVE",
    "ROTATE",
    "DELTA",
    "STOP",
    "POWER",
    "VEL",
    "MODE",
    "SONAR",
    "TELEM",
    "STATUS",
    "HELLO",
    "CAL",
]
COUNTS = {
    "MOVE": (4, 4),
    "ROTATE": (2, 2),
    "DELTA": (5, 5),
    "STOP": (0, 0),
    "POWER": (1 + MOTORS, 1 + MOTORS),
}
COUNTS |= {"VEL": (4, 4), "MODE": (1, 1), "SONAR": (5, 5), "TELEM": (2, 2), "STATUS": (0, 0), "HELLO": (0, 5)}
COUNTS |= {"CAL": (4, 4)}
INF_AT = {"MOVE": 0, "ROTATE": 0, "DELTA": 4}  # "L = ±INF", "A = ±INF", "R = INF"
INT = re.compile(r"[+-]?[0-9]+\Z")
INF_TOKEN = re.compile(r"[+-]?inf\Z", re.IGNORECASE)
CHECK = re.compile(rb"\*([0-9A-Fa-f]{4})\Z")
TAG = re.compile(rb"#[0-9]{1,4}\Z")


def model(line: bytes) -> str:
    """The reply the protocol pages prescribe to ``line`` (one command, no terminator): "" for none,
    "OK", "STATUS", "HELLO", "OK|ERROR 38" (CAL: depends on the tables), or "ERROR <code>"."""
    if len(line) > 64:
        return "ERROR 22"
    check = CHECK.search(line)
    if check:
        body = line[: check.start()]
        if binascii.crc_hqx(body, 0xFFFF) != int(check[1], 16):
            return "ERROR 26"
        line = body
    tag = TAG.search(line)
    if tag:
        line = line[: tag.start()]
    fields = line.decode("latin-1").split(",")
    keyword = fields[0].strip(" \t").upper()
    if not keyword and len(fields) == 1:
        return ""
    if keyword not in KEYWORDS:
        return "ERROR 23"
    if len(fields) > 6:
        return "ERROR 24"
    params = []
    for i, field in enumerate(fields[1:]):
        token = field.strip(" \t")
        if INF_AT.get(keyword) == i and INF_TOKEN.match(token):
            params.append(-INF if token.startswith("-") else INF)
        elif INT.match(token):
            params.append(int(token))
        else:
            return "ERROR 25"
    if any(not -32768 <= p <= 32767 for p in params):
        return "ERROR 34"
    low, high = COUNTS[keyword]
    if not low <= len(params) <= high:
        return "ERROR 24"
    code = limits(keyword, params)
    if code:
        return f"ERROR {code}"
    return {"STATUS": "STATUS", "HELLO": "HELLO", "CAL": "OK|ERROR 38"}.get(keyword, "OK")


def _move(L: int, V: int, D: int, C: int, k: int) -> int:
    if not (abs(L) < L_MAX * k or (k == 1 and abs(L) == INF)):
        return 32
    if (k == 1 and not V_MIN <= abs(V) <= V_MAX) or abs(V) > V_MAX * k:
        return 28
    if abs(D) >= 360 * k:
        return 31
    if abs(C) >= C_MAX * k:
        return 30
    return 0


def limits(keyword: str, p: list[int]) -> int:
    """The command's own limits, in the order docs/protocol.md gives them."""
    if keyword == "MOVE":
        return _move(p[0], p[1], p[2], p[3], 1)
    if keyword == "DELTA":
        return 35 if not 0 <= p[4] <= INF else _move(p[0], p[1], p[2], p[3], 2)
    if keyword == "ROTATE":
        return 29 if abs(p[0]) > INF else 28 if not 0 < abs(p[1]) < F_MAX else 0
    if keyword == "POWER":
        return 27 if not 1 <= p[0] <= 30000 else 28 if any(abs(x) > 255 for x in p[1:]) else 0
    if keyword == "VEL":
        if math.hypot(p[0], p[1]) > V_MAX or abs(p[2]) >= F_MAX:
            return 28
        return 27 if not 1 <= p[3] <= 1000 else 0
    if keyword == "SONAR":
        if not 1 <= p[0] <= len(SONAR_MIN):
            return 37
        if p[1] != 0 and not SONAR_MIN[p[0] - 1] <= p[1] <= 30000:
            return 33
        return 37 if any(not 0 <= x <= 500 for x in p[2:]) else 0
    if keyword == "TELEM":
        return 27 if p[0] != 0 and not 10 <= p[0] <= 30000 else 39 if p[1] & ~255 else 0
    if keyword == "MODE":
        return 39 if p[0] & ~codes.MODE_MASK or (p[0] & 2 and not ENCODERS) else 0
    if keyword == "HELLO":
        return 39 if p and not set(p) & set(codes.VERSIONS) else 0
    return 0


def observe(line: bytes) -> str:
    """What a fresh controller answers to ``line``: the same notation as :func:`model`."""
    rig = Rig(CONFIG)
    rig.hal.send(line.decode("latin-1") + "\n")
    rig.ctrl.poll()
    replies = [r for r in rig.hal.lines() if not r.startswith(("IDLE", "WARN", "RANGE", "TEL"))]
    assert len(replies) <= 1, replies
    if not replies:
        return ""
    reply = replies[0].encode("latin-1")
    for suffix in (CHECK, TAG):
        found = suffix.search(reply)
        reply = reply[: found.start()] if found else reply
    head = reply.decode("latin-1").split(",")
    if head[0] == "ERROR":
        return f"ERROR {head[1]}"
    return head[0].split(";")[0]


def _suffix(body: bytes, kind: str, tag: str) -> bytes:
    if kind == "none":
        return body
    tagged = body + b"#" + tag.encode() if kind != "check" else body
    crc = binascii.crc_hqx(tagged, 0xFFFF)
    if kind == "tag":
        return tagged
    if kind == "bad":
        crc ^= 0x0100
    return tagged + b"*%04X" % crc


SPACE = st.sampled_from(["", " ", "\t", "  ", "\x0b", "\x0c"])
INTS = st.one_of(
    st.integers(-40, 40),
    st.integers(-1100, 1100),
    st.integers(-120, 120),
    st.sampled_from([0, 1, 10, 29, 30, 60, 99, 100, 255, 256, 359, 360, 499, 500, 999, 1000, 30000, 30001]),
    st.sampled_from([32767, 32768, -32768, -32769, 99999, -99999, 10**12]),
)
NUMBER = st.builds(lambda v, sign: ("+" if sign and v >= 0 else "") + str(v), INTS, st.booleans())
JUNK = st.sampled_from(
    ["", "1.5", "0x10", "1_0", "+", "-", "x", "INF", "-inf", "Inf", "INFINITY", "1e3", "#", "*"]
)
FIELD = st.builds(lambda a, v, b: a + v + b, SPACE, st.one_of(NUMBER, NUMBER, NUMBER, JUNK), SPACE)
JUNK_WORD = st.text(st.characters(min_codepoint=32, max_codepoint=126, exclude_characters=";,"), max_size=6)


@st.composite
def command_lines(draw: st.DrawFn) -> bytes:
    """Mostly well-formed commands with the right number of parameters, near and past their limits;
    sometimes a wrong count, junk keyword, junk field, stray bytes, a long pad or a tag/check suffix."""
    if draw(st.integers(0, 9)) == 0:
        word = draw(JUNK_WORD)
        count = draw(st.integers(0, 7))
    else:
        keyword = draw(st.sampled_from(KEYWORDS))
        word = keyword.lower() if draw(st.booleans()) else keyword
        low, high = COUNTS[keyword]
        count = draw(st.integers(low, high)) if draw(st.integers(0, 5)) else draw(st.integers(0, 7))
    field = FIELD if draw(st.integers(0, 3)) == 0 else NUMBER
    fields = draw(st.lists(field, min_size=count, max_size=count))
    pad = " " * 40 if draw(st.integers(0, 15)) == 0 else ""
    lead = draw(st.sampled_from(["", "", "", "", " ", "\t", "\x0b"]))
    body = (lead + word + "".join("," + f for f in fields) + pad).encode("latin-1")
    kind = draw(st.sampled_from(["none", "none", "none", "tag", "check", "full", "bad"]))
    return _suffix(body, kind, str(draw(st.integers(0, 99999))))


LINE = command_lines()


@settings(
    max_examples=800, derandomize=True, deadline=None, database=None, suppress_health_check=list(HealthCheck)
)
@given(line=LINE)
def test_reply_matches_the_protocol_model(line: bytes) -> None:
    expected = model(line)
    got = observe(line)
    assert got in expected.split("|") if expected else got == "", (line, expected, got)


@settings(max_examples=300, derandomize=True, deadline=None, database=None)
@given(line=st.binary(max_size=80).filter(lambda b: not set(b) & set(b";\r\n")))
def test_arbitrary_bytes_match_the_model(line: bytes) -> None:
    expected = model(line)
    got = observe(line)
    assert got in expected.split("|") if expected else got == "", (line, expected, got)


def test_model_knows_the_documented_examples() -> None:
    assert model(b"MOVE,INF,60,0,0") == "OK"
    assert model(b"MOVE,2,40,0,0") == "OK"
    assert model(b"MOVE,99999,x,0,0") == "ERROR 25"
    assert model(b"MOVE,\x0b1,40,0,0") == "ERROR 25"
    assert model(b"\x0b") == "ERROR 23"
    assert model(b"STATUS#12") == "STATUS"
    assert observe(b"MOVE,INF,60,0,0") == "OK"
