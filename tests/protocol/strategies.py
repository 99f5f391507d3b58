"""Hypothesis strategies for every protocol message, within what each codec can carry."""

from __future__ import annotations

from hypothesis import strategies as st

from omnibot.protocol import codes
from omnibot.protocol import messages as m

i16 = st.integers(-32768, 32767)
i32 = st.integers(-(2**31), 2**31 - 1)
power = st.integers(-255, 255)
# printable ASCII; ERROR/WARN text is the rest of the line, so commas are fine there
texts = st.text(st.characters(min_codepoint=0x20, max_codepoint=0x7E), min_size=1, max_size=40)
names = st.text(st.sampled_from("abcdefghijklmnopqrstuvwxyzABCXYZ0123456789-_."), min_size=1, max_size=20)
small_tuple = st.lists(power, max_size=8).map(tuple)

commands: st.SearchStrategy[m.Command] = st.one_of(
    st.builds(m.Move, i16, i16, i16, i16),
    st.builds(m.Rotate, i16, i16),
    st.builds(m.Delta, i16, i16, i16, i16, i16),
    st.just(m.Stop()),
    st.builds(m.Power, i16, st.lists(i16, min_size=1, max_size=4).map(tuple)),
    st.builds(m.Vel, i16, i16, i16, i16, i16),
    st.builds(m.Vel, i16, i16, i16, i16, body=st.tuples(i16, i16, i16)),  # version 4
    st.builds(m.Mode, i16),
    st.builds(m.Sonar, i16, i16, i16, i16, i16),
    st.builds(m.Telem, i16, i16),
    st.just(m.Status()),
    st.builds(m.Hello, st.lists(i16, max_size=5).map(tuple)),
    st.builds(m.Cal, i16, i16, i16, i16),
)

telemetry = st.builds(
    m.Telemetry,
    st.integers(0, 2**32 - 1),
    powers=st.none() | small_tuple,
    encoders=st.none() | st.lists(i32, max_size=8).map(tuple),
    tracking=st.none() | st.lists(i32, max_size=4).map(tuple),
    gyro_rate=st.none() | i32,
    heading=st.none() | i32,
    battery_mv=st.none() | st.integers(0, 65535),
    queue=st.none() | st.tuples(st.sampled_from([0, 1, 3]), st.integers(0, 64)),
    ranges=st.none() | st.lists(st.integers(-1, 500), max_size=4).map(tuple),
)

status_replies = st.builds(
    m.StatusReply,
    st.sampled_from([0, 1, 3]),
    st.integers(0, 64),
    st.integers(0, 64),
    st.integers(0, 255),
    small_tuple,
    st.tuples(i16, i16, i16, i16),
)
# The binary HELLO reply announces the controller's window; the text line has none (window 0).
binary_hellos = st.builds(
    m.HelloReply,
    st.integers(0, 255),
    names,
    st.integers(0, 8),
    st.integers(codes.WINDOW_MIN, codes.WINDOW_LIMIT),
)
text_hellos = st.builds(m.HelloReply, st.integers(0, 255), names, st.integers(0, 8))

replies: st.SearchStrategy[m.Reply] = st.one_of(
    st.just(m.Ok()), st.builds(m.ErrorReply, st.integers(0, 99), texts), binary_hellos, status_replies
)
text_replies: st.SearchStrategy[m.Reply] = st.one_of(
    st.just(m.Ok()), st.builds(m.ErrorReply, st.integers(0, 99), texts), text_hellos, status_replies
)

events: st.SearchStrategy[m.Event] = st.one_of(
    st.builds(m.Range, st.integers(0, 16), st.integers(-1, 500)),
    st.builds(m.Warn, st.integers(0, 99), texts),
    st.builds(m.ErrorReply, st.integers(0, 99), texts),
    st.just(m.Idle()),
    telemetry,
)

host_bound = replies | events  # controller -> host
text_host_bound = text_replies | events
messages = commands | host_bound
