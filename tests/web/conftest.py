"""Fixtures for the dashboard tests: a served dashboard on 127.0.0.1 and Debian's chromium.

The browser is Debian's ``/usr/bin/chromium`` driven by playwright (never ``playwright install``);
``make test`` installs it when missing (``make browser``). It is started once per module with the
flags this machine needs (no background networking, no sandbox as root, a fresh profile that
playwright makes and removes); each test gets a fresh context and page. Every dashboard is bound
to 127.0.0.1 on an ephemeral port and stopped at the end of its test.
"""

from __future__ import annotations

import os
import shutil
from collections.abc import Iterator

import pytest
from playwright.sync_api import Browser, Page, expect, sync_playwright

from omnibot.web.dashboard import Dashboard

CHROMIUM = os.environ.get("OMNIBOT_CHROMIUM", "/usr/bin/chromium")
CHROMIUM_ARGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
]
ROOM = "sim://omni4?world=room&seed=1"
WAIT_MS = 30_000
"""How long an ``expect`` waits for the page (playwright's default, 5 s, is short on a loaded machine:
the dashboard's threads, the simulator and chromium share two cores with the rest of the suite)."""

expect.set_options(timeout=WAIT_MS)


@pytest.fixture
def dashboard() -> Iterator[Dashboard]:
    with Dashboard(ROOM, http_port=0) as dash:
        yield dash


@pytest.fixture(scope="module")
def browser() -> Iterator[Browser]:
    if not shutil.which(CHROMIUM) and not os.path.exists(CHROMIUM):
        pytest.fail(f"Debian's chromium is not at {CHROMIUM}: run `make browser` (apt-get install chromium)")
    with sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS, headless=True)
        try:
            yield browser
        finally:
            browser.close()


@pytest.fixture
def page(browser: Browser, dashboard: Dashboard) -> Iterator[Page]:
    """The dashboard's page, loaded and showing live state; fails the test on any script error."""
    context = browser.new_context(viewport={"width": 1400, "height": 950})
    page = context.new_page()
    errors: list[str] = []
    page.on("pageerror", lambda exc: errors.append(str(exc)))
    page.on("console", lambda msg: errors.append(msg.text) if msg.type == "error" else None)
    try:
        page.goto(dashboard.url)
        page.wait_for_function("window.omnibot && window.omnibot.state() !== null")
        yield page
        assert not errors, f"the page reported errors: {errors}"
    finally:
        context.close()
