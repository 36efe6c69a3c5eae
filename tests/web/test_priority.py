"""The web server's scheduling (cnc/ui/web/priority.py): its event loop thread at the
lowest realtime priority when allowed, what it starts ordinary again, a job's preview and
estimate below everything, in a session of their own."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

from cnc.ui.web.priority import ESTIMATE_NICE, JOB_NICE

PROBE = """
import json, os, threading
from cnc.ui.web.priority import raise_loop_priority, raise_worker_priority
problem = raise_loop_priority()
seen = {}
def worker():
    raise_worker_priority()
    seen["worker"] = [os.sched_getscheduler(0), os.getpriority(os.PRIO_PROCESS, 0)]
thread = threading.Thread(target=worker)
thread.start(); thread.join()
child = os.fork()
if child == 0:
    os._exit(os.sched_getscheduler(0) & 0xFF)
_, status = os.waitpid(child, 0)
print(json.dumps({"problem": problem, "loop": os.sched_getscheduler(0),
                  "rt_priority": os.sched_getparam(0).sched_priority, "worker": seen["worker"],
                  "child_policy": os.waitstatus_to_exitcode(status)}))
"""


def test_the_event_loop_runs_realtime_and_what_it_starts_does_not() -> None:
    done = subprocess.run(
        [sys.executable, "-c", PROBE], capture_output=True, text=True, timeout=60, check=True
    )
    found = json.loads(done.stdout)
    if found["problem"] is None:  # (allowed: root or CAP_SYS_NICE, as in CI)
        assert found["loop"] & ~0x40000000 == 1  # SCHED_FIFO (| SCHED_RESET_ON_FORK)
        assert found["rt_priority"] == 1
        assert found["worker"] == [0, -10]  # SCHED_OTHER at niceness -10
        assert found["child_policy"] == 0  # a job or filter: SCHED_OTHER
    else:
        assert "realtime priority" in found["problem"]
        assert found["loop"] == 0


JOB_PROBE = """
import json, os, sys
from pathlib import Path
import cnc.ui.estimate, cnc.ui.web.preview
from cnc.ui.web import jobs
seen = {}
def where():
    group = Path("/proc/self/autogroup")
    return {"nice": os.getpriority(os.PRIO_PROCESS, 0), "is_leader": os.getsid(0) == os.getpid(),
            "group": group.read_text().split()[-1] if group.exists() else None}
real_preview = cnc.ui.web.preview.preview
def preview(*args, **kwargs):
    seen["preview"] = where()
    return real_preview(*args, **kwargs)
def estimate(*args, **kwargs):
    seen["estimate"] = where()
    return cnc.ui.estimate.Estimate()
cnc.ui.web.preview.preview = preview
cnc.ui.estimate.estimate = estimate
status = jobs.main([sys.argv[1]])
print(json.dumps(seen | {"status": status}))
"""


def test_a_job_s_preview_and_estimate_yield_to_everything_else(tmp_path: Path) -> None:
    """In a session of its own (with the kernel's autogroup scheduling, niceness counts
    only within a session), the preview at JOB_NICE, the estimate lower still."""
    machine = Path(__file__).parents[1] / "halui" / "machine"
    (tmp_path / "p.ngc").write_text("G0 X1\nG1 X2 F100\nM2\n")
    spec = {
        "kind": "preview",
        "folder": str(tmp_path),
        "program": str(tmp_path / "p.ngc"),
        "ini": str(machine / "mill.ini"),
    }
    (tmp_path / "spec.json").write_text(json.dumps(spec))
    done = subprocess.run(
        [sys.executable, "-c", JOB_PROBE, str(tmp_path / "spec.json")],
        capture_output=True, text=True, timeout=60, check=True,
    )  # fmt: skip
    found = json.loads(done.stdout.splitlines()[-1])
    assert found["status"] == 0, done.stderr
    assert found["preview"]["nice"] == JOB_NICE
    assert found["estimate"]["nice"] == ESTIMATE_NICE
    assert found["preview"]["is_leader"]
    if found["preview"]["group"] is not None and os.geteuid() == 0:  # (else rate-limited)
        assert (found["preview"]["group"], found["estimate"]["group"]) == ("5", "15")


WATCH_PROBE = """
import asyncio, json, sys, threading
from cnc.ui.web.priority import watch_jobs_without_threads
watch_jobs_without_threads()
async def job():
    process = await asyncio.create_subprocess_exec(
        sys.executable, "-c", "import time; time.sleep(0.3)"
    )
    threads = threading.active_count()
    return threads, await process.wait()
print(json.dumps(asyncio.run(job())))
"""


def test_the_loop_starts_no_thread_to_watch_a_job() -> None:
    """A new thread makes the realtime loop wait until it has run once: a job's end comes
    through a pidfd instead (Python 3.11's asyncio started a thread for each)."""
    done = subprocess.run(
        [sys.executable, "-c", WATCH_PROBE], capture_output=True, text=True, timeout=60,
        check=True,
    )  # fmt: skip
    threads, status = json.loads(done.stdout)
    assert (threads, status) == (1, 0)
