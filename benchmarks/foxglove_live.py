"""What serving Foxglove live costs the robot's process: CPU per message delivered to a subscriber.

Run: ``python -m benchmarks.foxglove_live [--messages N] [--quick]``. A
:class:`~omnibot.logs.live.FoxgloveLive` on 127.0.0.1 and one Foxglove client in a child process (a
plain ``websockets`` client speaking ``foxglove.sdk.v1``, subscribed to one channel, counting what
it receives); the recorder's call ``live(topic, typename, cdr, ns)`` is made N times with a 300-byte
message, in a burst every 10 ms: 1 kHz (about what the recorder mirrors of a run with telemetry and
VEL at 100 Hz: ten topics) and 10 kHz. Measured: this process's CPU time (the publishing call and
the server's thread, not the client) per message, and the messages the client got (a client slower
than the stream loses the oldest beyond the server's backlog of 1,024). A last case publishes at
1 kHz with no client subscribed (what ``--foxglove`` costs when nobody watches).
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import time

from omnibot.logs import schemas
from omnibot.logs.live import FoxgloveLive

PAYLOAD = 300
BURST_PERIOD = 0.01
RATES = (1000, 10_000)

CLIENT = r"""
import json, sys
from websockets.sync.client import connect
port, topic = int(sys.argv[1]), sys.argv[2]
got = 0
with connect(f"ws://127.0.0.1:{port}", subprotocols=["foxglove.sdk.v1"], max_size=None) as ws:
    ws.recv(timeout=10)  # serverInfo
    channel = None
    while channel is None:
        msg = json.loads(ws.recv(timeout=10))
        if msg["op"] == "advertise":
            channel = next((c["id"] for c in msg["channels"] if c["topic"] == topic), None)
    ws.send(json.dumps({"op": "subscribe", "subscriptions": [{"id": 1, "channelId": channel}]}))
    print("subscribed", flush=True)
    try:
        while True:
            if isinstance(ws.recv(timeout=3), bytes):
                got += 1
    except TimeoutError:
        pass
print(got, flush=True)
"""


def run(messages: int, rate: int, subscribed: bool) -> dict[str, float]:
    """Publish ``messages`` at ``rate`` a second through a fresh server; with ``subscribed``, to a
    client in a child process."""
    burst = max(1, round(rate * BURST_PERIOD))
    live = FoxgloveLive(0)
    data = schemas.serialize(schemas.new("std_msgs/msg/String", data="x" * PAYLOAD), "std_msgs/msg/String")
    client = None
    try:
        live("/bench", "std_msgs/msg/String", data, 0)  # the channel exists: the client can subscribe
        if subscribed:
            client = subprocess.Popen(
                [sys.executable, "-c", CLIENT, str(live.port), "/bench"], stdout=subprocess.PIPE, text=True
            )
            assert client.stdout is not None
            if client.stdout.readline().strip() != "subscribed":
                raise RuntimeError("the client did not subscribe")
            time.sleep(0.5)  # the subscription reaches the server's thread
        cpu0, wall0 = time.process_time(), time.perf_counter()
        for i in range(messages):
            live("/bench", "std_msgs/msg/String", data, i + 1)
            if i % burst == burst - 1:
                time.sleep(BURST_PERIOD)
        wall = time.perf_counter() - wall0
        got = 0
        if client is not None:
            out, _ = client.communicate(timeout=60)
            got = int(out.split()[-1])
        time.sleep(0.2)
        cpu = time.process_time() - cpu0
    finally:
        if client is not None and client.poll() is None:
            client.kill()
            client.wait()
        live.close()
    return {"messages": messages, "received": got, "cpu_s": cpu, "wall_s": wall}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description="CPU cost of Foxglove live per message delivered")
    parser.add_argument("--messages", type=int, default=50_000)
    parser.add_argument("--quick", action="store_true", help="2,000 messages")
    args = parser.parse_args(argv)
    n = 2000 if args.quick else args.messages
    if n < 100:
        parser.error("--messages: at least 100")
    print("| case | messages | received | CPU per message | CPU, share of one core |")
    print("|---|---|---|---|---|")
    lost = 0
    for rate, subscribed in [*((r, True) for r in RATES), (RATES[0], False)]:
        r = run(n, rate, subscribed)
        lost += subscribed and rate == RATES[0] and r["received"] < n
        case = f"{rate:,} messages/s, {'one client subscribed' if subscribed else 'no client'}"
        print(
            f"| {case} | {n} | {r['received'] if subscribed else '-'} | {1e6 * r['cpu_s'] / n:.1f} us | "
            f"{100 * r['cpu_s'] / r['wall_s']:.0f} % |"
        )
    return 1 if lost else 0


if __name__ == "__main__":
    raise SystemExit(main())
