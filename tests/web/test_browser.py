"""cnc ui web end to end: Debian's chromium (headless, through Playwright) drives the page
against a real machine (``cnc run --headless`` on tests/task/machine/mill.ini, see
conftest.py), at 1280x800 as a touch panel would show it.

Skipped when Playwright or /usr/bin/chromium is missing (no browser is ever downloaded:
``executable_path`` is the system chromium). Screenshots of the main views are saved in
tests/web/artifacts/ (git-ignored; ``$CNC_TEST_ARTIFACTS/web`` if that is set), for CI to
keep. Every wait is on a condition (generous timeouts for a slow CI box), never a sleep.
"""

from __future__ import annotations

import os
import re
from pathlib import Path

import pytest

from hal.api import HAL_BIT, HAL_OUT, component
from hal.core import Hal
from tests.task.test_machine import Machine

CHROMIUM = Path("/usr/bin/chromium")
CHROMIUM_ARGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-dev-shm-usage",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
]
WAIT_MS = 30_000  # generous: only reached when something is broken

sync_api = pytest.importorskip("playwright.sync_api")
pytestmark = pytest.mark.skipif(not CHROMIUM.exists(), reason="no /usr/bin/chromium")


def artifacts() -> Path:
    """Where the screenshots go (printed, so a failing run says where to look)."""
    root = os.environ.get("CNC_TEST_ARTIFACTS")
    folder = Path(root) / "web" if root else Path(__file__).with_name("artifacts")
    folder.mkdir(parents=True, exist_ok=True)
    print(f"screenshots in {folder}")
    return folder


def pin(hal: Hal, name: str) -> object:
    found = hal.find_pin(name)
    assert found is not None, f"no pin {name}"
    return hal.pin_value(found[1])


def test_the_page_brings_the_machine_up_and_runs_mdi_programs_dialogs_and_tool_edits(
    machine: Machine, page_url: str
) -> None:
    shots = artifacts()
    hal = Hal(is_creating=False)  # the machine's HAL: a component drives the message pin
    driver = component("driver", hal=hal)
    driver.newpin("door-open", HAL_BIT, HAL_OUT)
    driver.ready()
    hal.new_signal("door-open", HAL_BIT)
    hal.link("driver.door-open", "door-open")
    hal.link("web.messages.door", "door-open")
    expect = sync_api.expect
    expect.set_options(timeout=WAIT_MS)
    try:
        with sync_api.sync_playwright() as playwright:
            browser = playwright.chromium.launch(
                executable_path=str(CHROMIUM), args=CHROMIUM_ARGS, timeout=WAIT_MS
            )
            try:
                page = browser.new_page(viewport={"width": 1280, "height": 800})
                page.set_default_timeout(WAIT_MS)
                page.goto(page_url)
                bring_up(page, expect)
                run_mdi_and_a_program(page, expect, shots)
                jog_and_abort(page, expect)
                answer_a_message_dialog(page, expect, shots, driver, hal)
                show_the_preview(page, expect, shots)
                edit_a_tool(page, expect, shots, machine)
                type_decimal_commas(page, expect)
                page.set_viewport_size({"width": 800, "height": 1000})  # narrow: one column
                page.screenshot(path=str(shots / "narrow.png"), full_page=True)
            finally:
                browser.close()
    finally:
        driver.exit()
        hal.close()


def bring_up(page, expect) -> None:  # type: ignore[no-untyped-def]
    expect(page.locator("#link")).to_have_text("online")
    expect(page.locator("#task-state")).to_have_text("ESTOP")
    page.click("#estop")
    expect(page.locator("#task-state")).to_have_text("ESTOP_RESET")
    page.click("#power")
    expect(page.locator("#task-state")).to_have_text("ON")
    page.click("#home-all")
    expect(page.locator("#dro tbody tr.is-homed")).to_have_count(3)
    # 1280x800 (a touch panel): nothing sticks out sideways, nor below the window
    size = page.evaluate(
        "[document.documentElement.scrollWidth, document.documentElement.scrollHeight]"
    )
    assert size[0] <= 1280 and size[1] <= 800, size


def run_mdi_and_a_program(page, expect, shots: Path) -> None:  # type: ignore[no-untyped-def]
    x_work = page.locator('#dro tr[data-axis="X"] td.work')
    y_work = page.locator('#dro tr[data-axis="Y"] td.work')
    page.fill("#mdi-text", "G0 X10 Y-5")
    page.press("#mdi-text", "Enter")
    expect(x_work).to_have_text("10.000")
    expect(y_work).to_have_text("-5.000")
    expect(page.locator("#mdi-history li").first).to_have_text("G0 X10 Y-5")

    page.fill("#mdi-text", "G999")  # the controller's reason, as a dismissible notice
    page.press("#mdi-text", "Enter")
    refused = page.locator(".notice.error").filter(has_text="G-code out of range")
    expect(refused).to_be_visible()
    refused.locator("button").click()
    expect(refused).to_have_count(0)

    page.select_option("#program-list", "part.ngc")  # open and run: the DRO reaches its end
    page.click("#program-open")
    expect(page.locator("#listing li")).to_have_count(4)
    page.click("#run")
    expect(x_work).to_have_text("3.000")
    expect(y_work).to_have_text("2.000")
    expect(page.locator("#interp-state")).to_have_text("IDLE")
    expect(page.locator('#dro tr[data-axis="X"] td.dtg')).to_have_text("0.000")
    page.screenshot(path=str(shots / "main.png"))
    page.click("#dro-joints")  # the joint view, and back
    expect(page.locator('#dro tr[data-axis="J0"] td.work')).to_have_text("3.000")
    page.click("#dro-joints")
    expect(x_work).to_have_text("3.000")


def jog_and_abort(page, expect) -> None:  # type: ignore[no-untyped-def]
    x_work = page.locator('#dro tr[data-axis="X"] td.work')
    page.select_option("#increment", label="1 mm")  # a step jog switches to manual
    page.click("text=X+")
    expect(x_work).to_have_text("4.000")
    expect(page.locator("#task-mode")).to_have_text("MANUAL")
    page.locator("body").press("ArrowRight")  # keyboard jog, as AXIS
    expect(x_work).to_have_text("5.000")

    page.fill("#mdi-text", "G1 X90 F300")  # 17 s long: Esc stops it
    page.press("#mdi-text", "Enter")
    expect(page.locator("#interp-state")).not_to_have_text("IDLE")
    page.keyboard.press("Escape")
    expect(page.locator("#interp-state")).to_have_text("IDLE")
    expect(page.locator('#dro tr[data-axis="X"] td.dtg')).to_have_text("0.000")
    assert float(x_work.inner_text()) < 89


def answer_a_message_dialog(page, expect, shots: Path, driver, hal: Hal) -> None:  # type: ignore[no-untyped-def]
    """[DISPLAY] MESSAGE_* yesnodialog (GUI-018): the pin rises, the page asks, the answer
    comes back on web.messages.door-response."""
    driver["door-open"] = True
    dialog = page.locator('#dialogs .dialog[data-name="door"]')
    expect(dialog).to_be_visible()
    expect(dialog.locator("h3")).to_have_text("Door")
    expect(dialog.locator("p")).to_have_text("Is the door closed?")
    assert pin(hal, "web.messages.door-waiting") == 1
    page.screenshot(path=str(shots / "dialog.png"))
    dialog.get_by_role("button", name="Yes").click()
    expect(dialog).to_have_count(0)
    assert pin(hal, "web.messages.door-response") == 1
    assert pin(hal, "web.messages.door-waiting") == 0


def show_the_preview(page, expect, shots: Path) -> None:  # type: ignore[no-untyped-def]
    page.click("#show-preview")
    expect(page.locator("#preview")).to_be_visible()
    expect(page.locator("#preview")).to_have_attribute("data-points", re.compile("[1-9]"))
    expect(page.locator("#preview-error")).to_have_text("")
    page.click('[data-view="top"]')
    page.screenshot(path=str(shots / "preview.png"))


def edit_a_tool(page, expect, shots: Path, machine: Machine) -> None:  # type: ignore[no-untyped-def]
    """A tool edit with a decimal comma reaches the file and iocontrol (stat.tool_table)."""
    page.click("#show-tools")
    rows = page.locator("#tools tbody tr")
    expect(rows).to_have_count(2)  # test.tbl: T1, T2
    row = page.locator('#tools tr[data-tool="1"]')
    expect(row.locator("td.comment")).to_have_text("6 mm end mill")
    row.get_by_role("button", name="Edit").click()
    row.locator('input[name="z"]').fill("12,5")
    row.locator('input[name="diameter"]').fill("x")  # not a number: refused in the page
    row.get_by_role("button", name="Save").click()
    expect(page.locator(".notice.error").filter(has_text="diameter: 'x'")).to_be_visible()
    row.locator('input[name="diameter"]').fill("6,35")
    row.get_by_role("button", name="Save").click()
    expect(row.locator("td").nth(1)).to_have_text("12.500")
    expect(row.locator("td").nth(3)).to_have_text("6.350")
    assert (machine.folder / "test.tbl").read_text().splitlines()[0] == (
        "T1   P1   D+6.350000 Z+12.500000 ;6 mm end mill"
    )
    machine.until(lambda s: s.tool_table[1].zoffset == 12.5)
    page.screenshot(path=str(shots / "tools.png"))
    upload = {"name": "up.ngc", "mimeType": "text/plain", "buffer": b"G0 X5\nM2\n"}
    page.set_input_files("#program-upload", files=[upload])
    expect(page.locator("#program-file")).to_contain_text("up.ngc")


def type_decimal_commas(page, expect) -> None:  # type: ignore[no-untyped-def]
    """Every typed number takes ',' or '.' (GUI-003): the page's parser, the rpm field and
    the touch-off prompt (tool edits are above)."""
    cases = ["1,5", "1.5", "-0,25", " 1 234,5 ", ",5", "1,2,3", "1.2,3", "abc", "", "1e3"]
    parsed = page.evaluate(f"{cases}.map(parseDecimal)")
    assert parsed == [1.5, 1.5, -0.25, 1234.5, 0.5, None, None, None, None, None]
    page.fill("#spindle-speed", "1234,4")
    page.click('[data-spindle="forward"]')
    expect(page.locator("#spindle-state")).to_contain_text("1234 rpm")
    page.click('[data-spindle="stop"]')
    expect(page.locator("#spindle-state")).to_have_text("stopped 0 rpm")
    page.once("dialog", lambda prompt: prompt.accept("2,5"))
    page.locator('#dro tr[data-axis="Y"] button.touch').click()
    expect(page.locator('#dro tr[data-axis="Y"] td.work')).to_have_text("2.500")
    page.fill("#run-line", "1,5")  # a line number is whole
    page.click("#run")
    expect(
        page.locator(".notice.error").filter(has_text="'1,5' is not a line number")
    ).to_be_visible()
