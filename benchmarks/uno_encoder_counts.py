"""The UNO's single-channel encoder counts against the simulated wheels', through reversals.

    python -m benchmarks.uno_encoder_counts [--robot omni4] [--runs 2]

The emulated UNO with the physics in the loop (``uno://ROBOT?world=empty``) drives VEL steps of
0.8 s, a VEL every 50 ms: +0.3 m/s along x, -0.3 along x, +0.3 along y, a turning translation
(0.2, -0.2 m/s, 0.4 rad/s) and its reverse, and a stop; closed loop (MODE 2) and open loop. Once the
simulated wheels are still, it prints the firmware's counts (TEL) less the simulated encoders'
(docs/uno.md, "Single-channel encoders"). Real time in simavr: about 10 s a run.
"""

from __future__ import annotations

import argparse

from omnibot.client import RobotClient, Telemetry
from omnibot.protocol import codes
from omnibot.robot import load_robot
from omnibot.uno import UnoLink, counts_at_rest, missing_tools

STEPS = (
    (0.3, 0.0, 0.0),
    (-0.3, 0.0, 0.0),
    (0.0, 0.3, 0.0),
    (0.2, -0.2, 0.4),
    (-0.2, 0.2, -0.4),
    (0.0, 0.0, 0.0),
)


def run(robot: str, closed_loop: bool) -> tuple[list[int], list[int]]:
    """One run: the simulated encoders' counts and the firmware's, both at rest."""
    samples: list[Telemetry] = []
    with RobotClient.open(f"uno://{robot}?world=empty&seed=1", load_robot(robot)) as client:
        link = client.link
        assert isinstance(link, UnoLink)
        sim = link.device.sim
        client.on_telemetry(samples.append)
        client.mode(closed_loop=closed_loop)
        client.telemetry(0.02, codes.TEL_ENCODERS)
        for vx, vy, w in STEPS:
            for _ in range(16):
                client.vel(vx, vy, w, 0.2)
                client.sleep(0.05)
        client.stop()
        counts, firmware = counts_at_rest(client, sim, samples)
        client.telemetry(0)
    if firmware is None:
        raise RuntimeError("no TEL with encoder counts came")
    return counts, firmware


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--robot", default="omni4", help="omni4 or mecanum4")
    ap.add_argument("--runs", type=int, default=2, help="runs of each loop (default 2)")
    args = ap.parse_args(argv)
    reason = missing_tools()
    if reason:
        print(f"skipped: {reason}")
        return 0
    print("| loop | simulated counts | firmware less simulated |\n|---|---|---|")
    for closed_loop in (True, False):
        for _ in range(args.runs):
            sim, firmware = run(args.robot, closed_loop)
            diff = [f - s for f, s in zip(firmware, sim, strict=True)]
            print(f"| {'closed' if closed_loop else 'open'} | {sim} | {diff} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
