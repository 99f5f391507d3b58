"""Protocol constants shared by the host and the motor-controller firmware (docs/protocol.md).

MicroPython-safe on purpose: plain integer constants and dicts, no imports. The firmware imports this
module on the board, the host codecs import it under CPython; one table, so both always agree.
"""

# --- versions and limits ---------------------------------------------------------------------------
PROTOCOL_VERSION = 2  # the reset HELLO's and a bare HELLO's version; one number covers text and binary
VERSIONS = (2, 3, 4)  # protocol versions this implementation speaks (1 had CRC-16 frames without a length)
VEL_ACCEL_VERSION = 3  # version 3 = 2 + VEL's optional fifth parameter, the planned acceleration
VEL_BODY_ACCEL_VERSION = 4  # version 4 = 3 + VEL,VX,VY,W,T,AX,AY,AW: the planned body acceleration
INF = 30000  # "infinite" distance, angle or repeat
INT_MIN = -32768  # command parameters are 16-bit signed
INT_MAX = 32767
PARAMS_MAX = 5  # parameters of one command (events and telemetry may carry more fields)
VEL_PARAMS_MAX = 7  # VEL's in version 4 (VX, VY, W, T, AX, AY, AW): the one command allowed more
LINE_MAX = 64  # longest command, host -> controller, terminator excluded
EVENT_LINE_MAX = 256  # longest reply/event line, controller -> host, CR LF excluded
POWER_MAX = 255  # raw motor power -255..255
MOTORS_MAX = PARAMS_MAX - 1  # POWER,T,P1..Pn carries at most 4 motors

# --- text framing ----------------------------------------------------------------------------------
COMMAND_TERMINATORS = b";\r\n"  # any run of these ends a command (host -> controller)
LINE_TERMINATORS = b"\r\n"  # reply/event lines (';' is part of a STATUS reply line)
COMMAND_END = b"\n"  # what the host codec writes after a command
LINE_END = b"\r\n"  # what the controller writes after a reply or event

# --- keywords ----------------------------------------------------------------------------------------
# Command ids double as binary message types (see BINARY below).
MOVE = 1
ROTATE = 2
DELTA = 3
POWER = 4
STOP = 5
VEL = 6
MODE = 7
SONAR = 8
TELEM = 9
STATUS = 10
HELLO = 11
CAL = 12
ACK = 31  # binary only: the host acknowledges an event frame

COMMANDS = {
    "MOVE": MOVE,
    "ROTATE": ROTATE,
    "DELTA": DELTA,
    "POWER": POWER,
    "STOP": STOP,
    "VEL": VEL,
    "MODE": MODE,
    "SONAR": SONAR,
    "TELEM": TELEM,
    "STATUS": STATUS,
    "HELLO": HELLO,
    "CAL": CAL,
}
# (fewest, most) parameters of each command; POWER is T plus one power per motor.
PARAM_COUNTS = {
    MOVE: (4, 4),
    ROTATE: (2, 2),
    DELTA: (5, 5),
    POWER: (2, 5),
    STOP: (0, 0),
    VEL: (4, 7),  # 4, 5 (version 3's A) or 7 (version 4's AX, AY, AW); 6 is refused
    MODE: (1, 1),
    SONAR: (5, 5),
    TELEM: (2, 2),
    STATUS: (0, 0),
    HELLO: (0, 5),
    CAL: (4, 4),
}


def params_max(kind: int) -> int:
    """The most parameters command ``kind`` may carry before its own count is checked (ERROR 24
    beyond): 5, VEL 7 (version 4); a version 2 or 3 controller takes 5 for VEL too."""
    return VEL_PARAMS_MAX if kind == VEL else PARAMS_MAX


QUEUED = (MOVE, ROTATE, DELTA, POWER)  # commands that go through the queue
# Where a text command may spell INF as a token (``INF``, ``-INF``, any case): MOVE's L, ROTATE's A,
# DELTA's R (index of the parameter). Elsewhere ``INF`` is not an integer (ERROR 25).
INF_PARAMS = {MOVE: 0, ROTATE: 0, DELTA: 4}

# --- replies and events (binary message types; text keywords in KEYWORDS) ------------------------
OK = 32
ERROR = 33  # ERROR reply to a command
HELLO_REPLY = 34
STATUS_REPLY = 35
RANGE = 64
WARN = 65
ERROR_EVENT = 66  # ERROR raised by the motion or sensor logic, not a reply
IDLE = 67
TEL = 68

KEYWORDS = {
    MOVE: "MOVE",
    ROTATE: "ROTATE",
    DELTA: "DELTA",
    POWER: "POWER",
    STOP: "STOP",
    VEL: "VEL",
    MODE: "MODE",
    SONAR: "SONAR",
    TELEM: "TELEM",
    STATUS: "STATUS",
    HELLO: "HELLO",
    CAL: "CAL",
    ACK: "ACK",
    OK: "OK",
    ERROR: "ERROR",
    HELLO_REPLY: "HELLO",
    STATUS_REPLY: "STATUS",
    RANGE: "RANGE",
    WARN: "WARN",
    ERROR_EVENT: "ERROR",
    IDLE: "IDLE",
    TEL: "TEL",
}
REPLIES = (OK, ERROR, HELLO_REPLY, STATUS_REPLY)  # frame seq = the answered command's seq
EVENTS = (RANGE, WARN, ERROR_EVENT, IDLE)  # own seq, acknowledged by the host with ACK
# Binary payload: these types carry this many integers, then the rest of the frame is ASCII text.
TEXT_AFTER = {ERROR: 1, ERROR_EVENT: 1, WARN: 1, HELLO_REPLY: 3}  # HELLO reply: version, motors, window

# --- WARN and ERROR codes ----------------------------------------------------------------------------
W_SPEED_REDUCED = 11
W_POWER_TOO_LOW = 12
W_SONAR_STOP = 13
W_SONAR_LIMIT = 14  # project: speed limited so the robot can stop before what a sonar sees
W_UNCOVERED = 15  # project: travel where no armed sonar looks, speed limited
W_UNCOVERED_STOP = 16  # project: a running motion turned where no armed sonar looks, stopped (MODE bit 3)
W_SHORT = 17  # project: a MOVE stood still short of its distance, as its wheel encoders measured
W_REACH = 18  # project: an open-loop MOVE asked beyond the calibrated reach, run at the reach
W_BATTERY_LOW = 19  # project: the battery fell below its warning threshold
W_BATTERY_LIMIT = 20  # project: the battery fell below its power-limit threshold, motor power limited
W_NO_GYRO = 10  # project: the described gyro did not answer at boot; the board runs without it
E_QUEUE_FULL = 21
E_TOO_LONG = 22
E_UNKNOWN = 23
E_PARAM_COUNT = 24
E_NOT_INTEGER = 25
E_CHECKSUM = 26  # project: a text command's "*" check does not match (docs/protocol.md, tags)
E_TIME = 27
E_SPEED = 28
E_ANGLE = 29
E_CURVATURE = 30
E_COURSE = 31
E_DISTANCE = 32
E_SONAR_PERIOD = 33
E_RANGE16 = 34
E_REPEAT = 35
E_INTERNAL = 36
E_SONAR = 37
E_CALIBRATION = 38  # project: CAL table, index or knot order
E_UNSUPPORTED = 39  # project: MODE bit, TELEM mask bit or protocol version not supported
E_ESTOP = 40
E_UNCOVERED = 41  # project: travel where no armed sonar looks, refused (MODE bit 3)
E_CHECK_REQUIRED = 42  # project: a text command without a "*" check while MODE bit 4 requires one
W_BATTERY_STOP = 43  # project: WARN: the battery fell below its stop threshold; motors stopped, latched
E_BATTERY = 44  # project: motion blocked: battery stop latched

TEXTS = {
    W_SPEED_REDUCED: "speed reduced to what the motors can give",
    W_POWER_TOO_LOW: "power below what moves the robot, set to 0",
    W_SONAR_STOP: "emergency stop by sonar",
    W_SONAR_LIMIT: "speed limited to stop before the sonar's obstacle",
    W_UNCOVERED: "no sonar covers this direction, speed limited",
    W_UNCOVERED_STOP: "no sonar covers this direction, motion stopped",
    W_SHORT: "MOVE fell short of its distance (encoders)",
    W_REACH: "speed reduced to the calibrated reach",
    W_BATTERY_LOW: "battery low",
    W_BATTERY_LIMIT: "battery low, power limited",
    W_BATTERY_STOP: "battery flat, motors stopped",
    E_BATTERY: "motion blocked: battery flat",
    W_NO_GYRO: "no gyro: it did not answer at boot",
    E_QUEUE_FULL: "queue full",
    E_TOO_LONG: "command too long",
    E_UNKNOWN: "unknown command",
    E_PARAM_COUNT: "wrong number of parameters",
    E_NOT_INTEGER: "parameter is not an integer",
    E_TIME: "time out of range",
    E_SPEED: "speed or power out of range",
    E_ANGLE: "angle out of range",
    E_CURVATURE: "curvature out of range",
    E_COURSE: "course out of range",
    E_DISTANCE: "distance out of range",
    E_SONAR_PERIOD: "sonar period out of range",
    E_RANGE16: "value outside 16-bit range",
    E_REPEAT: "repeat out of range",
    E_INTERNAL: "internal fault",
    E_SONAR: "sonar distance out of range or no such sonar",
    E_CALIBRATION: "calibration table, index or knot order wrong",
    E_UNSUPPORTED: "mode, mask bit or version not supported",
    E_ESTOP: "motion blocked: emergency stop latched",
    E_UNCOVERED: "motion refused: no sonar covers this direction",
    E_CHECKSUM: "checksum mismatch",
    E_CHECK_REQUIRED: "check required",
}

# --- STATUS states -----------------------------------------------------------------------------------
STATE_MOVING = 0
STATE_IDLE = 1
STATE_ESTOP = 3
STATE_BATTERY = 4  # project: the battery stop is latched

# --- MODE bits -----------------------------------------------------------------------------------------
MODE_SIMULATION = 1  # bit 0: run every algorithm, apply no power
MODE_CLOSED_LOOP = 2  # bit 1: closed-loop wheel-speed control (needs motor encoders)
MODE_BINARY = 4  # bit 2: binary framing in both directions (after the OK of this MODE)
MODE_REFUSE_UNCOVERED = 8  # bit 3: with the sonar stop armed, refuse travel no armed sonar covers
MODE_CHECKED_TEXT = 16  # bit 4: a text command runs only with a matching "*" check (else ERROR 42)
MODE_SEQUENCED_TEXT = 32  # bit 5: tags of checked text are sequence numbers; a duplicate is not run again
MODE_MASK = 63  # every defined bit; others get ERROR 39 (the UNO's own mask: firmware-avr/src/checks.h)

# --- TEL mask bits; groups follow t_ms and mask in bit order -------------------------------------
TEL_POWER = 1  # n, p1..pn: applied motor powers
TEL_ENCODERS = 2  # n, c1..cn: motor encoder counts (cumulative, signed 32-bit)
TEL_TRACKING = 4  # m, k1..km: passive tracking-wheel counts (cumulative, signed 32-bit)
TEL_GYRO = 8  # yaw rate, 0.01 deg/s
TEL_HEADING = 16  # integrated yaw, 0.01 deg, not wrapped
TEL_BATTERY = 32  # battery voltage, mV
TEL_QUEUE = 64  # state, queued commands
TEL_SONAR = 128  # k, r1..rk: last range of each sonar, cm (-1: none)
TEL_MASK = 255
TEL_PERIOD_MIN = 10  # ms; TELEM,P with 0 < P < 10 gets ERROR 27

# --- CAL tables (CAL,T,I,X,Y) --------------------------------------------------------------------------
CAL_K = 0  # Y = K in 0.001 PWM counts per cm/s of rim speed (I = X = 0)
CAL_KT = 1  # K_t(power): knot I = (X power, Y factor x 1000)
CAL_KR = 2  # K_r(power)
CAL_OFFSET = 3  # dead-band offset of motor I (X = 0), Y in 0.1 PWM counts
CAL_ROLLER_COS = 4  # roller drag of wheel I (X = 0): cosine coefficient, Y in 0.1 PWM counts (signed)
CAL_ROLLER_SIN = 5  # the same, sine coefficient
CAL_ROLLER_COAST = 6  # roller drag's coast time: knot I = (X speed cm/s, Y ms)
CAL_SPEED = 7  # motor I's speed term (X = 0): Y in 0.1 PWM counts per m/s of its rim speed (signed)
CAL_REACH = 8  # the calibrated reach: knot I = (X folded course degrees, Y speed cm/s; 0: none)
CAL_SLIP = 9  # the floor's wheel creep (X = 0): I 0 roll in 0.01 mm/s, 1 combined and 2 scale x 10000, 3 ramp in 1e-6 s^3/m
CAL_SLIP_SCALE = 10000  # CAL table 9's combined and scale: Y = value x 10000
CAL_GAIN = 20  # 20 + i: gain table of motor i: knot I = (X nominal power, Y gain x 1000)
CAL_MOTORS = 8  # motors with a gain table at most
CAL_KL = 10  # 10 + k: K_l curve k; I = -1 sets its course (X degrees), I = -2 drops curves k.., I >= 0 a knot
CAL_KL_DROP = -2
CAL_COURSE_MAX = 90  # a K_l curve's course, degrees: 0..90 (courses fold onto 0..90 at most)
CAL_KL_CURVES = 8
CAL_KNOTS_MAX = 16
CAL_SCALE = 1000

# --- binary framing (frame.py, arq.py) ------------------------------------------------------------
FRAME_DELIMITER = 0  # COBS-encoded frames are separated by 0x00
FRAME_SYNC = 0x80  # flag in the type byte: the sender abandoned every earlier frame
FRAME_TYPE_MASK = 0x7F
FRAME_MAX = 255  # bytes of a frame between its delimiters (the length byte L)
SEQ_MAX = 255  # sequence numbers run 1..255 and wrap to 1; 0 = unsequenced (TEL only)
# Send windows (docs/protocol.md, "Window"): a controller announces the window it takes in its binary
# HELLO reply (WINDOW_MIN..WINDOW_LIMIT); the host sends at most min(that, WINDOW) frames unacknowledged
# (WINDOW_MIN before the reply) and takes the controller's events with a window of WINDOW.
TEXT_WINDOW = 192  # text flow control: a host keeps at most this many bytes of commands unanswered
TEXT_SEQ_WINDOW = 8  # MODE bit 5: tags a host sends past its oldest unanswered one; kept replies
TEXT_SEQ_MAX = 9999  # MODE bit 5: tags run 1..9999 and wrap to 1 (linecheck.TAG_DIGITS digits)
WINDOW_MIN = 8  # the least a controller announces (the UNO's): a line full with a 2 ms loop, no host load
WINDOW = 32  # this implementation's window: the host's, the MicroPython controller's (a loaded host)
WINDOW_LIMIT = 127  # the most: W duplicates behind and W - 1 new seqs ahead must not meet in SEQ_MAX
RETRY_TIMEOUT_MS = 50
RETRIES = 10  # retransmissions before giving up (0.55 s): 1 % of bytes lost or corrupted never gets there
# The host's: after 9 retransmissions 50 ms apart, 8 more waiting 100, 200, then 400 ms (3.2 s in
# all), so a stalled line, controller or host (a pty emulator not scheduled for a second) costs no call.
HOST_RETRIES = 17
HOST_RETRY_TIMEOUT_MAX_MS = 400
# Sequenced text's host (MODE bit 5): as many fast retransmissions more. A text VEL and its reply are
# about 42 bytes on the line, a binary one's about 25, and one damaged byte costs the try: at 5 % of
# the bytes damaged a try gets through 0.95^42 = 12 % of the time against binary's 28 %, so text needs
# ln(1 - 0.28) / ln(1 - 0.12) = 2.6 times binary's 18 tries to give up as seldom (BENCHMARKS.md).
TEXT_HOST_EXTRA_RETRIES = 29
