"""What a faulty line does to commands, text against binary, through the client and the real firmware.

Run: ``python -m benchmarks.link_faults [--commands N] [--waiting W] [--quick] [--json]``. Each scenario opens a
lockstep link (115200 baud, simulated time) to a fresh simulated omni4, puts a fault wrapper on it
(both directions), switches to the protocol and streams N ``VEL`` commands through
:class:`~omnibot.client.RobotClient` (``submit``, at most W waiting, 8 by default; 32 fills the
binary window the simulated controller announces; every reply awaited). Every
``VEL`` has its own parameters, so the controller's log of what it executed (every command it
answered OK, taken inside the firmware) tells each command apart. Text is the client's default:
tagged, checked and sequenced (MODE bits 4 and 5, set up on the clean line before the stream), so a
command whose reply is lost is sent again and answered from the controller's kept reply. Per 10,000
commands:

* **corrupted**: commands executed that were never sent (changed parameters, another command);
* **lost unseen**: commands never executed whose call reported success;
* **twice**: commands executed more than once;
* **false failures**: calls that raised (timeout, protocol error, ERROR) for a command that ran;
  of them, ``timed_out_ran`` (in ``--json``) raised LinkTimeout, which says the command may or may
  not have run (no reply came), the rest said it did not.

Faults, each alone, at a rate p of 1 % and 0.1 % per byte, both ways, fixed seeds:

* drop: the byte is lost; corrupt: one bit of the byte flips (``faults+`` wrapper);
* delay: the line pauses 2-20 ms before the byte (order kept);
* stall: the line stops for 0.1-0.4 s at random times, p of the time in all (each way: at 1 %
  one stall every 25 s); stalls are shorter than the binary protocol's retry budget (the host's
  3.2 s): a longer outage is reported as a failure ("may or may not have run") by design;
* reorder: the byte swaps places with one 1-8 bytes later in the same chunk.
"""

from __future__ import annotations

import argparse
import json
import random
import time
from collections import Counter, deque
from dataclasses import asdict, dataclass

from omnibot.client import Pending, RobotClient
from omnibot.errors import LinkTimeout, OmnibotError
from omnibot.firmware.controller import Controller
from omnibot.protocol import codes
from omnibot.protocol.messages import Vel
from omnibot.sim import SimDevice
from omnibot.transport import FaultLink, LockstepLink
from omnibot.transport.faults import _Channel

KINDS = ("drop", "corrupt", "delay", "stall", "reorder")
RATES = (0.01, 0.001)
PER = 10_000
WAITING = 8
DELAY = (0.002, 0.020)  # s, a pause before a byte
STALL = (0.1, 0.4)  # s, the line stopped
STALL_MEAN = sum(STALL) / 2


def vel(k: int) -> Vel:
    """The k-th command: parameters unique for k < 3.3 million, all inside the omni4's limits."""
    return Vel(k % 61 - 30, (k // 61) % 61 - 30, 0, 100 + (k // 3721) % 900)


def unvel(params: tuple[int, ...]) -> int | None:
    """The k of a VEL's parameters, None if no vel(k) has them."""
    vx, vy, w, t = params
    if w != 0 or not (-30 <= vx <= 30 and -30 <= vy <= 30 and 100 <= t < 1000):
        return None
    return (vx + 30) + 61 * (vy + 30) + 3721 * (t - 100)


class _Hiccups(_Channel):
    """A direction of the line with pauses (delay, stall) or swapped bytes (reorder)."""

    def __init__(self, name: str, seed: int, link: FaultLink, kind: str, rate: float) -> None:
        super().__init__(name, seed, link, True)
        self.kind = kind
        self.rate = rate
        self.events = random.Random(f"omnibot-hiccups:{seed}:{name}")
        self.hits = 0
        self._stall_end = 0.0
        self._next_stall = self._stall_gap()

    def _stall_gap(self) -> float:
        """Time to the next stall: stalls of STALL_MEAN s take up ``rate`` of the time."""
        return self.events.expovariate(self.rate / STALL_MEAN)

    def mangle(self, data: bytes) -> bytes:
        self.bytes += len(data)
        if self.kind != "reorder":
            return data
        out = bytearray(data)
        for i in range(len(out)):
            if self.events.random() < self.rate:
                j = min(len(out) - 1, i + self.events.randint(1, 8))
                out[i], out[j] = out[j], out[i]
                self.hits += i != j
        return bytes(out)

    def push(self, now: float, data: bytes) -> None:
        if self.kind == "reorder" or not data:
            super().push(now, data)
            return
        release = max(now, self._last_release)
        if self.kind == "stall":
            while release >= self._next_stall:  # a stall began: the line is blocked until it ends
                self._stall_end = self._next_stall + self.events.uniform(*STALL)
                self._next_stall = self._stall_end + self._stall_gap()
                self.hits += 1
            release = max(release, self._stall_end)
            self.queue.append((release, data))
            self._last_release = release
            return
        start = 0
        for i in range(len(data)):
            if self.events.random() < self.rate:
                if i > start:
                    self.queue.append((release, data[start:i]))
                release += self.events.uniform(*DELAY)
                self.hits += 1
                start = i
        self.queue.append((release, data[start:]))
        self._last_release = release


@dataclass
class Outcome:
    protocol: str
    kind: str
    rate: float
    commands: int
    corrupted: int = 0
    lost_unseen: int = 0
    twice: int = 0
    false_failures: int = 0
    timed_out_ran: int = 0
    true_failures: int = 0
    faults: int = 0
    sim_seconds: float = 0.0

    def per(self, count: int) -> float:
        return PER * count / self.commands


def fault_link(inner: LockstepLink, kind: str, rate: float, seed: int) -> FaultLink:
    if kind in ("drop", "corrupt"):
        return FaultLink(inner, seed=seed, **{kind: rate})  # type: ignore[arg-type]
    link = FaultLink(inner, seed=seed)
    link.tx = _Hiccups("tx", seed, link, kind, rate)
    link.rx = _Hiccups("rx", seed, link, kind, rate)
    return link


def executed_log(ctrl: Controller) -> list[tuple[int, tuple[int, ...]]]:
    """Start logging every command the firmware answers OK: (keyword, parameters)."""
    log: list[tuple[int, tuple[int, ...]]] = []
    current: list[tuple[int, tuple[int, ...]]] = []
    execute, ok = ctrl.execute, ctrl._ok

    def logged_execute(kw: int, p: list[int]) -> None:
        current.append((kw, tuple(p)))
        try:
            execute(kw, p)
        finally:
            current.pop()

    def logged_ok() -> None:
        if current:
            log.append(current[-1])
        ok()

    ctrl.execute = logged_execute  # type: ignore[method-assign]
    ctrl._ok = logged_ok  # type: ignore[method-assign]
    return log


def run_one(
    protocol: str,
    kind: str,
    rate: float,
    n: int,
    seed: int = 1,
    waiting_max: int = WAITING,
    clean_setup: bool = True,
    sequenced: bool = True,
) -> Outcome:
    """One scenario. ``clean_setup``: the client sets up its protocol on a clean line (text: the tag
    question and MODE bits 4 and 5) and only the stream meets the faults; else text sets up under
    them. ``sequenced=False``: the controller refuses MODE bit 5 (ERROR 39), as a firmware before it."""
    device = SimDevice("omni4", seed=seed)
    if not sequenced:
        limits = device.controller.limits
        check = limits.check

        def no_bit_5(kw: int, p: list[int]) -> int:
            return (
                codes.E_UNSUPPORTED if kw == codes.MODE and p[0] & codes.MODE_SEQUENCED_TEXT else check(kw, p)
            )

        limits.check = no_bit_5  # type: ignore[method-assign]
    inner = LockstepLink(device)
    link = fault_link(inner, kind, rate, seed)
    out = Outcome(protocol, kind, rate, n)
    with RobotClient(link, "omni4") as client:
        client.sleep(0.05)  # the greeting
        saved = (link.drop, link.corrupt, link.tx, link.rx)
        link.drop = link.corrupt = 0.0  # set up on a clean line: the stream is what is measured
        link.tx, link.rx = _Channel("tx", seed, link, False), _Channel("rx", seed, link, False)
        if protocol == "binary":
            client.use_binary()
        elif clean_setup:
            client.status()  # the tag question, then MODE bits 4 and 5 (checked, sequenced text)
        link.drop, link.corrupt, link.tx, link.rx = saved
        log = executed_log(device.controller)
        t0 = client.clock.now()
        ok: dict[int, bool] = {}
        timed_out: set[int] = set()
        waiting: deque[tuple[int, Pending]] = deque()

        def settle(k: int, pending: Pending) -> None:
            try:
                pending.result()
                ok[k] = True
            except OmnibotError as exc:
                ok[k] = False
                if isinstance(exc, LinkTimeout):
                    timed_out.add(k)

        for k in range(n):
            try:
                waiting.append((k, client.submit(vel(k))))
            except OmnibotError as exc:
                ok[k] = False
                if isinstance(exc, LinkTimeout):
                    timed_out.add(k)
            while len(waiting) >= waiting_max:
                settle(*waiting.popleft())
        while waiting:
            settle(*waiting.popleft())
        client.sleep(1.0)  # late retransmissions land
        out.sim_seconds = client.clock.now() - t0
    runs = Counter(unvel(p) if kw == codes.VEL else None for kw, p in log)
    out.corrupted = sum(c for k, c in runs.items() if k is None or k >= n)
    for k in range(n):
        times = runs.get(k, 0)
        out.lost_unseen += times == 0 and ok[k]
        out.twice += times >= 2
        out.false_failures += times >= 1 and not ok[k]
        out.timed_out_ran += times >= 1 and not ok[k] and k in timed_out
        out.true_failures += times == 0 and not ok[k]
    s = link.stats
    out.faults = s.tx_dropped + s.tx_corrupted + s.rx_dropped + s.rx_corrupted
    for channel in (link.tx, link.rx):
        out.faults += getattr(channel, "hits", 0)
    return out


def run(
    n: int, kinds: tuple[str, ...] = KINDS, rates: tuple[float, ...] = RATES, waiting: int = WAITING
) -> list[Outcome]:
    return [
        run_one(protocol, kind, rate, n, waiting_max=waiting)
        for rate in rates
        for kind in kinds
        for protocol in ("text", "binary")
    ]


def report(outcomes: list[Outcome]) -> str:
    lines = [
        f"per {PER:,} commands | corrupted | lost unseen | twice | false failures | (told failed, not run) | faults | sim s",
        "---|---|---|---|---|---|---|---",
    ]
    for o in outcomes:
        lines.append(
            f"{o.protocol} {o.kind} {100 * o.rate:g} % | {o.per(o.corrupted):.0f} | {o.per(o.lost_unseen):.0f} | "
            f"{o.per(o.twice):.0f} | {o.per(o.false_failures):.0f} | {o.per(o.true_failures):.0f} | "
            f"{o.faults} | {o.sim_seconds:.1f}"
        )
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description="commands through a faulty line, text against binary")
    parser.add_argument("--commands", type=int, default=5000, help="commands per scenario (default 5000)")
    parser.add_argument(
        "--waiting",
        type=int,
        default=WAITING,
        metavar="W",
        help=f"calls waiting for their replies at most (1..{codes.WINDOW}, default {WAITING})",
    )
    parser.add_argument("--quick", action="store_true", help="200 commands, 1 %% only: a smoke test")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args(argv)
    if args.commands < 1:
        parser.error("--commands must be at least 1")
    if not 1 <= args.waiting <= codes.WINDOW:
        parser.error(f"--waiting must be 1..{codes.WINDOW}, got {args.waiting}")
    start = time.monotonic()
    if args.quick:
        outcomes = run(200, rates=(0.01,), waiting=args.waiting)
    else:
        outcomes = run(args.commands, waiting=args.waiting)
    if args.json:
        print(json.dumps([asdict(o) for o in outcomes]))
    else:
        print(report(outcomes))
        print(f"({len(outcomes)} scenarios in {time.monotonic() - start:.0f} s wall)")
    bad = [o for o in outcomes if o.corrupted or o.lost_unseen or o.twice or o.false_failures]
    return 1 if bad else 0


if __name__ == "__main__":
    raise SystemExit(main())
