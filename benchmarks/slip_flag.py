"""The estimator's wheel-slip flag against the simulator's truth: detection and false alarms.

Run: ``python -m benchmarks.slip_flag`` (``--help`` for options). Each run is the real stack in
lockstep (runtime at 100 Hz, wheel-speed loop, binary TEL every 10 ms, fixed seed); every TEL sample
is recorded with the simulator's true per-wheel slip speed (contact speed minus rim speed along the
wheel's traction direction, :attr:`omnibot.sim.physics.Physics.slip`), and the flags are then replayed
on the recorded telemetry, so every flag sees the same samples.

Robots: the presets with more wheels than the three planar motions (omni4, mecanum4: a fit
residual), wood and carpet. Drives:

* ``lemniscate``: the standard lemniscate facing its tangent at the robot's top speed (the tracker);
* ``steps``: hard steps of the twist at the top speed (forward, sideways, diagonal, back, a turn),
  0.6 s each with 0.4 s stops between them: the hardest accelerations the firmware's loop gives;
* ``pinned``: forward into the corridor's end wall, the wheels spinning against it for 2 s.

Each drive runs twice: with the preset as described (clean: every flag is a false alarm unless the
truth says a wheel slipped) and with one wheel's rollers at ``--grip`` of their grip (a worn or
wet wheel: one wheel slipping). A wheel *slips* on a sample when its true slip speed, less the part
a rigid motion of the body explains (what no estimator can see from its wheels), exceeds
:data:`SLIP_SPEED`; an *episode* is such samples with gaps under 0.1 s. Reported per robot, floor
and drive: the slip episodes found by each flag (a flag within the episode or 0.1 s after) and the
median delay from its start, and the false alarms: the share of quiet samples flagged (no wheel
slipping by more than :data:`QUIET` in any way, rigid or not, for 0.1 s around and for as long
before as the flag may be held). The flags: ``before`` (the rule before 2026-12-07: one interval's
largest residual over 3 counts), ``residual`` (:mod:`omnibot.estimation.wheelslip`) and
``estimate`` (the ``fused`` estimate's ``slipping``: that, or the heading filter's, whose gyro
check also sees a slip that turns the body rigidly).
"""

from __future__ import annotations

import argparse
import math
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field
from typing import Any

import numpy as np

SLIP_SPEED = 0.03
"""m/s of a wheel's non-rigid true slip above which it counts as slipping (the carpet's creep at a
hard start is under 0.01 m/s of it)."""
QUIET = 0.01
"""m/s of non-rigid true slip under which no wheel slips (a flag then is a false alarm)."""
EPISODE_GAP = 0.1
"""s: slipping samples closer than this are one episode; a flag this late still finds it."""
ROBOTS = ("omni4", "mecanum4")
SURFACES = ("wood", "carpet")
DRIVES = ("lemniscate", "steps", "pinned")


@dataclass
class Record:
    """One run's telemetry and truth, sample by sample."""

    samples: list[Any] = field(default_factory=list)
    slip: list[np.ndarray] = field(default_factory=list)
    """True per-wheel slip speed (m/s) at each sample."""


def slippery(preset: str, wheel: int, grip: float) -> Any:
    """The preset with wheel ``wheel``'s rollers at ``grip`` of their grip."""
    from omnibot.robot import load_robot, parse_description

    robot = load_robot(preset)
    data = robot.model_dump(exclude_none=True)
    rollers = data["wheels"][wheel].setdefault("rollers", {})
    rollers["grip"] = rollers.get("grip", 1.0) * grip
    return parse_description(data, f"{preset} (wheel {wheel} at {grip:g} grip)")


def _steps(top: float, turn: float) -> Callable[[float], Any]:
    from omnibot.motion import Twist
    from omnibot.runtime import ScriptSource

    d = top / math.sqrt(2.0)
    moves = [(top, 0, 0), (0, top, 0), (d, d, 0), (-top, 0, 0), (0, 0, turn), (0, -top, 0)]

    def script(t: float) -> Any:
        k, phase = divmod(t - 1.0, 1.0)
        if k >= len(moves):
            return ScriptSource.END
        return Twist(*moves[int(k)]) if t >= 1.0 and phase < 0.6 else Twist(0.0, 0.0, 0.0)

    return script


def record(job: tuple[str, str, str, float, int]) -> Record:
    """Drive ``preset`` on ``surface`` (``drive``), its wheel 1 at ``grip`` (1: as described)."""
    from omnibot.client import RobotClient
    from omnibot.control import standard_path
    from omnibot.estimation import make_estimator
    from omnibot.motion import Pose2D, Twist
    from omnibot.navigation import follower_source
    from omnibot.navigation.session import follower_limits
    from omnibot.protocol import codes
    from omnibot.robot import load_robot
    from omnibot.runtime import Runtime, ScriptSource
    from omnibot.sim import SimDevice
    from omnibot.transport import LockstepLink

    preset, surface, drive, grip, seed = job
    robot = load_robot(preset)
    true_robot = slippery(preset, 1, grip) if grip != 1.0 else None
    path = standard_path("lemniscate", size=1.0, heading="tangent")
    start = Pose2D(*path.start) if drive == "lemniscate" else Pose2D(8.0, 0.0, 0.0)
    world = "corridor" if drive == "pinned" else "empty"
    device = SimDevice(
        robot,
        true_robot=true_robot,
        surface=surface,
        world=world,
        seed=seed,
        start_pose=(start.x, start.y, start.theta),
    )
    client = RobotClient(LockstepLink(device, url=f"sim://{preset}?seed={seed}"), robot)
    out = Record()
    physics: Any = device.sim.physics  # the simulator's own Physics: it has the true slip

    def hook(event: Any) -> None:
        out.samples.append(event)
        out.slip.append(np.array(physics.slip[0], dtype=float))

    with client:
        client.sleep(0.05)
        runtime = Runtime(client, period=0.01, estimator=make_estimator("fused", robot, start))
        runtime.telemetry_hooks.append(hook)
        limits = follower_limits(robot)
        source: Any
        if drive == "lemniscate":
            source = follower_source(robot, path, 0.01)
        elif drive == "steps":
            source = ScriptSource(_steps(limits.v_max, limits.w_max))
        else:
            source = ScriptSource(lambda t: Twist(0.5, 0.0, 0.0) if t < 6.0 else ScriptSource.END)
        runtime.add_source(source)
        client.use_binary()
        client.telemetry(0.01, codes.TEL_MASK)
        runtime.run(duration=1.0)
        runtime.run(until=lambda: source.finished, duration=40.0)
        runtime.close()
    return out


def nonrigid_slip(robot: Any, slip: np.ndarray) -> np.ndarray:
    """m/s per sample: the true slip no rigid motion explains, as one wheel's rim slip (the largest
    studentised residual of the true slip speeds)."""
    from omnibot.estimation import WheelSlipCheck

    rim = np.array([w.radius * math.cos(w.gamma) for w in robot.wheels])
    check = WheelSlipCheck(robot.wheel_matrix, np.zeros(robot.n_wheels), window=0.0)
    out: np.ndarray = np.abs(check.student @ (slip / rim).T).max(axis=0) * float(rim.max())
    return out


def old_rule(robot: Any, angles: np.ndarray) -> bool:
    """The flag before 2026-12-07: one interval's largest fit residual over 3 counts."""
    J = np.asarray(robot.wheel_matrix, dtype=float)
    residual = angles - J @ (np.linalg.pinv(J) @ angles)
    per_count = max(2.0 * math.pi / e.counts_per_rev for e in robot.encoders.motors)
    return bool(np.abs(residual).max() > 3.0 * per_count)


def replay_flags(preset: str, rec: Record) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """Sample times and each flag on the recorded telemetry: ``before`` (:func:`old_rule`),
    ``residual`` (:class:`~omnibot.estimation.wheelslip.WheelSlipCheck` in the ``fused`` estimator)
    and ``estimate`` (its ``slipping``: the residual or the heading filter's gyro check)."""
    from omnibot.estimation import PoseEstimator, make_estimator
    from omnibot.estimation.odometry import count_delta
    from omnibot.robot import load_robot

    robot = load_robot(preset)
    est = make_estimator("fused", robot)
    assert isinstance(est, PoseEstimator)
    per_count = np.array([2.0 * math.pi / e.counts_per_rev for e in robot.encoders.motors])
    flags: dict[str, list[bool]] = {"before": [], "residual": [], "estimate": []}
    last = None
    for sample in rec.samples:
        e = est.update(sample)
        if last is not None:
            d = count_delta(np.asarray(sample.encoders, float), np.asarray(last.encoders, float))
            flags["before"].append(old_rule(robot, d * per_count))
            flags["residual"].append(est.wheel_slip.slipping)
            flags["estimate"].append(e.slipping)
        last = sample
    t = np.array([s.controller_time for s in rec.samples[1:]])
    return t, {k: np.array(v) for k, v in flags.items()}


def _episodes(t: np.ndarray, on: np.ndarray) -> list[tuple[float, float]]:
    """(start, end) of the runs of ``on`` with gaps under :data:`EPISODE_GAP`."""
    out: list[tuple[float, float]] = []
    for ti in t[on]:
        if out and ti - out[-1][1] < EPISODE_GAP:
            out[-1] = (out[-1][0], ti)
        else:
            out.append((ti, ti))
    return out


@dataclass(frozen=True)
class Score:
    """One flag on one run: slip episodes, those found, their median delay (s), the share of quiet
    samples flagged and the share of all samples flagged."""

    episodes: int
    found: int
    delay: float
    false_alarms: float
    flagged: float


def score(t: np.ndarray, flag: np.ndarray, truth: np.ndarray, moving: np.ndarray, hold: float) -> Score:
    """``flag`` against the true non-rigid slip ``truth`` and the largest true slip of any kind
    ``moving`` (m/s per sample); ``hold`` s a flag may outlast a slip."""
    episodes = _episodes(t, truth > SLIP_SPEED)
    delays = []
    for a, b in episodes:
        hit = (t >= a) & (t <= b + EPISODE_GAP) & flag
        if hit.any():
            delays.append(float(t[hit][0] - a))
    busy = np.zeros(len(t), dtype=bool)
    for ti in t[np.maximum(truth, moving) > QUIET]:
        busy |= (t >= ti - EPISODE_GAP) & (t <= ti + EPISODE_GAP + hold)
    quiet = ~busy
    false = float((flag & quiet).sum() / max(1, quiet.sum()))
    median = float(np.median(delays)) if delays else math.nan
    return Score(len(episodes), len(delays), median, false, float(flag.mean()))


def evaluate(job: tuple[str, str, str, float, int]) -> dict[str, Any]:
    """Record one run and score every flag on it."""
    from omnibot.estimation.wheelslip import WINDOW
    from omnibot.robot import load_robot

    rec = record(job)
    t, flags = replay_flags(job[0], rec)
    slip = np.array(rec.slip[1:])
    truth, moving = nonrigid_slip(load_robot(job[0]), slip), np.abs(slip).max(axis=1)
    holds = {"before": 0.0, "residual": WINDOW, "estimate": 0.4}
    return {"job": job, "scores": {k: score(t, f, truth, moving, holds[k]) for k, f in flags.items()}}


def _cell(s: Score) -> str:
    delay = "-" if math.isnan(s.delay) else f"{1000 * s.delay:.0f} ms"
    return f"{s.found}/{s.episodes}, {delay}, {100 * s.false_alarms:.1f} %"


def main(argv: Sequence[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--robots", default=",".join(ROBOTS))
    parser.add_argument("--surfaces", default=",".join(SURFACES))
    parser.add_argument("--drives", default=",".join(DRIVES))
    parser.add_argument("--grip", type=float, default=0.2, help="the slippery wheel's grip (default 0.2)")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--jobs", type=int, default=2)
    args = parser.parse_args(argv)
    jobs = [
        (robot, surface, drive, grip, args.seed)
        for robot in args.robots.split(",")
        for surface in args.surfaces.split(",")
        for drive in args.drives.split(",")
        for grip in (1.0, args.grip)
    ]
    with ProcessPoolExecutor(args.jobs) as pool:
        results = list(pool.map(evaluate, jobs))
    print("found/episodes, median delay, quiet samples flagged; per flag (before: 3 counts on one")
    print("interval's residual; residual: studentised, windowed; estimate: residual or gyro)\n")
    print("| robot | floor | drive | wheel 1 grip | before | residual | estimate |")
    print("|---|---|---|---|---|---|---|")
    for r in results:
        robot, surface, drive, grip, _ = r["job"]
        cells = " | ".join(_cell(r["scores"][k]) for k in ("before", "residual", "estimate"))
        print(f"| {robot} | {surface} | {drive} | {grip:g} | {cells} |")
    for key in ("before", "residual", "estimate"):
        found = sum(r["scores"][key].found for r in results)
        total = sum(r["scores"][key].episodes for r in results)
        worst = max(r["scores"][key].false_alarms for r in results)
        print(f"\n{key}: {found}/{total} episodes found, worst quiet share flagged {100 * worst:.1f} %")


if __name__ == "__main__":
    main()
