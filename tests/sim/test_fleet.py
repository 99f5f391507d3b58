"""Several robots in one world on one clock (sim://PRESET?fleet=NAME&name=R&pose=X,Y,THETA): they
collide as bodies, their sonars see each other, and a fleet driven by one runtime per robot, each in
its own thread, runs in lockstep and deterministically."""

from __future__ import annotations

import contextlib
import itertools
import math
import threading
from collections.abc import Iterator

import numpy as np
import pytest

from omnibot.client import RobotClient
from omnibot.errors import ConfigError
from omnibot.motion import Pose2D, Twist
from omnibot.runtime import Cycle, Runtime, ScriptSource
from omnibot.sim.fleet import Fleet
from omnibot.sim.fleet_link import FleetLink, open_fleets
from omnibot.sim.world import load_world
from omnibot.transport import open_link

from .linkio import read_until

HALF = 0.10
"""Half the side of omni4's square footprint, m."""
_keys = itertools.count()


@pytest.fixture
def fleet() -> Iterator[str]:
    """A fresh fleet name; every link of it must be closed by the end of the test."""
    key = f"test{next(_keys)}"
    yield key
    assert key not in open_fleets()


def link_of(url: str) -> FleetLink:
    link = open_link(url)
    assert isinstance(link, FleetLink)
    return link


def test_two_robots_driving_into_each_other_stop_at_contact(fleet: str) -> None:
    a = link_of(f"sim://omni4?fleet={fleet}&name=a&pose=0,0,0&seed=1")
    b = link_of(f"sim://omni4?fleet={fleet}&name=b&pose=0.6,0,180&seed=2")
    with a, b:
        sa, sb = a.device.sim, b.device.sim
        a.write(b"MOVE,100,40,0,0;")  # 1 m ahead at 0.4 m/s: head on, 0.4 m apart
        b.write(b"MOVE,100,40,0,0;")
        gaps = []
        while a.clock.now() < 3.0:
            a.clock.sleep(0.005)  # one robot's client moves time for both
            gaps.append((sb.pose.x - HALF) - (sa.pose.x + HALF))
        assert a.clock.now() == b.clock.now() == sa.time == sb.time
        assert max(gaps) == pytest.approx(0.4, abs=1e-3) and min(gaps) > -0.002  # at most 2 mm sunk in
        assert abs(gaps[-1]) < 0.001  # pressed together, not bounced apart
        assert sa.pose.x == pytest.approx(0.2, abs=0.005) and sb.pose.x == pytest.approx(0.4, abs=0.005)
        assert abs(sa.pose.y) < 0.01 and abs(sb.pose.y) < 0.01
        assert abs(sa.twist.vx) < 0.01 and abs(sb.twist.vx) < 0.01
        (hit_a,) = sa.collisions
        (hit_b,) = sb.collisions
        assert (hit_a.owner, hit_b.owner) == ("robot b", "robot a")
        assert hit_a.normal[0] == pytest.approx(-1.0) and hit_b.normal[0] == pytest.approx(1.0)
        assert hit_a.speed == pytest.approx(0.8, abs=0.1)  # closing at twice the robots' speed
        # b's client never read: its firmware ran all the same, its replies wait on its line; each
        # MOVE stopped 0.2 m into its 1 m, and the encoders say so once the wheels stand (WARN 17)
        short = b"WARN,17,MOVE fell short of its distance (encoders)\r\n"
        assert read_until(a, short) == read_until(b, short) == b"HELLO,2,omni4,4\r\nOK\r\nIDLE\r\n" + short


def test_a_sonar_sees_the_other_robot_at_its_range(fleet: str) -> None:
    a = link_of(f"sim://omni4?fleet={fleet}&name=a&pose=0,0,0&seed=3")
    b = link_of(f"sim://omni3?fleet={fleet}&name=b&pose=1.6,0.05,30&seed=4")
    with a:
        with b:
            a.write(b"SONAR,1,100,1,500,0;")  # RANGE every 100 ms while something is within 5 m
            out = read_until(a, b"RANGE,1", timeout=1.0) + read_until(a, b"\r\n", timeout=0.1)
            # omni3's footprint is a circle of radius 0.32 m; a's sonar sits on its front face
            expected = math.hypot(1.6 - HALF, 0.05) - 0.32
            cm = int(out.split(b"RANGE,1,")[1].split(b"\r\n")[0])
            assert cm == pytest.approx(expected * 100, abs=2)
            assert a.device.sim.sonar_ping(0) == pytest.approx(expected, abs=0.02)
        a.clock.sleep(0.2)  # b's link closed: b has left the room, a's sonar sees nothing
        assert a.device.sim.sonar_ping(0) is None


def test_robots_are_stepped_together_while_only_one_client_reads(fleet: str) -> None:
    with (
        link_of(f"sim://omni4?fleet={fleet}&name=a&world=room&pose=1,1,0") as a,
        link_of(f"sim://omni3?fleet={fleet}&name=c&pose=2,2,90&seed=5") as c,  # takes the fleet's room
    ):
        assert c.device.sim.world is a.device.sim.world
        c.write(b"MOVE,30,30,0,0;")
        a.clock.sleep(2.0)
        assert c.clock.now() == pytest.approx(2.0, abs=0.002)
        assert 0.2 < c.device.sim.pose.y - 2.0 < 0.4  # its MOVE (30 cm, open loop) ran to the end
        assert c.device.sim.pose.x == pytest.approx(2.0, abs=0.05)


def drive_fleet(fleet: str) -> tuple[list[tuple[float, ...]], ...]:
    """Two robots, each driven by its own runtime in its own thread, heading past each other and
    swerving on contact; a third whose client never reads, turning on the spot. Every cycle's truth."""
    urls = [
        f"sim://omni4?fleet={fleet}&name=r1&pose=0,0,0&seed=1",
        f"sim://omni4?fleet={fleet}&name=r2&pose=1,0.1,180&seed=2",
        f"sim://omni3?fleet={fleet}&name=r3&pose=0.5,1,0&seed=3",
    ]
    clients = [RobotClient.open(url, timeout=0.5) for url in urls[:2]]  # opened (HELLO) in this thread
    idle = link_of(urls[2])  # nobody reads it
    traces: list[list[tuple[float, ...]]] = [[], []]
    errors: list[BaseException] = []
    try:
        idle.write(b"ROTATE,180,90;")

        def run(k: int) -> None:
            sim = clients[k].link.device.sim  # type: ignore[attr-defined]

            def record(cycle: Cycle) -> None:
                p = sim.pose
                traces[k].append((cycle.now, p.x, p.y, p.theta))

            twist = Twist(0.35, 0.05 * (1 - 2 * k), 0.2)
            script = ScriptSource(lambda t: twist if t < 2.0 else ScriptSource.END)
            runtime = Runtime(clients[k], period=0.01, sources=[script], sinks=[record])
            try:
                runtime.run(until=lambda: script.finished)
                runtime.close()
            except BaseException as exc:
                errors.append(exc)

        threads = [threading.Thread(target=run, args=(k,)) for k in (0, 1)]
        for thread in threads:
            thread.start()
        for thread in threads:
            thread.join(120)
        assert not errors, errors
        r3 = idle.device.sim
        traces.append([(r3.time, r3.pose.x, r3.pose.y, r3.pose.theta)])
    finally:
        for client in clients:
            client.close()
        idle.close()
    return tuple(traces)


def test_a_fleet_run_with_a_runtime_per_robot_thread_is_deterministic() -> None:
    first = drive_fleet(f"det{next(_keys)}")
    second = drive_fleet(f"det{next(_keys)}")
    assert first == second
    r1, r2, r3 = first
    assert 195 <= len(r1) <= 205 and len(r1) == len(r2)
    assert [t for t, *_ in r1] == [t for t, *_ in r2]  # one clock: their cycles fall on the same times
    assert r1[-1][1] - r1[0][1] > 0.3 and r2[0][1] - r2[-1][1] > 0.3  # both drove
    assert min(math.hypot(p[1] - q[1], p[2] - q[2]) for p, q in zip(r1, r2, strict=True)) > 2 * HALF - 0.005
    (end,) = r3
    assert end[3] == pytest.approx(math.pi, abs=0.3)  # turned by its own firmware, never read


@pytest.mark.parametrize(
    ("second", "message"),
    [
        ("sim://omni4?fleet={f}&name=a&pose=2,2,0", "fleet already has a robot named 'a'"),
        ("sim://omni4?fleet={f}&name=b&pose=1.15,1,45", "robot 'b' at .* overlaps robot 'a'"),
        ("sim://omni3?fleet={f}&name=b", "overlaps robot 'a'; give each robot its own pose"),
        ("sim://omni4?fleet={f}&name=b&pose=0.05,2,0", r"robot 'b': start pose .* overlaps walls\[0\]"),
        ("sim://omni4?fleet={f}&name=b&world=corridor&pose=3,1,0", "fleet '.*' is in world 'room'"),
        ("sim://omni4?fleet={f}&name=b&surface=carpet&pose=3,1,0", "has a wood floor.*asks for surface"),
        ("sim://omni4?fleet={f}&pose=3,1", r"expected pose=X,Y,THETA \(m, m, degrees\), got '3,1'"),
        ("sim://omni4?name=b&pose=3,1,0", "name= names a robot of a fleet: add fleet=NAME"),
        ("sim://omni4?fleet=&name=b", "fleet= needs a name"),
        ("sim://omni4?fleet={f}&nmae=b", "did you mean 'name'"),
    ],
)
def test_url_errors(fleet: str, second: str, message: str) -> None:
    with link_of(f"sim://omni4?fleet={fleet}&name=a&world=room&pose=1,1,0") as a:
        with pytest.raises(ConfigError, match=message):
            open_link(second.format(f=fleet))
        assert open_fleets()[fleet].fleet.names == ["a"]  # nothing half-added
        assert a.fleet.names == ["a"]


def test_a_pose_in_a_wall_of_a_new_fleet_leaves_no_fleet_behind(fleet: str) -> None:
    with pytest.raises(ConfigError, match=r"start pose .* overlaps walls\[0\]"):
        open_link(f"sim://omni4?fleet={fleet}&world=room&pose=0,0,0")
    with pytest.raises(ConfigError, match=r"overlaps walls\[0\].*pose=0,0,0"):
        open_link("sim://omni4?world=room&pose=0,0,0")  # a lone robot takes pose= too
    with open_link("sim://omni4?world=room&pose=2,2,90") as lone:
        assert lone.device.sim.pose.theta == pytest.approx(math.pi / 2)  # type: ignore[attr-defined]


def test_names_are_given_in_order_and_freed_on_close(fleet: str) -> None:
    with link_of(f"sim://omni4?fleet={fleet}") as r1, link_of(f"sim://omni4?fleet={fleet}&pose=1,0,0") as r2:
        assert (r1.name, r2.name) == ("r1", "r2")
    with link_of(f"sim://omni4?fleet={fleet}&world=corridor&pose=1,0,0") as again:  # a new fleet
        assert again.name == "r1" and again.device.sim.world.name == "corridor"


def test_a_driver_that_stops_waiting_is_let_go_and_time_moves_on(
    fleet: str, caplog: pytest.LogCaptureFixture
) -> None:
    a = link_of(f"sim://omni4?fleet={fleet}&name=a&pose=0,0,0")
    b = link_of(f"sim://omni4?fleet={fleet}&name=b&pose=1,0,0")
    with a, b:
        b.read(timeout=0.01)  # this thread drives b, then turns to other work (the join below)
        a.shared.grace = 0.2
        b.write(b"MOVE,30,30,0,0;")
        thread = threading.Thread(target=a.clock.sleep, args=(2.0,), name="driver-of-a")
        thread.start()
        thread.join(60)
        assert not thread.is_alive() and a.clock.now() > 2.0
        assert "thread 'MainThread' has not waited on robot 'b'" in caplog.text
        assert b.device.sim.pose.x == pytest.approx(1.3, abs=0.05)  # b's firmware ran meanwhile
        assert b.driver is None and a.driver is not None
        b.clock.sleep(0.01)  # it drives b again when it waits again
        assert b.driver is threading.current_thread()


def test_the_contact_sweep_finds_every_pair_whose_bounding_circles_meet() -> None:
    """Sweep and prune along x gives the pairs a test of every pair gives, in step order."""
    fleet = Fleet(load_world("empty"))
    rng = np.random.default_rng(8)
    while len(fleet) < 14:
        x, y, th = rng.uniform(-1.2, 1.2), rng.uniform(-0.8, 0.8), rng.uniform(-3, 3)
        with contextlib.suppress(ConfigError):  # overlaps one already there
            fleet.add(
                f"r{len(fleet):02d}", "omni3" if len(fleet) % 3 == 0 else "omni4", pose=Pose2D(x, y, th)
            )
    bodies = fleet._order

    def every_pair() -> list[tuple[int, int]]:
        return [
            (i, j)
            for i, j in itertools.combinations(range(len(bodies)), 2)
            if math.dist(bodies[i].pose_row[:2], bodies[j].pose_row[:2]) < bodies[i].reach + bodies[j].reach
        ]

    before = every_pair()
    assert fleet._near_pairs() == before and len(before) >= 3
    for body in bodies[::2]:
        body.sim.physics.pose[0, :2] += 0.3  # some robots moved (not stepped: only the sweep is tested)
    assert fleet._near_pairs() == every_pair() != before
