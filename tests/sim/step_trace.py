"""A seeded trace of everything the simulator computes per step, for checking that a faster step
gives the same numbers bit for bit.

``python -m tests.sim.step_trace --write`` records it into ``tests/sim/data/step_trace.json`` (done
once with the simulator before its step was compiled whole: the reference); ``test_step_trace.py``
runs the same scenes and compares every float by its bits. The scenes cover what the step does:
contacts with walls and furniture (one robot pushing into the cabinet, hand pushes and applied
forces), surface patches, encoders, tracking wheels, the gyro, sonar pings, a scanner revolution,
and a fleet whose robots bump into each other and see each other with their sonars and scanners.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import struct
from pathlib import Path
from typing import Any

from omnibot.floor import Surface, get_surface
from omnibot.motion import Pose2D
from omnibot.robot import RobotDescription, load_robot
from omnibot.sim.fleet import Fleet
from omnibot.sim.physics import Physics
from omnibot.sim.simulator import Simulator
from omnibot.sim.truth import CollisionEvent
from omnibot.sim.world import load_world

GOLDEN = Path(__file__).with_name("data") / "step_trace.json"
RECORDED_CARPET = Surface("carpet", mu=0.60, slip_velocity=0.04, rolling_multiplier=4.0)
"""The carpet the trace was recorded on (4x wood's roller resistance, before carpet was fitted to seed
000's "up to 20 %"): the trace checks the step's arithmetic, not the floor's numbers."""


def as_recorded(robot: RobotDescription, *, n: int, surfaces: list[str], dt: float, seed: int) -> Physics:
    """The simulator's physics (a :data:`~omnibot.sim.physics_like.PhysicsFactory`; the physics has no
    randomness, so no seed) on the floors as the trace was recorded (:data:`RECORDED_CARPET`)."""
    floors = [RECORDED_CARPET if get_surface(s).name == "carpet" else get_surface(s) for s in surfaces]
    return Physics(robot, n=n, surfaces=floors, dt=dt)


def _bits(values: Any) -> list[str]:
    """Floats as hex strings of their bits (ints and None as they are)."""
    out = []
    for v in values:
        if v is None or isinstance(v, int):
            out.append(str(v))
        else:
            out.append(struct.pack("<d", float(v)).hex())
    return out


def _event(e: CollisionEvent) -> list[str]:
    return [*_bits([e.time, e.x, e.y, *e.normal, e.depth, e.speed]), e.owner]


def single_robot() -> dict[str, Any]:
    """omni4 in the room: drives into the cabinet, is pushed, crosses the carpet; every sensor."""
    sim = Simulator(
        load_robot("omni4"), world="room", seed=7, start_pose=(1.5, 3.4, 0.3), physics_factory=as_recorded
    )
    scans: list[str] = []
    sim.add_scan_listener(lambda scan: scans.append(hashlib.sha256(scan.ranges.tobytes()).hexdigest()))
    rows: list[list[str]] = []
    patterns = [[150, -40, -150, 40], [-120, -120, -120, -120], [-150, 40, 150, -40], [200, 60, -200, -60]]
    for k in range(4000):
        if k % 700 == 0:
            sim.set_pwm(patterns[(k // 700) % len(patterns)])
        if k == 1500:
            sim.push((3.0, -2.0), 0.1, duration=0.05, motors_off=False)
        if 2000 <= k < 2100:
            sim.apply_force(1.5, 0.5, -0.05)
        sim.step()
        if k % 20 == 0:
            sonars = [sim.sonar_ping(i) for i in range(len(sim.sonars))]
            rows.append(
                _bits([*sim.pose_array, *sim._twist_row, *sim.wheel_speeds, sim.gyro_rate(), *sonars])
                + [str(c) for c in sim.encoder_counts()]
                + sim.wheel_surfaces
            )
    events = [_event(e) for e in sim.collisions]
    return {"rows": rows, "events": events, "scans": scans}


def tracking_robot() -> dict[str, Any]:
    """omni3 (tracking wheels, gyro) in the house."""
    sim = Simulator(load_robot("omni3"), world="house", seed=3, physics_factory=as_recorded)
    sim.set_pwm([120, -60, -60])
    rows = []
    for k in range(1500):
        sim.step()
        if k % 25 == 0:
            rows.append(_bits([*sim.pose_array, sim.gyro_rate()]) + [str(c) for c in sim.tracking_counts()])
    return {"rows": rows}


def fleet() -> dict[str, Any]:
    """Three robots in the room driving into each other, with sonars and scanners."""
    fl = Fleet(load_world("room"))
    # the firmware's powers as they were recorded: rounded once (its dithering came later, and this
    # trace checks the simulator's step, not the firmware)
    rounded = {"pwm_dither": False}
    a = fl.add("a", "omni4", seed=1, pose=Pose2D(1.0, 1.0, 0.0), firmware_overrides=rounded)
    b = fl.add("b", "omni4", seed=2, pose=Pose2D(1.6, 1.05, 3.0), firmware_overrides=rounded)
    c = fl.add("c", "mecanum4", seed=3, pose=Pose2D(1.3, 1.7, -1.5), firmware_overrides=rounded)
    scans: list[str] = []
    b.sim.add_scan_listener(lambda scan: scans.append(hashlib.sha256(scan.ranges.tobytes()).hexdigest()))
    a.command("MOVE,100,40,0,0;")
    b.command("MOVE,100,40,0,0;")
    c.command("MOVE,80,30,0,0;")
    rows = []
    for k in range(2500):
        fl.step()
        if k % 25 == 0:
            for dev in (a, b, c):
                s = dev.sim
                sonars = [s.sonar_ping(i) for i in range(len(s.sonars))]
                rows.append(_bits([*s.pose_array, *s._twist_row, *sonars]))
    events = [_event(e) for dev in (a, b, c) for e in dev.sim.collisions]
    out = b"".join(dev.transmit() for dev in (a, b, c))
    return {"rows": rows, "events": events, "scans": scans, "bytes": hashlib.sha256(out).hexdigest()}


SCENES = {"single_robot": single_robot, "tracking_robot": tracking_robot, "fleet": fleet}


def assert_as_recorded(scene: str) -> None:
    """Run ``scene`` and compare everything it gives with the recorded trace, float by float."""
    expected = json.loads(GOLDEN.read_text(encoding="utf-8"))[scene]
    got = json.loads(json.dumps(SCENES[scene]()))
    for key, rows in expected.items():
        if isinstance(rows, list):
            assert len(got[key]) == len(rows), key
            for k, (row, want) in enumerate(zip(got[key], rows, strict=True)):
                assert row == want, f"{scene} {key}[{k}]"
        else:
            assert got[key] == rows, key


def main(argv: list[str] | None = None) -> int:
    """Print the trace's digest, or write it as the reference with ``--write``."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--write", action="store_true", help=f"record the reference into {GOLDEN}")
    args = parser.parse_args(argv)
    trace = {name: scene() for name, scene in SCENES.items()}
    text = json.dumps(trace, indent=0, sort_keys=True)
    if args.write:
        GOLDEN.write_text(text + "\n", encoding="utf-8")
    print(hashlib.sha256(text.encode()).hexdigest())
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
