"""The scanner on the dashboard, in Debian's chromium: the state frames carry the latest scan's returns
(world frame, at most SCAN_POINTS of them) and the page draws them on its map canvas, where the room's
walls and furniture are."""

from __future__ import annotations

import math

from playwright.sync_api import Page

from omnibot.web.dashboard import Dashboard
from omnibot.web.scanview import SCAN_POINTS


def _distance(p: tuple[float, float], a: list[float], b: list[float]) -> float:
    (px, py), (ax, ay), (bx, by) = p, a, b
    dx, dy = bx - ax, by - ay
    k = max(0.0, min(1.0, ((px - ax) * dx + (py - ay) * dy) / (dx * dx + dy * dy or 1e-12)))
    return math.hypot(px - ax - k * dx, py - ay - k * dy)


def test_the_page_draws_the_latest_scan_where_the_walls_are(page: Page, dashboard: Dashboard) -> None:
    page.wait_for_function("window.omnibot.scan() !== null && window.omnibot.scene() !== null")
    scan = page.evaluate("window.omnibot.scan()")
    world = page.evaluate("window.omnibot.scene().world")
    points = scan["points"]
    assert 100 <= len(points) <= SCAN_POINTS  # omni4's 360 rays, decimated, less the dropouts
    edges = [((x0, y0), (x1, y1)) for x0, y0, x1, y1 in world["segments"]]
    for poly in world["obstacles"]:
        edges += [(poly[i], poly[(i + 1) % len(poly)]) for i in range(len(poly))]
    # every return lies on a wall or a piece of furniture (1 % range noise, 2 cm; the robot stands)
    far = [p for p in points if min(_distance((p[0], p[1]), list(a), list(b)) for a, b in edges) > 0.1]
    assert len(far) <= 2, far
    # and the map canvas shows them: pixels of the scan's colour
    drawn = page.evaluate(
        """() => {
          const c = document.getElementById("map");
          const d = c.getContext("2d").getImageData(0, 0, c.width, c.height).data;
          let n = 0;
          for (let i = 0; i < d.length; i += 4) if (d[i] === 225 && d[i + 1] === 29 && d[i + 2] === 72) n++;
          return n;
        }"""
    )
    assert drawn >= 4 * len(points) // 2, drawn  # a 4x4 dot each, some overlapping
    assert page.locator("#legend-scan").is_visible()
    # the scan is renewed: a later frame carries a later one
    t0 = scan["t"]
    page.wait_for_function(f"window.omnibot.scan().t > {t0}")
