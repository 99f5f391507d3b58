"""The real page in Debian's chromium: load, drive with the keyboard, emergency stop, bad messages.

Each test drives the simulated robot (``sim://omni4`` in the room world, paced to the wall clock by
the link thread) and checks what the robot did on the simulator's ground truth, as streamed in the
state frames (``dashboard.hub.latest``), and what the page shows. A key or the stick is held until
the robot has gone far enough (not for a wall-clock time: on a loaded machine the simulation gets
less of a wall-clock second), and every wait is for a condition, with a generous deadline.
"""

from __future__ import annotations

import math
import os
import time
from pathlib import Path
from typing import Any

from playwright.sync_api import Browser, Page, expect

from omnibot.web.dashboard import Dashboard
from tests.web.conftest import ROOM

DOCS = Path(__file__).resolve().parents[2] / "docs"


def latest(dashboard: Dashboard) -> dict[str, Any]:
    state = dashboard.hub.latest
    assert state is not None
    return state


def pose(dashboard: Dashboard) -> list[float]:
    p = latest(dashboard)["pose"]
    assert p is not None
    return list(p)


def wait_for(predicate: Any, timeout: float = 30.0, what: str = "condition") -> None:
    end = time.monotonic() + timeout
    while not predicate():
        assert time.monotonic() < end, f"timed out waiting for {what}"
        time.sleep(0.02)


def sim_time(dashboard: Dashboard) -> float:
    """The link clock of the latest state frame: the simulator's time."""
    return float(latest(dashboard)["t"])


def moving(dashboard: Dashboard) -> bool:
    speeds: list[float] = latest(dashboard)["wheel_speeds"] or [0.0]
    return max(abs(v) for v in speeds) > 0.5


def test_page_loads_with_map_robot_and_live_state(page: Page, dashboard: Dashboard) -> None:
    expect(page).to_have_title("omnibot dashboard")
    expect(page.locator("#robot-name")).to_have_text("omni4")
    expect(page.locator("#link")).to_contain_text("link ok: sim://omni4")
    expect(page.locator("#pose")).to_contain_text("x 1.00 m, y 1.00 m")  # the room's start pose
    expect(page.locator("#ranges")).to_contain_text("front: ")
    scene = page.evaluate("window.omnibot.state() && true")
    assert scene
    assert page.locator("[data-teach]").first.is_disabled()  # teach and repeat: a hook for now
    # the live charts have data (telemetry at 20 Hz)
    wait_for(lambda: latest(dashboard)["link"]["tel_hz"] > 10, what="telemetry")
    expect(page.locator("#battery")).to_contain_text("V")


def test_keyboard_drives_the_robot_and_releasing_stops_it(page: Page, dashboard: Dashboard) -> None:
    x0, y0, _ = pose(dashboard)
    page.keyboard.down("w")
    wait_for(lambda: latest(dashboard)["drive"]["state"] == "driving", what="driving")
    expect(page.locator("#drive-state")).to_contain_text("driving (keyboard)")
    wait_for(lambda: pose(dashboard)[0] - x0 > 0.3, what="0.3 m forward")  # about a second at half speed
    page.keyboard.up("w")
    wait_for(lambda: latest(dashboard)["drive"]["ended"] == "released", what="release")
    wait_for(lambda: not moving(dashboard), what="the robot to stop")
    x1, y1, _ = pose(dashboard)
    assert x1 - x0 > 0.3  # forward (+x in the room)
    assert abs(y1 - y0) < 0.05
    expect(page.locator("#pose")).not_to_contain_text("x 1.00 m")
    time.sleep(0.3)
    assert pose(dashboard)[0] - x1 < 0.01  # it stays stopped


def test_emergency_stop_stops_the_robot_and_ignores_driving_until_resume(
    page: Page, dashboard: Dashboard
) -> None:
    page.keyboard.down("w")
    wait_for(lambda: moving(dashboard), what="moving")
    page.click("#estop")
    wait_for(lambda: latest(dashboard)["drive"]["state"] == "estop", what="e-stop")
    expect(page.locator("#drive-state")).to_have_text("E-STOP")
    expect(page.locator("#control")).to_contain_text("emergency stop (page)")  # who holds the robot
    wait_for(lambda: not moving(dashboard), what="the robot to stop")
    assert latest(dashboard)["robot_state"] in ("idle", "estop")
    page.keyboard.up("w")
    # driving is ignored while the emergency stop is engaged
    x0 = pose(dashboard)[0]
    for _ in range(15):
        page.evaluate("window.omnibot.send({type: 'drive', vx: 1, vy: 0, w: 0})")
        time.sleep(0.05)
    assert abs(pose(dashboard)[0] - x0) < 0.01
    expect(page.locator("#resume")).to_be_enabled()
    page.click("#resume")
    wait_for(lambda: latest(dashboard)["drive"]["state"] != "estop", what="resume")
    expect(page.locator("#resume")).to_be_disabled()


def test_malformed_messages_are_rejected_and_shown(page: Page, dashboard: Dashboard) -> None:
    x0 = pose(dashboard)[0]
    page.evaluate("""window.omnibot.sendRaw(JSON.stringify({type: "drive", vx: 5, vy: 0, w: 0}))""")
    expect(page.locator("#error")).to_be_visible()
    expect(page.locator("#error")).to_contain_text(
        "message rejected: drive.vx: Input should be less than or equal to 1"
    )
    page.evaluate("window.omnibot.sendRaw('not json')")
    expect(page.locator("#error")).to_contain_text("not JSON")
    page.evaluate("window.omnibot.sendRaw(JSON.stringify({type: 'fly'}))")
    expect(page.locator("#error")).to_contain_text("unknown message type 'fly'")
    expect(page.locator("#log")).to_contain_text("drive.vx")
    time.sleep(0.3)
    assert dashboard.hub.rejected == 3
    assert latest(dashboard)["drive"]["state"] == "idle"  # never acted on
    assert abs(pose(dashboard)[0] - x0) < 0.005


def test_on_screen_joystick_and_gamepad_messages_drive(page: Page, dashboard: Dashboard) -> None:
    box = page.locator("#stick").bounding_box()
    assert box is not None
    cx, cy = box["x"] + box["width"] / 2, box["y"] + box["height"] / 2
    x0, y0, _ = pose(dashboard)
    page.mouse.move(cx, cy)
    page.mouse.down()
    page.mouse.move(cx - 40, cy, steps=4)  # stick left: strafe left (+y)
    wait_for(lambda: pose(dashboard)[1] - y0 > 0.15, what="0.15 m to the left")
    page.mouse.up()
    wait_for(lambda: latest(dashboard)["drive"]["ended"] == "released", what="release")
    x1, y1, _ = pose(dashboard)
    assert y1 - y0 > 0.15 and abs(x1 - x0) < 0.05
    # a gamepad (standard layout), mapped with seed 003's teleop config: hold button 7 and move axis 3;
    # the browser's +0.3 is joy's -0.3, times scale_linear.x = -3.5: forward
    sources = set()
    end = time.monotonic() + 30.0
    while pose(dashboard)[0] - x1 <= 0.1:  # at 20 Hz, as the page polls a pad
        assert time.monotonic() < end, "timed out waiting for the gamepad drive"
        page.evaluate("window.omnibot.send({type: 'joy', axes: [0, 0, 0, 0.3], buttons: [0,0,0,0,0,0,0,1]})")
        time.sleep(0.05)
        sources.add(latest(dashboard)["drive"]["source"])
    assert "gamepad" in sources


def test_screenshot(browser: Browser, tmp_path: Path) -> None:
    """The page with a planned path, after a short drive; ``OMNIBOT_SCREENSHOT=1`` writes docs/dashboard.png."""
    corners = [(1.0, 1.0), (2.6, 1.0), (2.6, 1.9), (1.6, 1.9)]
    path = [(x + 0.0, y + 0.0) for x, y in corners]
    with Dashboard(ROOM, http_port=0, path=path) as dashboard:
        context = browser.new_context(viewport={"width": 1400, "height": 820})
        try:
            page = context.new_page()
            page.goto(dashboard.url)
            page.wait_for_function("window.omnibot && window.omnibot.state() !== null")
            for keys, seconds in ((["w"], 1.5), (["w", "a"], 0.9), (["a", "q"], 0.5), (["s", "q"], 0.4)):
                for key in keys:
                    page.keyboard.down(key)
                time.sleep(seconds)
                for key in keys:
                    page.keyboard.up(key)
            wait_for(lambda: not moving(dashboard), what="stop")
            time.sleep(1.0)
            out = (
                DOCS / "dashboard.png" if os.environ.get("OMNIBOT_SCREENSHOT") else tmp_path / "dashboard.png"
            )
            out.write_bytes(page.screenshot())  # (screenshot(path=...) writes through a thread pool)
        finally:
            context.close()
    assert out.stat().st_size > 10_000
    assert not math.isnan(pose(dashboard)[0])


def test_teach_and_repeat_from_the_page(browser: Browser) -> None:
    from omnibot.navigation import PathTeacher
    from omnibot.robot import load_robot

    teacher = PathTeacher(load_robot("omni4"), period=0.05, speed=0.3)
    with Dashboard(ROOM, http_port=0, teach=teacher) as dashboard:
        context = browser.new_context(viewport={"width": 1400, "height": 950})
        try:
            page = context.new_page()
            page.goto(dashboard.url)
            page.wait_for_function("window.omnibot && window.omnibot.state() !== null")
            teach = page.locator("[data-teach='record']")
            expect(teach).to_be_enabled()
            expect(page.locator("#teach-note")).to_contain_text("Repeat drives to its start")
            t0 = sim_time(dashboard)
            wait_for(lambda: sim_time(dashboard) - t0 >= 0.5, what="0.5 s standing")  # the gyro's bias
            x0 = pose(dashboard)[0]
            teach.click()
            page.keyboard.down("w")
            wait_for(lambda: pose(dashboard)[0] - x0 > 0.25, what="0.25 m forward")
            page.keyboard.up("w")
            wait_for(lambda: not moving(dashboard), what="the robot to stop")
            page.locator("[data-teach='stop']").click()
            expect(page.locator("#log")).to_contain_text("press Repeat to follow it")
            x1, y1, _ = pose(dashboard)
            page.locator("[data-teach='follow']").click()
            wait_for(lambda: latest(dashboard)["drive"]["state"] == "following", what="following")
            expect(page.locator("#log")).to_contain_text("to its start first")
            wait_for(lambda: latest(dashboard)["drive"]["state"] != "following", 20.0, what="the repeat")
            x2, y2, _ = pose(dashboard)
            assert math.hypot(x2 - x1, y2 - y1) < 0.03  # back at the end of the taught path
            assert x1 - x0 > 0.2
        finally:
            context.close()


def _open_page(browser: Browser, dashboard: Dashboard) -> Any:
    context = browser.new_context(viewport={"width": 1400, "height": 950})
    page = context.new_page()
    page.goto(dashboard.url)
    page.wait_for_function("window.omnibot && window.omnibot.state() !== null")
    return context, page


def test_a_path_file_is_drawn_from_the_robot_not_the_room_corner(browser: Browser, tmp_path: Path) -> None:
    from omnibot.web.scene import load_path

    file = tmp_path / "square.csv"  # a path file starts at its own origin, as `omnibot record` writes them
    file.write_text("t,x,y,theta\n0,0,0,0\n2,1,0,0\n3,1,0.5,0\n")
    with Dashboard(ROOM, http_port=0, path=load_path(file)) as dashboard:
        context, page = _open_page(browser, dashboard)
        try:
            drawn = page.evaluate("window.omnibot.scene().path")
            assert drawn[0] == [1.0, 1.0]  # on the robot at the room's start pose (1, 1), heading 0
            assert drawn[-1] == [2.0, 1.5]
            expect(page.locator("#pose")).to_contain_text("(truth)")  # sim:// gives ground truth
            expect(page.locator("#legend-odo")).to_be_visible()
        finally:
            context.close()


def test_on_a_real_link_the_pose_is_labelled_odometry_from_the_maps_start(browser: Browser) -> None:
    from omnibot.sim import spawn_pty_emulator
    from omnibot.web.scene import PlannedPath

    path = PlannedPath(((0.0, 0.0), (0.5, 0.0)))
    with (
        spawn_pty_emulator("omni4", world="room", seed=1) as device,  # a serial line: no truth
        Dashboard(device, "omni4", http_port=0, world="room", path=path) as dashboard,
    ):
        context, page = _open_page(browser, dashboard)
        try:
            expect(page.locator("#pose")).to_contain_text("(odometry)")
            expect(page.locator("#pose")).not_to_contain_text("truth")
            expect(page.locator("#legend-odo")).to_be_hidden()
            assert latest(dashboard)["pose_source"] == "odometry"
            # odometry starts where the room puts the robot, and the path file is drawn from there
            expect(page.locator("#pose")).to_contain_text("x 1.00 m, y 1.00 m")
            assert page.evaluate("window.omnibot.scene().path") == [[1.0, 1.0], [1.5, 1.0]]
        finally:
            context.close()
