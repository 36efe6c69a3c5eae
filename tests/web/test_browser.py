"""cnc ui web end to end: Debian's chromium (headless, through Playwright) drives the page
against a real machine (``cnc run --headless`` on tests/task/machine/mill.ini).

Skipped when Playwright or /usr/bin/chromium is missing (no browser is ever downloaded).
Screenshots of the main view are saved in the test's tmp_path.
"""

from __future__ import annotations

import re
import shutil
import signal
import socket
import subprocess
import time
import urllib.error
import urllib.request
from collections.abc import Iterator
from pathlib import Path

import pytest

from tests.conftest import Processes
from tests.task.test_machine import MACHINE, Machine

CHROMIUM = Path("/usr/bin/chromium")
CHROMIUM_ARGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
]
SERVER_MAIN = "import sys; from cnc.ui.web.server import main; sys.exit(main(sys.argv[1:]))"
WAIT_MS = 20_000  # generous: only reached when something is broken

sync_api = pytest.importorskip("playwright.sync_api")
pytestmark = pytest.mark.skipif(not CHROMIUM.exists(), reason="no /usr/bin/chromium")


def free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


def wait_http(url: str, proc: subprocess.Popen[str], timeout: float = 20) -> None:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        assert proc.poll() is None, proc.stderr.read() if proc.stderr else ""
        try:
            with urllib.request.urlopen(url, timeout=1):
                return
        except (urllib.error.URLError, ConnectionError):
            time.sleep(0.1)
    raise AssertionError(f"{url} never answered")


@pytest.fixture
def machine(procs: Processes, tmp_path: Path) -> Iterator[Machine]:
    folder = tmp_path / "machine"
    shutil.copytree(MACHINE, folder)
    (folder / "part.ngc").write_text("G21 G90\nG0 X1 Y2\nG3 X3 Y2 I1 F600\nM2\n")
    proc = procs.python("-m", "cnc", "run", "--headless", "mill.ini", cwd=folder)
    found = Machine(proc, folder)
    try:
        found.wait_ready()
        yield found
    finally:
        proc.send_signal(signal.SIGTERM)
        try:
            proc.wait(timeout=30)
        except subprocess.TimeoutExpired:
            proc.kill()


@pytest.fixture
def page_url(machine: Machine, procs: Processes) -> str:
    port = free_port()
    server = procs.python(
        "-c", SERVER_MAIN, "web", "mill.ini", "--port", str(port), cwd=machine.folder
    )
    url = f"http://127.0.0.1:{port}/"
    wait_http(url, server)
    return url


def test_the_page_brings_the_machine_up_and_runs_mdi_and_a_program(
    page_url: str, tmp_path: Path
) -> None:
    expect = sync_api.expect
    with sync_api.sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=str(CHROMIUM), args=CHROMIUM_ARGS)
        try:
            page = browser.new_page(viewport={"width": 1280, "height": 800})
            page.goto(page_url)
            expect(page.locator("#link")).to_have_text("online", timeout=WAIT_MS)
            expect(page.locator("#task-state")).to_have_text("ESTOP", timeout=WAIT_MS)
            page.click("#estop")
            expect(page.locator("#task-state")).to_have_text("ESTOP_RESET", timeout=WAIT_MS)
            page.click("#power")
            expect(page.locator("#task-state")).to_have_text("ON", timeout=WAIT_MS)
            page.click("#home-all")
            expect(page.locator("#dro tbody tr.is-homed")).to_have_count(3, timeout=WAIT_MS)

            page.fill("#mdi-text", "G0 X10 Y-5")
            page.press("#mdi-text", "Enter")
            x_work = page.locator('#dro tr[data-axis="X"] td.work')
            expect(x_work).to_have_text("10.000", timeout=WAIT_MS)
            expect(page.locator('#dro tr[data-axis="Y"] td.work')).to_have_text("-5.000")
            expect(page.locator("#mdi-history li").first).to_have_text("G0 X10 Y-5")

            page.fill("#mdi-text", "G999")
            page.press("#mdi-text", "Enter")
            expect(
                page.locator(".notice.error").filter(has_text="G-code out of range")
            ).to_be_visible(timeout=WAIT_MS)

            page.select_option("#program-list", "part.ngc")
            page.click("#program-open")
            expect(page.locator("#listing li")).to_have_count(4, timeout=WAIT_MS)
            page.click("#run")
            expect(x_work).to_have_text("3.000", timeout=WAIT_MS)
            expect(page.locator('#dro tr[data-axis="Y"] td.work')).to_have_text("2.000")
            expect(page.locator("#interp-state")).to_have_text("IDLE", timeout=WAIT_MS)
            page.screenshot(path=str(tmp_path / "main.png"))
            page.click("#dro-joints")  # the joint view, and back
            expect(page.locator('#dro tr[data-axis="J0"] td.work')).to_have_text("3.000")
            page.click("#dro-joints")
            expect(x_work).to_have_text("3.000")

            page.select_option("#increment", label="1 mm")  # a step jog switches to manual
            page.click("text=X+")
            expect(x_work).to_have_text("4.000", timeout=WAIT_MS)
            expect(page.locator("#task-mode")).to_have_text("MANUAL")
            page.locator("body").press("ArrowRight")  # keyboard jog, as AXIS
            expect(x_work).to_have_text("5.000", timeout=WAIT_MS)

            page.fill("#mdi-text", "G1 X90 F300")  # 17 s long: Esc stops it
            page.press("#mdi-text", "Enter")
            expect(page.locator("#interp-state")).not_to_have_text("IDLE", timeout=WAIT_MS)
            page.keyboard.press("Escape")
            expect(page.locator("#interp-state")).to_have_text("IDLE", timeout=WAIT_MS)
            expect(page.locator('#dro tr[data-axis="X"] td.dtg')).to_have_text("0.000")
            assert float(x_work.inner_text()) < 89

            page.click("#show-preview")
            expect(page.locator("#preview")).to_be_visible()
            expect(page.locator("#preview")).to_have_attribute("data-points", re.compile("[1-9]"))
            expect(page.locator("#preview-error")).to_have_text("")
            page.click('[data-view="top"]')
            page.screenshot(path=str(tmp_path / "preview.png"))

            page.click("#show-tools")
            expect(page.locator("#tools tbody tr")).to_have_count(2)  # test.tbl: T1, T2
            upload = {"name": "up.ngc", "mimeType": "text/plain", "buffer": b"G0 X5\nM2\n"}
            page.set_input_files("#program-upload", files=[upload])
            expect(page.locator("#program-file")).to_contain_text("up.ngc", timeout=WAIT_MS)
            page.screenshot(path=str(tmp_path / "tools.png"))

            page.set_viewport_size({"width": 800, "height": 1000})  # narrow: one column
            page.screenshot(path=str(tmp_path / "narrow.png"), full_page=True)
        finally:
            browser.close()
