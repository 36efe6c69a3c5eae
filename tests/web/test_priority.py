"""The web server's scheduling (cnc/ui/web/priority.py): its event loop thread at the
lowest realtime priority when allowed, what it starts ordinary again."""

from __future__ import annotations

import json
import subprocess
import sys

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
