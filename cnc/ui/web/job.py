"""Program runs as the operator sees them: progress, elapsed and remaining time while a
program runs, and the job history (recent runs with their times).

``JobTracker.update(status, analysis, now)`` is called with every status snapshot. A run
starts when the interpreter leaves IDLE in AUTO mode and ends when it is IDLE again. Its
progress comes from the program's time estimate (``cnc.ui.estimate``, through
``jobs.ProgramAnalysis``): the estimated time at which the machine reaches the line it
executes, over the estimated total. The remaining time is the estimate's rest, scaled by
how the run has gone so far (overrides, pauses in motion) once it has run long enough to
tell. Until the estimate is done (minutes for a program of a million lines) the progress
is the share of the program's lines run (``progress_by`` says which). At the end the page
gets a notice with the run time next to the estimate, and the run
joins the history ([DISPLAY]JOB_HISTORY_FILE, JSON, written atomically; the newest first).

A run is "finished" when the interpreter reached the program's end line (the preview's:
a run that ends before the preview is known waits for it, at most ``END_WAIT_S``), "error"
when an operator error arrived during it, else "stopped" (aborted).
"""

from __future__ import annotations

import contextlib
import json
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

from cnc.atomicfile import atomic_write_text
from cnc.ui.web.jobs import ProgramAnalysis, format_duration
from cnc.ui.web.priority import raise_worker_priority

HISTORY_KEPT = 200
MIN_CORRECTION_S = 20.0  # estimated seconds run before the remaining time is corrected
CORRECTION_LIMITS = (0.25, 4.0)  # a correction outside these says more about a stop
END_WAIT_S = 60.0  # how long an ended run waits for the program's end line
START_HINT_S = 10.0  # a run asked for this long ago (or earlier) is not the one starting


@dataclass
class JobRecord:
    """One run of a program."""

    file: str
    started: float  # time.time()
    run_s: float = 0.0  # running, pauses left out
    paused_s: float = 0.0
    estimate_s: float | None = None  # the estimate for the part run (from start_line)
    result: str = "running"  # finished, stopped, error
    start_line: int = 0
    last_line: int = 0


class JobTracker:
    def __init__(self, history_file: Path | None = None) -> None:
        self.history_file = history_file
        self.history: list[dict[str, Any]] = _read_history(history_file)
        self.job: JobRecord | None = None
        self._ended: JobRecord | None = None  # waits for the end line to say how it ended
        self._ended_at = 0.0
        self._is_ended_with_error = False
        self._last_now = 0.0
        self._expected_start = (0, 0.0)  # (line, when asked): see expect_start
        self._line, self._line_entered_s = -1, 0.0  # the line running, since (run time)
        self._is_error_seen = False
        self._start_time_s = 0.0  # the estimate's time at the start line
        self._saver = ThreadPoolExecutor(
            1, thread_name_prefix="cnc-web-history", initializer=raise_worker_priority
        )

    def note_error(self) -> None:
        """An operator error arrived (the run, if any, ends as "error")."""
        if self.job is not None:
            self._is_error_seen = True

    def update(
        self, status: dict[str, Any], analysis: ProgramAnalysis | None, now: float
    ) -> tuple[dict[str, Any] | None, list[dict[str, Any]]]:
        """The "job" status entry (None: no run), and messages for the pages (a notice
        and the new history when a run ends)."""
        is_running = (
            status.get("is_connected", False)
            and status.get("task_mode") == "AUTO"
            and status.get("interp_state") not in (None, "IDLE")
        )
        line = status.get("motion_line") or status.get("current_line") or 0
        messages: list[dict[str, Any]] = []
        if self.job is not None:
            self._count_time(self.job, status, now)
            if status.get("is_connected"):
                self.job.last_line = max(self.job.last_line, status.get("current_line") or 0)
        if is_running and self.job is None:
            messages += self._finish(analysis, now, is_forced=True)
            self._start(status, analysis, now)
        elif not is_running and self.job is not None:
            self._ended, self.job = self.job, None
            self._ended_at, self._is_ended_with_error = now, self._is_error_seen
        messages += self._finish(analysis, now)
        job = self.job
        if job is None:
            return None, messages
        return self._progress(job, analysis, line), messages

    def _count_time(self, job: JobRecord, status: dict[str, Any], now: float) -> None:
        """The time since the last update: paused or running."""
        elapsed = now - self._last_now
        self._last_now = now
        if status.get("is_paused"):
            job.paused_s += elapsed
        else:
            job.run_s += elapsed

    def expect_start(self, line: int, now: float) -> None:
        """A run from ``line`` was asked for (by a page of this server): the next run
        starts there (the first status of a run may show a later line already)."""
        self._expected_start = (line, now)

    def _start(self, status: dict[str, Any], analysis: ProgramAnalysis | None, now: float) -> None:
        file = status.get("file") or ""
        line, asked_at = self._expected_start
        self._expected_start = (0, 0.0)
        if now - asked_at > START_HINT_S:
            line = 0  # started elsewhere (another UI, halui): from the start, as usual
        self.job = JobRecord(file=file, started=time.time(), start_line=line)
        self._last_now = now
        self._is_error_seen = False
        self._start_time_s = 0.0
        if analysis is not None and analysis.file == file:
            self._start_time_s = analysis.time_at(line) or 0.0

    def _progress(
        self, job: JobRecord, analysis: ProgramAnalysis | None, line: int
    ) -> dict[str, Any]:
        shown: dict[str, Any] = {
            "file": job.file,
            "elapsed_s": round(job.run_s + job.paused_s),
            "progress": None,
            "progress_by": None,  # "time" (the estimate's) or "lines" (until it is done)
            "remaining_s": None,
            "estimate_s": None,
        }
        if analysis is None or analysis.file != job.file:
            return shown
        if analysis.total_s is None:
            end_line = (analysis.preview or {}).get("end_line")
            if not end_line or end_line <= job.start_line:
                return shown
            done = min(max(line - job.start_line, 0), end_line - job.start_line)
            return shown | {
                "progress": round(done / (end_line - job.start_line), 4),
                "progress_by": "lines",
            }
        start, end = analysis.span_of(line) or (0.0, 0.0)
        if line != self._line:  # the run time on this line counts towards its part
            self._line, self._line_entered_s = line, job.run_s
        reached = start + min(job.run_s - self._line_entered_s, end - start)
        part_s = max(analysis.total_s - self._start_time_s, 1e-9)
        done_s = min(max(reached - self._start_time_s, 0.0), part_s)
        rate = 1.0
        if done_s >= MIN_CORRECTION_S:
            low, high = CORRECTION_LIMITS
            rate = min(max(job.run_s / done_s, low), high)
        job.estimate_s = part_s
        return shown | {
            "progress": round(done_s / part_s, 4),
            "progress_by": "time",
            "remaining_s": round((part_s - done_s) * rate),
            "estimate_s": round(part_s, 1),
        }

    def _finish(
        self, analysis: ProgramAnalysis | None, now: float, is_forced: bool = False
    ) -> list[dict[str, Any]]:
        """Say how the ended run ended, once the program's end line is known (or when
        waiting longer makes no sense): a notice, and the history."""
        job = self._ended
        if job is None:
            return []
        end_line = None
        is_known = analysis is not None and analysis.file == job.file
        if is_known and analysis.preview is not None:
            end_line = analysis.preview.get("end_line")
        is_waiting = is_known and analysis.preview is None and analysis.failure is None
        if is_waiting and not is_forced and now - self._ended_at < END_WAIT_S:
            return []
        self._ended = None
        if end_line is not None and job.last_line >= end_line:
            job.result = "finished"
        elif self._is_ended_with_error:
            job.result = "error"
        else:
            job.result = "stopped"
        self.history.insert(0, asdict(job))
        del self.history[HISTORY_KEPT:]
        self._save()
        return [
            {"type": "notice", "kind": "text", "text": end_text(job)},
            {"type": "jobs", "jobs": self.history},
        ]

    def _save(self) -> None:
        """Written by a thread of its own, in order: an atomic write waits for the disk
        (fsync), which the server's event loop, reading STOPs, must never do."""
        if self.history_file is None:
            return
        self._saver.submit(_write_history, self.history_file, json.dumps(self.history, indent=1))

    def close(self) -> None:
        """Until the history saves asked for so far are on disk."""
        self._saver.shutdown(wait=True)


def _write_history(path: Path, text: str) -> None:
    # a read-only folder must not stop the UI: the history then stays in memory
    with contextlib.suppress(OSError):
        atomic_write_text(path, text)


def end_text(job: JobRecord) -> str:
    """ "part.ngc finished in 3:21 (estimate 3:15, +3 %)" and the like."""
    name = Path(job.file).name
    words = {"finished": "finished in", "stopped": "stopped after", "error": "failed after"}
    text = f"{name} {words.get(job.result, job.result)} {format_duration(job.run_s)}"
    notes = []
    if job.estimate_s:
        difference = (job.run_s - job.estimate_s) / job.estimate_s * 100
        estimate = f"estimate {format_duration(job.estimate_s)}"
        notes.append(f"{estimate}, {difference:+.0f} %" if job.result == "finished" else estimate)
    if job.paused_s >= 1:
        notes.append(f"paused {format_duration(job.paused_s)}")
    return f"{text} ({'; '.join(notes)})" if notes else text


def _read_history(path: Path | None) -> list[dict[str, Any]]:
    if path is None:
        return []
    try:
        found = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return []
    return [entry for entry in found if isinstance(entry, dict)] if isinstance(found, list) else []
