"""goto as a runtime source on the lockstep simulator: a goal gone to cycle by cycle, a person's
twist taking over and handing back, a new goal pre-empting the old, bad goals refused.

The map is the room world rasterised; the estimator starts at the world's start, so the map frame
is the world's and the pose is the runtime's estimate (or the truth: a perfect localiser). Arrival is checked against the simulator's
truth.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from contextlib import contextmanager

import pytest

from omnibot.errors import BlockedError, OffMapError
from omnibot.mapping.score import world_grid
from omnibot.motion import Pose2D, Twist
from omnibot.navigation.goal import GotoResult
from omnibot.navigation.goto import navigation_runtime
from omnibot.navigation.goto_source import POSE_WAIT, GotoSource
from omnibot.navigation.session import simulated_client
from omnibot.robot import load_robot
from omnibot.runtime import Runtime, ScriptSource
from omnibot.sim import Simulator, load_world
from omnibot.transport import find_simulator

START = Pose2D(1.0, 1.0, 0.0)


@contextmanager
def bench(
    seed: int = 1, *, truth: bool = False
) -> Iterator[tuple[Runtime, GotoSource, Simulator, list[GotoResult]]]:
    robot = load_robot("omni4")
    grid = world_grid(load_world("room"))
    with (
        simulated_client(robot, world="room", start=START, seed=seed) as client,
        navigation_runtime(client, robot, START) as runtime,
    ):
        sim = find_simulator(client.link)
        assert sim is not None

        def pose() -> Pose2D | None:
            if truth:  # a perfect localiser
                return Pose2D(sim.pose.x, sim.pose.y, sim.pose.theta)
            est = runtime.estimate_now()
            return None if est is None else est.pose

        results: list[GotoResult] = []
        source = GotoSource(robot, grid, runtime.period, pose, on_result=results.append)
        runtime.add_source(source)
        yield runtime, source, sim, results


def state(source: GotoSource) -> str:
    """The source's state, read afresh (not narrowed by an earlier assertion)."""
    return source.state


def truth_error(sim: Simulator, goal: Pose2D) -> tuple[float, float]:
    p = sim.pose
    return math.hypot(p.x - goal.x, p.y - goal.y), abs(math.remainder(p.theta - goal.theta, math.tau))


def test_a_goal_is_gone_to_cycle_by_cycle_and_reached_by_the_truth() -> None:
    goal = Pose2D(2.8, 2.2, math.radians(90))
    with bench() as (runtime, source, sim, results):
        assert source.go(goal) is False
        runtime.run(until=lambda: not source.active, duration=60.0)
        assert [r.outcome for r in results] == ["arrived"], results[-1].summary() if results else "no result"
        d, dth = truth_error(sim, goal)
        assert d <= 0.05 and dth <= math.radians(5), (d, math.degrees(dth))
        assert results[0].plans and results[0].duration > 1.0
        assert len(sim.collisions) == 0


def test_a_person_takes_over_and_the_goto_plans_again_when_handed_back() -> None:
    goal = Pose2D(2.8, 2.4, 0.0)

    def person(t: float) -> Twist | str | None:
        if t < 1.0:
            return Twist(0.0, 0.3, 0.0)  # 30 cm to the left, off the first plan
        return ScriptSource.END

    # the pose from the truth, as a localiser gives it: across the carpet the wheels slip and the
    # odometry ends 9 to 12 cm off, which no goto can see without one
    with bench(seed=2, truth=True) as (runtime, source, sim, results):
        source.go(goal)
        runtime.run(until=lambda: sim.pose.x > 1.6, duration=30.0)  # on the way
        assert state(source) == "leg"
        plans = len(source.result.plans) if source.result else 0
        runtime.add_source(ScriptSource(person, name="person", priority=90))
        runtime.run(until=lambda: state(source) == "standby", duration=2.0)
        assert state(source) == "standby"
        runtime.run(until=lambda: not source.active, duration=60.0)
        assert [r.outcome for r in results] == ["arrived"], results[-1].summary()
        assert len(results[0].plans) > plans  # planned again from where the person left it
        d, dth = truth_error(sim, goal)
        assert d <= 0.05 and dth <= math.radians(5), (d, math.degrees(dth))


def test_a_new_goal_pre_empts_the_old_one() -> None:
    first, second = Pose2D(3.0, 2.6, 0.5), Pose2D(1.5, 2.2, math.radians(-90))
    # the pose from the truth (see above)
    with bench(seed=3, truth=True) as (runtime, source, sim, results):
        source.go(first)
        runtime.run(until=lambda: sim.pose.x > 1.5, duration=30.0)
        assert source.go(second) is True
        assert [(r.outcome, r.reason) for r in results] == [("cancelled", "pre-empted by a new goal")]
        runtime.run(until=lambda: not source.active, duration=60.0)
        assert [r.outcome for r in results] == ["cancelled", "arrived"], results[-1].summary()
        d, dth = truth_error(sim, second)
        assert d <= 0.05 and dth <= math.radians(5), (d, math.degrees(dth))


def test_bad_goals_are_refused_and_change_nothing() -> None:
    with bench() as (_runtime, source, _sim, results):
        with pytest.raises(BlockedError, match="is inside a wall or obstacle"):
            source.go(Pose2D(3.6, 1.2, 0.0))  # the cabinet
        with pytest.raises(OffMapError, match="is off the map"):
            source.go(Pose2D(30.0, 1.0, 0.0))
        assert not source.active and results == []
        assert source.cancel("nothing to cancel") is False


def test_a_goal_without_a_pose_of_the_robot_fails_saying_so() -> None:
    with bench() as (runtime, source, _sim, _results):
        runtime.remove_source(source.name)
        results: list[GotoResult] = []
        blind = GotoSource(source.robot, source.grid, runtime.period, lambda: None, on_result=results.append)
        runtime.add_source(blind)
        blind.go(Pose2D(2.8, 2.2, 0.0))
        runtime.run(until=lambda: not blind.active, duration=POSE_WAIT + 2.0)
        assert [(r.outcome, r.reason) for r in results] == [
            ("stopped", f"no pose of the robot in the map after {POSE_WAIT:.0f} s")
        ]
