"""cnc ui web end to end: Debian's chromium (headless, through Playwright) drives the page
against a real machine (``cnc run --headless`` on tests/task/machine/mill.ini, see
conftest.py), as an operator would, for each behaviour of issue 18.

Skipped when Playwright or /usr/bin/chromium is missing (no browser is ever downloaded:
``executable_path`` is the system chromium; its software renderer, SwiftShader, gives the
page WebGL 2). Screenshots of every view at 1920x1080, 1280x800, 1024x600 and a 600 px
tablet go to tests/web/artifacts/ (git-ignored; ``$CNC_TEST_ARTIFACTS/web`` if set), for
CI to keep. Every wait is on a condition (generous timeouts for a slow CI box), never a
sleep. Latency figures are measured by scripts/bench/ui_bench.py, not asserted here.
"""

from __future__ import annotations

import math
import os
import re
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

import cnc
from hal.api import HAL_BIT, HAL_OUT, component
from hal.core import Hal
from tests.conftest import Processes
from tests.task.test_machine import Machine, launched

CHROMIUM = Path("/usr/bin/chromium")
CHROMIUM_ARGS = [
    "--headless=new",
    "--no-sandbox",
    "--use-angle=swiftshader",  # WebGL 2 without a graphics card
    "--enable-unsafe-swiftshader",
    "--disable-dev-shm-usage",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
]
WAIT_MS = 60_000  # generous: only reached when something is broken
SIZES = {"1920x1080": (1920, 1080), "1280x800": (1280, 800), "1024x600": (1024, 600),
         "tablet600": (600, 960)}  # fmt: skip
VIEWS = ("run", "offsets", "tools", "probe", "editor", "history")

sync_api = pytest.importorskip("playwright.sync_api")
pytestmark = [
    pytest.mark.skipif(not CHROMIUM.exists(), reason="no /usr/bin/chromium"),
    pytest.mark.slow,
]
expect = sync_api.expect


def artifacts() -> Path:
    """Where the screenshots go (printed, so a failing run says where to look)."""
    root = os.environ.get("CNC_TEST_ARTIFACTS")
    folder = Path(root) / "web" if root else Path(__file__).with_name("artifacts")
    folder.mkdir(parents=True, exist_ok=True)
    print(f"screenshots in {folder}")
    return folder


@pytest.fixture
def browser() -> Iterator:  # type: ignore[type-arg]
    expect.set_options(timeout=WAIT_MS)
    with sync_api.sync_playwright() as playwright:
        found = playwright.chromium.launch(
            executable_path=str(CHROMIUM), args=CHROMIUM_ARGS, timeout=WAIT_MS
        )
        try:
            yield found
        finally:
            found.close()


def open_page(browser, url: str, size: tuple[int, int] = (1280, 800)):  # type: ignore[no-untyped-def]
    page = browser.new_page(viewport={"width": size[0], "height": size[1]})
    page.set_default_timeout(WAIT_MS)
    errors: list[str] = []
    page.on("pageerror", lambda error: errors.append(str(error)))
    page.errors = errors  # type: ignore[attr-defined]
    page.goto(url)
    expect(page.locator("#preview")).to_have_attribute("data-renderer", "webgl")
    return page


def pin(hal: Hal, name: str) -> object:
    found = hal.find_pin(name)
    assert found is not None, f"no pin {name}"
    return hal.pin_value(found[1])


def work(page, axis: str):  # type: ignore[no-untyped-def]
    return page.locator(f'#dro tr[data-axis="{axis}"] td.work')


def mdi(page, line: str) -> None:  # type: ignore[no-untyped-def]
    page.fill("#mdi-text", line)
    page.press("#mdi-text", "Enter")


# ================================================================== the shop's day
@pytest.mark.timeout(900)
def test_the_page_runs_a_shop_day_on_a_real_machine(
    machine: Machine, page_url: str, browser
) -> None:
    """One machine for all (a machine takes seconds to start): each step checks one
    behaviour of issue 18 as an operator sees it."""
    shots = artifacts()
    page = open_page(browser, page_url)
    estop_is_unmistakable(page, shots)
    bring_up(page)
    one_notice_per_error_and_it_expires(page)
    arrow_keys_jog_after_choosing_a_step_with_the_mouse(page)
    a_continuous_jog_lasts_while_the_key_is_held(page, machine)
    spindle_limits_and_jog_speed_come_from_the_ini(page)
    overrides_reset_to_100_and_there_is_one_stop(page)
    a_program_runs_with_progress_and_an_estimate(page, shots, machine)
    the_machines_spindle_and_coolant_beside_the_modal_state(page, machine, shots)
    an_m0_stop_shows_its_line(page, shots)
    a_load_error_marks_its_line(page)
    answer_a_message_dialog(page, shots, machine)
    tools_are_edited_added_and_deleted(page, machine)
    work_offsets_are_picked_and_set(page, machine)
    units_theme_keyboard_sheet_and_editor(page, shots)
    every_view_at_every_size(page, shots)
    the_machine_goes(page, machine, shots)
    assert page.errors == []  # type: ignore[attr-defined]


def estop_is_unmistakable(page, shots: Path) -> None:  # type: ignore[no-untyped-def]
    expect(page.locator("#state")).to_have_text("E-STOP")
    expect(page.locator("#estop-banner")).to_be_visible()
    expect(page.locator("body")).to_have_class(re.compile(r"\bis-estop\b"))
    expect(page.locator("#estop")).to_have_text("E-STOP ACTIVE")
    page.screenshot(path=str(shots / "state-estop.png"))


def bring_up(page) -> None:  # type: ignore[no-untyped-def]
    page.click("#estop")  # reset
    expect(page.locator("#state")).to_have_text("MACHINE OFF")
    expect(page.locator("#estop-banner")).to_be_hidden()
    page.click("#power")
    expect(page.locator("#state")).to_have_text("NOT HOMED")
    page.click("#home-all")
    expect(page.locator("#dro tbody tr.is-homed")).to_have_count(3)
    expect(page.locator("#state")).to_have_text("READY")


def one_notice_per_error_and_it_expires(page) -> None:  # type: ignore[no-untyped-def]
    """G0 X1000 on a +-100 mm axis: motion writes three lines; the page shows one notice
    without "line 0", and it goes by itself."""
    page.evaluate(
        "async () => { (await import('/static/js/notices.js')).LIFETIME_MS.error = 3000; }"
    )
    mdi(page, "G0 X10 Y-5")
    expect(work(page, "X")).to_have_text("10.000")
    expect(work(page, "Y")).to_have_text("-5.000")
    mdi(page, "G0 X1000")
    notice = page.locator(".notice.error")
    expect(notice).to_have_count(1)
    expect(notice).to_contain_text("Linear move would exceed X's positive limit")
    text = notice.inner_text()
    assert "line 0" not in text and "motion refused" not in text
    assert not overlap(notice.bounding_box(), page.locator("#listing").bounding_box())
    expect(page.locator(".notice")).to_have_count(0)  # expired
    expect(page.locator("#notice-count")).to_have_text("1")  # kept in the log


def overlap(a: dict, b: dict) -> bool:
    """Whether two bounding boxes share any area."""
    return (
        a["x"] < b["x"] + b["width"]
        and b["x"] < a["x"] + a["width"]
        and a["y"] < b["y"] + b["height"]
        and b["y"] < a["y"] + a["height"]
    )


def arrow_keys_jog_after_choosing_a_step_with_the_mouse(page) -> None:  # type: ignore[no-untyped-def]
    page.locator("#increment button", has_text=re.compile(r"^1 mm$")).click()
    page.keyboard.press("ArrowRight")
    expect(work(page, "X")).to_have_text("11.000")
    page.keyboard.press("ArrowRight")  # the step stays 1 mm: it never became 10 mm
    expect(work(page, "X")).to_have_text("12.000")
    expect(page.locator("#increment button.on")).to_have_text("1 mm")
    page.select_option("#program-list", "cut.ngc")  # a list with the focus: keys still jog
    page.keyboard.press("ArrowLeft")
    expect(work(page, "X")).to_have_text("11.000")
    assert page.locator("#program-list").input_value() == "cut.ngc"


def a_continuous_jog_lasts_while_the_key_is_held(page, machine: Machine) -> None:  # type: ignore[no-untyped-def]
    """The page holds a continuous jog (the server stops one not held for 0.3 s) for as
    long as the key is down, and stops it when the key comes up."""
    page.locator("#increment button", has_text="Cont.").click()
    machine.stat.poll()
    start = machine.stat.position[1]
    page.keyboard.down("ArrowUp")
    machine.until(lambda s: s.position[1] > start + 0.1)
    time.sleep(1.0)  # three times the server's lease
    machine.stat.poll()
    held = machine.stat.position[1]
    assert held > start + 0.5  # still jogging after the lease: the page refreshed it
    page.keyboard.up("ArrowUp")
    machine.until(lambda s: all(not joint["homing"] for joint in s.joint[:3]) and s.inpos)
    machine.stat.poll()
    end = machine.stat.position[1]
    time.sleep(0.3)
    machine.stat.poll()
    assert machine.stat.position[1] == end  # at rest


def spindle_limits_and_jog_speed_come_from_the_ini(page) -> None:  # type: ignore[no-untyped-def]
    assert float(page.locator("#jog-speed").get_attribute("min")) > 0  # never 0
    expect(page.locator("#spindle-range")).to_have_text("0\u20136000 rpm")
    page.fill("#spindle-speed", "12000")
    page.click('[data-spindle="forward"]')
    expect(page.locator(".notice.error").last).to_contain_text("above the spindle's maximum, 6000")
    expect(page.locator("#spindle-state")).to_have_text("OFF")
    page.fill("#spindle-speed", "500")
    page.click('[data-spindle="reverse"]')
    expect(page.locator("#spindle-state")).to_have_text("REV 500 rpm")  # no "-500"
    page.click('[data-spindle="stop"]')
    expect(page.locator("#spindle-state")).to_have_text("OFF")


def overrides_reset_to_100_and_there_is_one_stop(page) -> None:  # type: ignore[no-untyped-def]
    page.locator("#feedrate").fill("40")
    expect(page.locator("#feedrate-value")).to_have_text("40%")
    page.locator("#override-limits").focus()  # the slider lets go: the status shows again
    expect(page.locator("#feedrate")).to_have_value("40")
    page.click('[data-reset="feedrate"]')
    expect(page.locator("#feedrate")).to_have_value("100")
    # one Stop: the spindle has "Off", the program no Stop of its own (E-STOP is apart)
    stops = page.get_by_role("button", name=re.compile(r"^\W*stop\W*$", re.IGNORECASE))
    assert stops.all_inner_texts() == ["STOP"]


def a_program_runs_with_progress_and_an_estimate(  # type: ignore[no-untyped-def]
    page, shots: Path, machine: Machine
) -> None:
    mdi(page, "G0 X0 Y0")
    # (as an operator waits for the move: Open while MDI runs is refused, as in AXIS)
    expect(work(page, "X")).to_have_text("0.000")
    machine.until(lambda s: s.current_vel == 0 and s.interp_state == cnc.INTERP_IDLE)
    page.select_option("#program-list", "part.ngc")
    page.click("#program-open")
    expect(page.locator("#program-list")).to_have_value("part.ngc")  # not the first file
    expect(page.locator("#listing")).to_have_attribute("data-lines", "4")
    expect(page.locator(".listing-row .code").nth(2)).to_have_text("G3 X3 Y2 I1 F600")
    expect(page.locator("#preview")).to_have_attribute("data-drawn", re.compile("[1-9]"))
    expect(page.locator("#analysis")).to_contain_text("estimated run time")
    row = page.locator(".run-row").bounding_box()
    page.click("#run")
    notice = page.locator(".notice", has_text="part.ngc finished in")
    expect(notice).to_contain_text("(estimate 0:")
    expect(work(page, "X")).to_have_text("3.000")
    page.click('#views [data-view="history"]')
    expect(page.locator("#jobs tbody tr").first).to_contain_text("finished")
    page.click('#views [data-view="run"]')
    long_name = "a-program-with-a-name-far-longer-than-the-panel-is-wide-for-the-run-row.ngc"
    (machine.folder / long_name).write_text("G0 X0\nM2\n")
    page.click("#program-refresh")
    page.select_option("#program-list", long_name)
    page.click("#program-open")
    expect(page.locator("#program-file")).to_contain_text(long_name)
    assert page.locator(".run-row").bounding_box() == row  # the same with any file name


def the_machines_spindle_and_coolant_beside_the_modal_state(  # type: ignore[no-untyped-def]
    page, machine: Machine, shots: Path
) -> None:
    """During the long feed of cut.ngc the interpreter has read "M5 M9" already; the
    machine's spindle and flood are still on, and the page says so. The modal codes are
    those of the line being cut (LinuxCNC's state tags: M3 M8), never the read-ahead's."""
    page.select_option("#program-list", "cut.ngc")
    page.click("#program-open")
    expect(page.locator("#analysis")).to_contain_text("estimated run time")
    codes = page.locator(".listing-row .code")  # never a line of the program before
    expect(codes).to_have_text(["G21 G90", "M3 S1000", "M8", "G1 X60 F300", "M5 M9", "G0 X0", "M2"])
    page.click("#run")
    expect(page.locator("#state")).to_have_text("RUNNING")  # never READING or WAITING
    expect(page.locator("#now-spindle")).to_have_text("S 1000 rpm FWD")
    expect(page.locator("#now-coolant")).to_have_text("flood on")
    expect(page.locator("#mcodes")).to_contain_text("M3")
    expect(page.locator("#mcodes")).to_contain_text("M8")
    expect(page.locator("#progress-text")).to_contain_text(re.compile(r"\d+\.\d %.*elapsed.*left"))
    expect(page.locator(".listing-row.current .number")).to_have_text("4")
    page.screenshot(path=str(shots / "state-running.png"))
    page.keyboard.press("Escape")  # STOP
    machine.until(lambda s: s.current_vel == 0 and s.interp_state == cnc.INTERP_IDLE)
    expect(page.locator("#state")).to_have_text("READY")
    expect(page.locator(".notice", has_text="cut.ngc stopped after")).to_have_count(1)
    mdi(page, "M5 M9")  # whatever STOP left on (task's business, not the page's)
    expect(page.locator("#now-spindle")).to_have_text("spindle off")


def an_m0_stop_shows_its_line(page, shots: Path) -> None:  # type: ignore[no-untyped-def]
    page.select_option("#program-list", "stop.ngc")
    page.click("#program-open")
    expect(page.locator("#listing")).to_have_attribute("data-lines", "8")
    page.click("#run")
    expect(page.locator("#state")).to_have_text("STOPPED")
    expect(page.locator("#state-detail")).to_contain_text("at line 5 (M0, M1 or a step)")
    expect(page.locator(".listing-row.current .number")).to_have_text("5")  # the M0 line
    page.screenshot(path=str(shots / "state-m0.png"))
    page.click("#resume")
    expect(page.locator(".notice", has_text="stop.ngc finished in")).to_have_count(1)


def a_load_error_marks_its_line(page) -> None:  # type: ignore[no-untyped-def]
    page.select_option("#program-list", "bad.ngc")
    page.click("#program-open")
    expect(page.locator(".notice.error", has_text="bad.ngc: line 3:")).to_have_count(1)
    row = page.locator(".listing-row.error")
    expect(row.locator(".number")).to_have_text("3")
    expect(page.locator("#analysis")).to_contain_text("error on line 3")


def answer_a_message_dialog(page, shots: Path, machine: Machine) -> None:  # type: ignore[no-untyped-def]
    """[DISPLAY] MESSAGE_* yesnodialog (GUI-018): the pin rises, the page asks, the answer
    comes back on web.messages.door-response."""
    hal = Hal(is_creating=False)  # the machine's HAL: a component drives the message pin
    driver = component("driver", hal=hal)
    try:
        driver.newpin("door-open", HAL_BIT, HAL_OUT)
        driver.ready()
        hal.new_signal("door-open", HAL_BIT)
        hal.link("driver.door-open", "door-open")
        hal.link("web.messages.door", "door-open")
        driver["door-open"] = True
        dialog = page.locator('#dialogs .dialog[data-name="door"]')
        expect(dialog).to_be_visible()
        expect(dialog.locator("h3")).to_have_text("Door")
        assert pin(hal, "web.messages.door-waiting") == 1
        page.screenshot(path=str(shots / "dialog.png"))
        dialog.get_by_role("button", name="Yes").click()
        expect(dialog).to_have_count(0)
        assert pin(hal, "web.messages.door-response") == 1
    finally:
        driver.exit()
        hal.close()


def tools_are_edited_added_and_deleted(page, machine: Machine) -> None:  # type: ignore[no-untyped-def]
    page.click('#views [data-view="tools"]')
    rows = page.locator("#tools tbody tr")
    expect(rows).to_have_count(2)  # test.tbl: T1, T2
    row = page.locator('#tools tr[data-tool="1"]')
    row.get_by_role("button", name="Edit").click()
    z = row.locator('input[name="z"]')
    z.fill("35,125")  # wide enough to read whole
    assert z.evaluate("e => e.scrollWidth <= e.clientWidth")
    row.get_by_role("button", name="Save").click()
    expect(row.locator("td").nth(1)).to_have_text("35.125")
    machine.until(lambda s: s.tool_table[1].zoffset == 35.125)
    form = page.locator("#tool-add")
    form.locator('input[name="tool"]').fill("7")
    form.locator('input[name="z"]').fill("12,5")
    form.locator('input[name="comment"]').fill("chamfer")
    form.get_by_role("button", name="Add").click()
    expect(page.locator('#tools tr[data-tool="7"] td.comment')).to_have_text("chamfer")
    page.locator('#tools tr[data-tool="7"]').get_by_role("button", name="Delete").click()
    page.locator("#modal").get_by_role("button", name="Delete").click()
    expect(page.locator('#tools tr[data-tool="7"]')).to_have_count(0)
    assert "T7" not in (machine.folder / "test.tbl").read_text()


def work_offsets_are_picked_and_set(page, machine: Machine) -> None:  # type: ignore[no-untyped-def]
    page.click('#views [data-view="offsets"]')
    g55 = page.locator('#offsets tr[data-system="G55"]')
    g55.get_by_role("button", name="Use").click()
    machine.until(lambda s: s.g5x_index == 2)
    expect(page.locator("#offsets tr.active th")).to_contain_text("G55")
    g55.locator("td.editable").first.click()  # X
    page.locator("#modal input").fill("5")
    page.locator("#modal").get_by_role("button", name="OK").click()
    machine.until(lambda s: s.g5x_offset[0] == pytest.approx(5.0))
    expect(g55.locator("td").first).to_have_text("5.000")
    page.select_option("#touch-system", "G55")
    page.get_by_role("button", name="Touch off Y").click()
    page.locator("#modal input").fill("1,5")
    page.locator("#modal").get_by_role("button", name="OK").click()
    page.click('#views [data-view="run"]')
    expect(work(page, "Y")).to_have_text("1.500")
    expect(page.locator("#g5x")).to_have_value("G55")
    page.select_option("#g5x", "G54")  # the picker in the DRO
    machine.until(lambda s: s.g5x_index == 1)


def units_theme_keyboard_sheet_and_editor(page, shots: Path) -> None:  # type: ignore[no-untyped-def]
    mdi(page, "G0 X25.4")
    expect(work(page, "X")).to_have_text("25.400")
    page.click("#units")
    expect(work(page, "X")).to_have_text("1.0000")  # inches, for display only
    page.click("#units")
    expect(work(page, "X")).to_have_text("25.400")
    page.click("#theme")
    expect(page.locator("html")).to_have_attribute("data-theme", "light")
    page.screenshot(path=str(shots / "run-light-1280x800.png"))
    page.click("#theme")
    page.locator("body").press("?")
    expect(page.locator("#modal .shortcuts")).to_contain_text("STOP: abort everything")
    page.screenshot(path=str(shots / "keyboard-sheet.png"))
    page.locator("#modal").get_by_role("button", name="Close").click()
    page.click('#views [data-view="editor"]')
    page.fill("#editor-file", "part.ngc")
    page.click("#editor-load")
    expect(page.locator("#editor-text")).to_have_value(re.compile("G3 X3 Y2 I1 F600"))
    page.fill("#editor-text", "G21\nG0 X1\nG999\nG1 X2 F100\nM2\n")
    page.click("#editor-check")
    expect(page.locator("#editor-errors li")).to_have_text(["line 3: G-code out of range"])
    expect(page.locator("#editor-gutter")).to_have_attribute("data-errors", "3")
    page.click('#views [data-view="run"]')


def every_view_at_every_size(page, shots: Path) -> None:  # type: ignore[no-untyped-def]
    """Screenshots of each view at each size; E-STOP and STOP always in view, nothing
    wider than the window, the DRO's buttons whole."""
    page.select_option("#program-list", "part.ngc")
    page.click("#program-open")
    expect(page.locator(".listing-row .code").nth(2)).to_have_text("G3 X3 Y2 I1 F600")
    expect(page.locator("#preview")).to_have_attribute("data-drawn", re.compile("[1-9]"))
    expect(page.locator("#analysis")).to_contain_text("estimated run time")
    for name, (width, height) in SIZES.items():
        page.set_viewport_size({"width": width, "height": height})
        for view in VIEWS:
            page.click(f'#views [data-view="{view}"]')
            page.wait_for_function("document.fonts.status === 'loaded'")
            page.screenshot(path=str(shots / f"{view}-{name}.png"))
            for button in ("#estop", "#abort"):
                box = page.locator(button).bounding_box()
                assert box is not None and box["x"] >= 0 and box["x"] + box["width"] <= width
                assert box["y"] >= 0 and box["y"] + box["height"] <= height, (name, view, button)
            assert page.evaluate("document.documentElement.scrollWidth") <= width, (name, view)
            clipped = page.evaluate(  # tables whose right part would need scrolling
                "[...document.querySelectorAll('.view:not([hidden]) .table-box')]"
                ".filter((box) => box.scrollWidth > box.clientWidth + 1).length"
            )
            assert clipped == 0, (name, view)
        page.click('#views [data-view="run"]')
        if width >= 1024:  # listing and preview side by side, both whole in the window
            for part in ("#listing", "#preview"):
                box = page.locator(part).bounding_box()
                assert box["height"] > 100 and box["y"] + box["height"] <= height, (name, part)
        page.evaluate("window.scrollTo(0, document.body.scrollHeight)")  # the tablet scrolls
        for button in ("#estop", "#abort"):  # ... under a header that stays
            assert page.locator(button).bounding_box()["y"] >= 0
        page.evaluate("window.scrollTo(0, 0)")
        for touch in page.locator("#dro button.touch").all():
            box, panel = touch.bounding_box(), page.locator(".dro-panel").bounding_box()
            assert box["x"] + box["width"] <= min(width, panel["x"] + panel["width"]), name
    page.set_viewport_size({"width": 1280, "height": 800})


def the_machine_goes(page, machine: Machine, shots: Path) -> None:  # type: ignore[no-untyped-def]
    """This server owns message pins of the machine's HAL, so the machine's shut-down
    stops it too (as LinuxCNC's unload all stops user components): the page shows that
    nothing answers and takes no command. (The 200,000-line test sees a controller go
    while its server stays, and come back.) First F1, E-stop from the keyboard."""
    page.keyboard.press("F1")
    machine.until(lambda s: s.task_state == cnc.STATE_ESTOP)
    expect(page.locator("#state")).to_have_text("E-STOP")
    machine.stop()
    expect(page.locator("#state")).to_have_text("OFFLINE")
    expect(page.locator("#offline")).to_contain_text("The web server does not answer")
    expect(page.locator("#offline")).to_contain_text("Commands are disabled")
    assert page.locator("#home-all").evaluate("e => getComputedStyle(e).pointerEvents") == "none"
    page.screenshot(path=str(shots / "state-offline.png"))


# ================================================================== a big program
LEVEL_OF_DETAIL = """async () => {
  // A 10 mm square in 0.1 mm feeds, a rapid in ten steps, a 5 mm circle in 1 degree
  // feeds; each point's line is its index. Given in two pieces, as a page receives it.
  const { Decimator } = await import("/static/js/lod.js");
  const points = [];
  const corners = [[0, 0], [10, 0], [10, 10], [0, 10], [0, 0]];
  for (let side = 0; side < 4; side++) {
    const [a, b] = [corners[side], corners[side + 1]];
    for (let i = side ? 1 : 0; i <= 100; i++) {
      points.push([a[0] + (b[0] - a[0]) * i / 100, a[1] + (b[1] - a[1]) * i / 100, 0, 1]);
    }
  }
  for (let i = 1; i <= 10; i++) points.push([2.5 * i, 0.5 * i, 0.5 * i, 0]);
  for (let i = 1; i <= 360; i++) {
    const angle = Math.PI / 2 - i * Math.PI / 180;
    points.push([25 + 5 * Math.cos(angle), 5 * Math.sin(angle), 5, 1]);
  }
  const records = new ArrayBuffer(16 * points.length);
  const floats = new Float32Array(records), words = new Uint32Array(records);
  points.forEach(([x, y, z, kind], i) => {
    floats.set([x, y, z], 4 * i);
    words[4 * i + 3] = (i << 1) | kind;
  });
  const decimator = new Decimator(0.01);
  const half = 16 * 250;
  decimator.add(records.slice(0, half));
  decimator.add(records.slice(half));
  const keptWords = new Uint32Array(decimator.kept().slice().buffer);
  const kept = [];
  for (let i = 3; i < keptWords.length; i += 4) kept.push(keptWords[i] >> 1);
  // how far each point is from the line drawn instead
  let farthest = 0;
  for (let k = 0; k + 1 < kept.length; k++) {
    const a = points[kept[k]], b = points[kept[k + 1]];
    for (let i = kept[k] + 1; i < kept[k + 1]; i++) {
      const p = points[i];
      const d = [0, 1, 2].map((n) => b[n] - a[n]), q = [0, 1, 2].map((n) => p[n] - a[n]);
      const length = d[0] ** 2 + d[1] ** 2 + d[2] ** 2;
      const t = Math.max(0, Math.min(1, (q[0] * d[0] + q[1] * d[1] + q[2] * d[2]) / length));
      farthest = Math.max(farthest, Math.hypot(q[0] - t * d[0], q[1] - t * d[1], q[2] - t * d[2]));
    }
  }
  return { total: points.length, kept, farthest };
}"""


def the_level_of_detail_keeps_the_shape(page) -> None:  # type: ignore[no-untyped-def]
    """What the preview draws while the view turns (js/lod.js): corners and the ends of
    rapids kept, every point dropped within the tolerance, far fewer points."""
    found = page.evaluate(LEVEL_OF_DETAIL)
    kept = found["kept"]
    assert {0, 100, 200, 300, 400, 410, found["total"] - 1} <= set(kept)  # corners, rapid
    assert found["farthest"] <= 0.01 + 1e-5
    assert len(kept) < found["total"] / 8


TURNING_LEVEL = """async () => {
  // a 10,000-point spiral cut to 500 points at most; a card's pace while the view turns
  const { levelWithin } = await import("/static/js/lod.js");
  const { TurnPace } = await import("/static/js/renderer.js");
  const records = new ArrayBuffer(16 * 10000);
  const floats = new Float32Array(records), words = new Uint32Array(records);
  for (let i = 0; i < 10000; i++) {
    const angle = i * 0.01, radius = 1 + i * 0.001;
    floats.set([radius * Math.cos(angle), radius * Math.sin(angle), 0], 4 * i);
    words[4 * i + 3] = (i << 1) | 1;
  }
  const level = levelWithin([records], 1e-6, 500);
  const keptWords = new Uint32Array(level.kept().slice().buffer);
  const paced = (isSlow, intervals) => {
    const pace = new TurnPace(isSlow);
    let time = 1000;
    pace.frame(time);
    for (const interval of intervals) pace.frame(time += interval);
    return pace.isSlow;
  };
  return {
    count: level.count, first: keptWords[3] >> 1, last: keptWords[keptWords.length - 1] >> 1,
    fast: paced(false, [16, 17, 90, 16, 120, 16, 16]),  // a fast card, a hand that hesitates
    paused: paced(false, [16, 3000, 16, 2500, 16, 4000]),  // ... that stops and goes on
    slow: paced(false, [16, 80, 75, 90, 85]),  // a card that cannot keep up
    software: paced(true, []),  // known slow from the start
  };
}"""


def the_turning_level_suits_the_card(page) -> None:  # type: ignore[no-untyped-def]
    """While the view turns a slow card draws a coarser level of detail (js/lod.js
    levelWithin, js/renderer.js TurnPace): at most the points asked, the ends kept; a card
    is slow when turning frames keep coming slower than it would take to look smooth."""
    found = page.evaluate(TURNING_LEVEL)
    assert 4 < found["count"] <= 500
    assert (found["first"], found["last"]) == (0, 9999)
    assert not found["fast"]
    assert not found["paused"]
    assert found["slow"]
    assert found["software"]


def big_program(path: Path, lines: int) -> None:
    """A Lissajous of ``lines`` short feeds at 3000 mm/min within the test mill's limits."""
    out = ["G21 G90 G64 F3000", "G0 Z1", "G0 X0 Y9", "G1 Z-0.5 F600", "F3000"]
    for n in range(lines):
        t = n / lines * 2 * math.pi * (lines // 2000)
        out.append(f"G1 X{40 * math.sin(3 * t):.4f} Y{30 * math.sin(2 * t + 0.3):.4f}")
    path.write_text("\n".join([*out, "G0 Z5", "M2"]) + "\n")


@pytest.mark.timeout(600)
@pytest.mark.parametrize("machine", [False], indirect=True)  # no message pins
def test_a_200000_line_program_loads_draws_runs_and_stops(
    machine: Machine, page_url: str, browser, procs: Processes
) -> None:
    """The listing shows every line (virtual), the preview draws every move (WebGL), and
    STOP, pressed while the preview follows the run, brings the machine to rest. Then the
    controller goes while the server stays: the page says so, refuses commands, and comes
    back by itself."""
    shots = artifacts()
    program = machine.folder / "big.ngc"
    big_program(program, 200_000)
    page = open_page(browser, page_url)
    bring_up(page)
    page.select_option("#program-list", "big.ngc")
    page.click("#program-open")
    listing = page.locator("#listing")
    expect(listing).to_have_attribute("data-lines", "200007")
    expect(page.locator("#preview")).to_have_attribute("data-drawn", "200005")
    assert page.locator(".listing-row").count() < 100  # only the lines in view exist
    the_level_of_detail_keeps_the_shape(page)
    the_turning_level_suits_the_card(page)
    preview = page.locator("#preview")  # turned: drawn simplified, then whole again
    frames = int(preview.get_attribute("data-frames"))
    box = preview.bounding_box()
    page.mouse.move(box["x"] + box["width"] / 2, box["y"] + box["height"] / 2)
    page.mouse.down()
    page.mouse.move(box["x"] + box["width"] / 2 + 60, box["y"] + box["height"] / 2, steps=6)
    page.mouse.up()
    expect(preview).to_have_attribute("data-drawn", "200005")
    assert int(preview.get_attribute("data-frames")) > frames
    assert 0 < int(preview.get_attribute("data-turning-lod")) <= 16_000
    listing.evaluate("e => { e.scrollTop = e.scrollHeight; }")
    expect(page.locator(".listing-row .code").last).to_have_text("M2")
    page.click('[data-camera="top"]')
    page.click("#run")
    machine.until(lambda s: s.current_vel > 0 and s.motion_line > 10)
    expect(page.locator("#state")).to_have_text("RUNNING")
    expect(page.locator(".listing-row.current")).to_have_count(1)  # followed
    # its estimate takes minutes: meanwhile the share of the lines run
    expect(page.locator("#progress-text")).to_contain_text(re.compile(r"\d\.\d % of the lines"))
    page.keyboard.press("p")  # pause: one word, never "PAUSED (paused)"
    expect(page.locator("#state")).to_have_text("PAUSED")
    expect(page.locator("#state-detail")).to_contain_text("Resume to continue")
    page.keyboard.press("s")
    expect(page.locator("#state")).to_have_text("RUNNING")
    page.screenshot(path=str(shots / "big-running.png"))
    box = page.locator("#abort").bounding_box()
    page.mouse.move(box["x"] + box["width"] / 2, box["y"] + box["height"] / 2)
    page.mouse.down()  # STOP acts on the press
    machine.until(lambda s: s.current_vel == 0 and s.interp_state == cnc.INTERP_IDLE)
    page.mouse.up()
    machine.stat.poll()
    assert machine.stat.motion_line < 200_000  # stopped, not finished
    expect(page.locator("#state")).to_have_text("READY")
    machine.stop()
    expect(page.locator("#state")).to_have_text("OFFLINE")
    expect(page.locator("#offline")).to_contain_text("The controller is not running")
    expect(page.locator("#dro tbody tr.is-homed .homed").first).to_have_css(
        "color", "rgba(0, 0, 0, 0)"
    )  # nothing says "homed" any more
    assert page.locator("#run").evaluate("e => getComputedStyle(e).pointerEvents") == "none"
    page.screenshot(path=str(shots / "state-controller-offline.png"))
    with launched(procs, machine.folder):
        expect(page.locator("#state")).to_have_text("E-STOP")  # back by itself
    assert page.errors == []  # type: ignore[attr-defined]
