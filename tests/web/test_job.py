"""Program runs as the page shows them (cnc/ui/web/job.py): progress from the time
estimate, remaining time, how a run ended, the history file."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from cnc.ui.estimate import reached_times
from cnc.ui.web.job import JobTracker, end_text
from cnc.ui.web.jobs import ProgramAnalysis

FILE = "/nc/part.ngc"


def analysis(is_done: bool = True) -> ProgramAnalysis:
    """A 100 s program of 10 lines: line n starts moving at 10 * (n - 1) s; it ends on 11."""
    found = ProgramAnalysis(1, FILE, Path(FILE), 0, Path("/nonexistent"))
    if is_done:
        found.preview = {"end_line": 11, "error": None}
        found.estimate_summary = {"total_s": 100.0}
        found.reached_s = reached_times(np.array([np.nan] + [10.0 * n for n in range(10)]))
    return found


def status(interp: str = "READING", line: int = 0, **extra) -> dict:  # type: ignore[no-untyped-def]
    return {"is_connected": True, "task_mode": "AUTO", "interp_state": interp, "file": FILE,
            "motion_line": line, "current_line": line, "is_paused": False} | extra  # fmt: skip


def test_progress_and_remaining_time_come_from_the_estimate(tmp_path: Path) -> None:
    tracker = JobTracker(tmp_path / "jobs.json")
    program = analysis()
    assert tracker.update(status("IDLE"), program, 0.0) == (None, [])
    job, _ = tracker.update(status(line=1), program, 0.0)
    assert job["progress"] == 0.0 and job["estimate_s"] == 100.0
    job, _ = tracker.update(status(line=6), program, 50.0)  # on time: line 6 at 50 s
    assert (job["progress"], job["remaining_s"], job["elapsed_s"]) == (0.5, 50, 50)
    job, _ = tracker.update(status(line=6, is_paused=True), program, 70.0)  # 20 s paused
    job, _ = tracker.update(status(line=7), program, 130.0)  # then half speed: 110 s for 60
    assert job["progress"] == 0.6 and job["elapsed_s"] == 130
    assert job["remaining_s"] == round(40 * 110 / 60)  # the rest at the pace so far
    job, messages = tracker.update(status("IDLE", line=11), program, 140.0)
    assert job is None
    assert messages[0] == {
        "type": "notice",
        "kind": "text",
        "text": "part.ngc finished in 2:00 (estimate 1:40, +20 %; paused 0:20)",
    }
    tracker.close()  # (saved by a thread of its own)
    saved = json.loads((tmp_path / "jobs.json").read_text())
    assert saved == messages[1]["jobs"]
    assert saved[0]["result"] == "finished" and saved[0]["run_s"] == pytest.approx(120)


def test_a_run_ended_before_its_preview_waits_for_the_end_line() -> None:
    tracker = JobTracker()
    waiting = analysis(is_done=False)
    tracker.update(status(line=1), waiting, 0.0)
    tracker.update(status("IDLE", line=11), waiting, 1.0)
    assert tracker.update(status("IDLE", line=11), waiting, 2.0) == (None, [])  # not yet
    _, messages = tracker.update(status("IDLE", line=11), analysis(), 3.0)
    assert tracker.history[0]["result"] == "finished"
    assert messages[0]["text"].startswith("part.ngc finished in 0:01")


def test_an_aborted_run_is_stopped_and_one_with_an_error_failed() -> None:
    tracker = JobTracker()
    program = analysis()
    tracker.update(status(line=3), program, 0.0)
    _, messages = tracker.update(status("IDLE", line=3), program, 25.0)
    assert messages[0]["text"] == "part.ngc stopped after 0:25 (estimate 1:40)"
    tracker.update(status(line=3), program, 30.0)
    tracker.note_error()
    tracker.update(status("IDLE", line=4), program, 31.0)
    assert [job["result"] for job in tracker.history] == ["error", "stopped"]


def test_without_an_estimate_the_run_shows_its_time_only() -> None:
    tracker = JobTracker()
    program = analysis(is_done=False)
    job, _ = tracker.update(status(line=2), program, 0.0)
    assert job == {"file": FILE, "elapsed_s": 0, "progress": None, "progress_by": None,
                   "remaining_s": None, "estimate_s": None}  # fmt: skip


def test_until_the_estimate_is_done_progress_counts_lines() -> None:
    """A program of a million lines takes minutes to estimate: meanwhile the share of its
    lines run (from the start line to the preview's end line)."""
    tracker = JobTracker()
    program = analysis(is_done=False)
    program.preview = {"end_line": 11, "error": None}  # the preview is done, not the estimate
    tracker.expect_start(1, 0.0)
    job, _ = tracker.update(status(line=1), program, 0.0)
    assert (job["progress"], job["progress_by"], job["remaining_s"]) == (0.0, "lines", None)
    job, _ = tracker.update(status(line=6), program, 5.0)
    assert (job["progress"], job["progress_by"]) == (0.5, "lines")
    done = analysis()  # the estimate arrives: its time from then on
    job, _ = tracker.update(status(line=6), done, 6.0)
    assert job["progress_by"] == "time" and job["estimate_s"] == 100.0


def test_the_end_text_says_what_happened() -> None:
    tracker = JobTracker()
    tracker.update(status(line=2), None, 0.0)
    job = tracker.job
    job.run_s, job.result = 3725.0, "finished"
    assert end_text(job) == "part.ngc finished in 1:02:05"


def test_progress_moves_on_within_a_long_line() -> None:
    """One line of 100 s: the progress follows the time run on it (at most its length)."""
    program = analysis()
    program.reached_s = reached_times(np.array([np.nan, np.nan, 0.0, 100.0]))
    program.estimate_summary = {"total_s": 100.0}
    tracker = JobTracker()
    tracker.update(status(line=2), program, 0.0)
    job, _ = tracker.update(status(line=2), program, 25.0)
    assert job["progress"] == 0.25 and job["remaining_s"] == 75
    job, _ = tracker.update(status(line=2), program, 140.0)  # slower than estimated
    assert job["progress"] == 1.0
