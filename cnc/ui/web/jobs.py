"""Work on programs that must never slow the server: preview, time estimate, editor checks.

Each job is a process of its own (``python -m cnc.ui.web.jobs SPEC.json``), run at a
lower priority (``priority.JOB_NICE``), so that neither its CPU time nor its memory can
delay a STOP the server must pass on, and a job that is no longer wanted is simply
killed. A job writes its results into its folder; the server (``ProgramJobs``, in its
event loop) looks at the folder every display cycle and tells the pages what is new:

- ``preview.bin``: the toolpath (``preview.RECORD``s), appended while the interpreter runs,
  so a page draws a long program while it loads; ``preview.json`` when it is complete.
- ``estimate-progress.json``: the machine time the estimate has reached so far;
  ``estimate.npy`` (when each line starts moving) and ``estimate.json`` when it is done.
- ``check.json``: an editor check's errors.
- ``failed.json``: the job itself failed (a bug, or a bad INI), with the reason.

Every result file is written whole (``atomic_write_text``) or appended in whole records.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import math
import os
import shutil
import sys
import tempfile
import threading
import time
import traceback
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from cnc.atomicfile import atomic_write_text
from cnc.ui.web.priority import at_estimate_priority, at_job_priority

PROGRESS_EVERY_S = 5.0  # of machine time, between two estimate-progress.json
RECORD_SIZE = 16  # preview.RECORD.size (imported lazily: the server need not load it)
PARENT_CHECK_S = 1.0


# ------------------------------------------------------------------ in the job's process
def _write_json(path: Path, value: Any) -> None:
    atomic_write_text(path, json.dumps(value))


def run_job(spec: dict[str, Any]) -> None:
    """Do what ``spec`` asks; results in ``spec["folder"]``."""
    from cnc.ini import IniFile
    from cnc.ui.estimate import estimate
    from cnc.ui.web.preview import preview

    folder = Path(spec["folder"])
    ini_path = spec.get("ini")
    ini = IniFile.load(ini_path) if ini_path else None
    options = {
        "units_per_mm": spec.get("units_per_mm", 1.0),
        "parameter_file": spec.get("parameter_file") or "",
        "tool_table": spec.get("tool_table"),
        "ini": ini,
    }
    if spec["kind"] == "check":
        result = preview(spec["program"], lambda chunk: None, is_checking_all=True, **options)
        _write_json(folder / "check.json", result)
        return
    with open(folder / "preview.bin", "ab") as out:

        def sink(chunk: bytes) -> None:
            out.write(chunk)
            out.flush()  # visible to the server at once

        result = preview(spec["program"], sink, **options)
    _write_json(folder / "preview.json", result)
    if not ini_path:
        return  # no machine limits: no estimate
    next_report = [PROGRESS_EVERY_S]

    def progress(machine_s: float) -> None:
        if machine_s >= next_report[0]:
            next_report[0] = machine_s + PROGRESS_EVERY_S
            _write_json(folder / "estimate-progress.json", {"machine_s": round(machine_s, 1)})

    at_estimate_priority()
    found = estimate(spec["program"], ini_path, start=spec.get("start"), progress=progress)
    import numpy as np

    np.save(folder / "estimate.npy", found.line_start_s)
    _write_json(folder / "estimate.json", found.summary())  # last: the estimate is done


def _end_with_the_server(server: int) -> None:
    """A job of a server that died (even by SIGKILL) ends too: nobody wants its result."""
    while True:
        time.sleep(PARENT_CHECK_S)
        if os.getppid() != server:
            os._exit(1)


def main(argv: list[str]) -> int:
    """``python -m cnc.ui.web.jobs SPEC.json``."""
    at_job_priority()
    threading.Thread(target=_end_with_the_server, args=(os.getppid(),), daemon=True).start()
    spec = json.loads(Path(argv[0]).read_text())
    try:
        run_job(spec)
    except Exception as exc:  # reported to the pages; never a silent end
        problem = f"{type(exc).__name__}: {exc}"
        _write_json(Path(spec["folder"]) / "failed.json", {"message": problem})
        traceback.print_exc()
        return 1
    return 0


# ------------------------------------------------------------------ in the server
@dataclass
class ProgramAnalysis:
    """The preview and estimate of one program (``path``, as task opened it)."""

    number: int  # pages ask for data by this number (a newer program has another)
    file: str  # what stat.file says
    path: Path
    mtime_ns: int
    folder: Path
    process: asyncio.subprocess.Process | None = None
    preview: dict[str, Any] | None = None  # preview.json, once complete
    estimate_summary: dict[str, Any] | None = None  # estimate.json
    reached_s: Any = None  # estimate.reached_times of estimate.npy
    estimate_progress_s: float = 0.0
    failure: str | None = None
    _last_state: dict[str, Any] = field(default_factory=dict)

    @property
    def preview_points(self) -> int:
        """Whole records written so far."""
        try:
            return (self.folder / "preview.bin").stat().st_size // RECORD_SIZE
        except OSError:
            return 0

    def refresh(self) -> None:
        """Read what the job finished since the last look."""
        folder = self.folder
        if self.preview is None:
            self.preview = _read_json(folder / "preview.json")
        if self.estimate_summary is None:
            summary = _read_json(folder / "estimate.json")
            if summary is not None:
                import numpy as np

                from cnc.ui.estimate import reached_times

                self.reached_s = reached_times(np.load(folder / "estimate.npy"))
                self.estimate_summary = summary
            else:
                progress = _read_json(folder / "estimate-progress.json")
                if progress is not None:
                    self.estimate_progress_s = progress["machine_s"]
        if self.failure is None:
            failed = _read_json(folder / "failed.json")
            if failed is not None:
                self.failure = failed["message"]

    def state(self) -> dict[str, Any]:
        """What the pages are told (the "program" message)."""
        preview = self.preview or {}
        return {
            "number": self.number,
            "file": self.file,
            "preview_points": self.preview_points,
            "is_preview_done": self.preview is not None,
            "preview_error": preview.get("error"),
            "is_truncated": preview.get("is_truncated", False),
            "end_line": preview.get("end_line"),
            "estimate": self.estimate_summary,
            "estimate_progress_s": self.estimate_progress_s,
            "failure": self.failure,
        }

    def time_at(self, line: int) -> float | None:
        """When the machine reaches ``line`` by the estimate (None before it is done)."""
        if self.reached_s is None:
            return None
        from cnc.ui.estimate import time_at

        return time_at(self.reached_s, line)

    def span_of(self, line: int) -> tuple[float, float] | None:
        """When ``line`` starts moving and when the next one does (None without estimate)."""
        if self.reached_s is None:
            return None
        from cnc.ui.estimate import line_span

        return line_span(self.reached_s, line)

    @property
    def total_s(self) -> float | None:
        return None if self.estimate_summary is None else self.estimate_summary["total_s"]


def _read_json(path: Path) -> Any:
    try:
        return json.loads(path.read_text())
    except (OSError, ValueError):
        return None


class ProgramJobs:
    """Starts and watches the jobs; used from the server's event loop only."""

    def __init__(self, settings: Any) -> None:
        self.settings = settings
        self._root = Path(tempfile.mkdtemp(prefix="cnc-web-jobs-"))
        self.current: ProgramAnalysis | None = None
        self._count = 0
        self._processes: set[asyncio.subprocess.Process] = set()

    def _spec(self, kind: str, program: Path, folder: Path) -> dict[str, Any]:
        settings = self.settings
        return {
            "kind": kind,
            "program": str(program),
            "folder": str(folder),
            "ini": settings.ini_file,
            "units_per_mm": settings.units_per_mm,
            "parameter_file": str(settings.parameter_file or ""),
            "tool_table": str(settings.tool_table) if settings.tool_table else None,
        }

    async def _start(self, spec: dict[str, Any]) -> asyncio.subprocess.Process:
        spec_file = Path(spec["folder"]) / "spec.json"
        spec_file.write_text(json.dumps(spec))
        process = await asyncio.create_subprocess_exec(
            sys.executable,
            "-m",
            "cnc.ui.web.jobs",
            str(spec_file),
            stdin=asyncio.subprocess.DEVNULL,
            stdout=asyncio.subprocess.DEVNULL,
        )
        self._processes.add(process)
        return process

    def needs_analysis(self, file: str) -> bool:
        """Whether ``file`` (stat.file) is not the program analysed, or changed since. No
        file (task between programs, or none opened) keeps the last one, as AXIS shows the
        last program it loaded."""
        current = self.current
        if not file:
            return False
        if current is None or current.file != file:
            return True
        try:
            return current.path.stat().st_mtime_ns != current.mtime_ns
        except OSError:
            return False

    async def analyse(self, file: str, start: list[float] | None) -> ProgramAnalysis | None:
        """Preview and estimate ``file`` (stat.file) from machine position ``start``; the
        previous program's job is stopped. None (nothing analysed) for no file."""
        await self._drop_current()
        path = Path(file)
        if not file or not path.is_file():
            return None
        self._count += 1
        folder = self._root / str(self._count)
        folder.mkdir()
        analysis = ProgramAnalysis(self._count, file, path, path.stat().st_mtime_ns, folder)
        spec = self._spec("analyse", path, folder) | {"start": start}
        analysis.process = await self._start(spec)
        self.current = analysis
        return analysis

    async def _drop_current(self) -> None:
        current, self.current = self.current, None
        if current is None:
            return
        await self._stop(current.process)
        shutil.rmtree(current.folder, ignore_errors=True)

    async def _stop(self, process: asyncio.subprocess.Process | None) -> None:
        if process is None:
            return
        if process.returncode is None:
            with contextlib.suppress(ProcessLookupError):
                process.kill()
        await process.wait()
        self._processes.discard(process)

    def poll(self) -> dict[str, Any] | None:
        """The current program's state if it changed since the last poll (reads files:
        call it from a worker thread)."""
        current = self.current
        if current is None:
            return None
        current.refresh()
        state = current.state()
        if state == current._last_state:
            return None
        current._last_state = state
        return state

    async def check(self, text: str) -> dict[str, Any]:
        """Run the preview interpreter over ``text`` (an editor's), every error reported:
        {"errors": [{"line", "message"}], "points", ...}."""
        folder = Path(tempfile.mkdtemp(prefix="check-", dir=self._root))
        try:
            program = folder / "program.ngc"
            program.write_text(text, encoding="utf-8")
            process = await self._start(self._spec("check", program, folder))
            try:
                await process.wait()
            finally:
                await self._stop(process)
            found = _read_json(folder / "check.json")
            if found is None:
                failed = _read_json(folder / "failed.json") or {"message": "the check failed"}
                raise RuntimeError(failed["message"])
            return found
        finally:
            shutil.rmtree(folder, ignore_errors=True)

    async def close(self) -> None:
        for process in list(self._processes):
            await self._stop(process)
        self.current = None
        shutil.rmtree(self._root, ignore_errors=True)


def format_duration(seconds: float) -> str:
    """1:02:03, 2:03 or 0:05."""
    total = max(0, math.floor(seconds + 0.5))
    hours, rest = divmod(total, 3600)
    minutes, secs = divmod(rest, 60)
    return f"{hours}:{minutes:02d}:{secs:02d}" if hours else f"{minutes}:{secs:02d}"


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
