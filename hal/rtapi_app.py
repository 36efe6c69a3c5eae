"""The realtime host (LinuxCNC's rtapi_app): loads realtime components and runs HAL threads.

Run as ``python -m hal.rtapi_app [--no-rt] [--spin-us N]``; halcmd starts it on the first
``loadrt``. It listens on an abstract unix socket for commands (ping, loadrt, unloadrt,
unloadall, modules, exit), one JSON object per line, answering ``{"ok": bool, "error": str,
...}``. Pin values never pass through the socket: everyone reads and writes them in shared
memory. The host exits with its last module, like LinuxCNC's.

Each HAL thread is an OS thread that sleeps to absolute deadlines (clock_nanosleep with
TIMER_ABSTIME on CLOCK_MONOTONIC), then calls its functions in ``addf`` order. Where the
system permits (it says once when it does not), the host works like LinuxCNC's: SCHED_FIFO
at the highest priority for the fastest thread, pinned to the highest isolated CPU or else
the last CPU, memory locked, and ``/dev/cpu_dma_latency`` held at 0 so the CPUs do not doze
between periods; threads also wake ``--spin-us`` early and busy-wait to the deadline. The
``$CNC_HAL_*`` variables of hal/README.md change each of these; ``--no-rt`` (or
``CNC_HAL_NO_RT=1``) turns them all off. The garbage collector is disabled (objects made
while loading are frozen), so no collection pauses land in a period. Each thread publishes
``<thread>.time`` (pin) and ``<thread>.tmax`` (param) like LinuxCNC, plus
an overrun count (periods whose functions ran past the next deadline; ``Hal.thread_overruns``,
kept out of the parameter list so that halcmd's listings stay LinuxCNC's).
"""

from __future__ import annotations

import argparse
import contextlib
import ctypes
import gc
import importlib
import importlib.util
import json
import os
import resource
import selectors
import signal
import socket
import subprocess
import sys
import threading
import time
import traceback
from collections.abc import Callable
from pathlib import Path
from typing import Any, TextIO

from cnc.stdio import protect_output
from hal.api import RtComponent, set_shared_hal
from hal.core import HAL_BIT, HAL_OUT, HAL_RO, HAL_RW, HAL_S32, Hal, HalError
from nml.ipcnames import ipc_name
from nml.shmem import is_process_alive

CLOCK_MONOTONIC = 1
TIMER_ABSTIME = 1
MCL_CURRENT, MCL_FUTURE = 1, 2
RECOMMENDED_MEMLOCK_KIB = 20480
# the fastest thread's SCHED_FIFO priority: the highest, as LinuxCNC's uspace rtapi_app
# gives it; each slower thread gets one less
RT_PRIORITY = os.sched_get_priority_max(os.SCHED_FIFO)
S32_MAX = (1 << 31) - 1
COMPONENTS_ENV = "CNC_HAL_COMPONENTS"
# Where the host finds the realtime modules ``loadrt NAME`` loads, in order: HAL's own
# components, kinematics modules, then motion's ``motmod``. The host loads them by name
# only; nothing in HAL imports them.
MODULE_PACKAGES = ("hal.components", "motion.kinematics", "motion")
HOST_START_TIMEOUT_S = 15.0  # (how long HostClient.ensure waits for a new host)
NO_RT_ENV = "CNC_HAL_NO_RT"
SPIN_ENV = "CNC_HAL_SPIN_US"
# wake this long before each deadline and busy-wait to it (at most a quarter of the
# period, so slower threads on the same CPU still run): with the CPU kept awake, on a
# 2-vCPU VM the median lateness goes from 30-45 µs to 0 and the p99 from 60-470 µs to
# 30-75 µs (scripts/bench/hal_bench.py)
DEFAULT_SPIN_US = 100
SPIN_PERIOD_FRACTION = 4
CPU_ENV = "CNC_HAL_CPU"
PRIORITY_ENV = "CNC_HAL_PRIORITY"
ISOLATED_CPUS = Path("/sys/devices/system/cpu/isolated")
AWAKE_ENV = "CNC_HAL_KEEP_CPU_AWAKE"
CPU_LATENCY_FILE = Path("/dev/cpu_dma_latency")  # PM QoS: the wake-up latency we accept
PR_SET_TIMERSLACK = 29
M_TRIM_THRESHOLD, M_MMAP_MAX, M_ARENA_MAX = -1, -4, -8  # mallopt(3) parameters
PRE_ALLOC_BYTES = 32 << 20  # heap faulted in at start, as LinuxCNC's rtapi_app


def socket_address() -> str:
    """The host's abstract unix socket (no file to clean up)."""
    return "\0" + ipc_name("hal", "rtapi")


class _Timespec(ctypes.Structure):
    _fields_ = [("tv_sec", ctypes.c_long), ("tv_nsec", ctypes.c_long)]


_libc = ctypes.CDLL(None, use_errno=True)  # the C library already loaded: no ldconfig search
_clock_nanosleep = _libc.clock_nanosleep
_clock_nanosleep.argtypes = [
    ctypes.c_int,
    ctypes.c_int,
    ctypes.POINTER(_Timespec),
    ctypes.c_void_p,
]
_prctl = _libc.prctl
_prctl.argtypes = [ctypes.c_int, ctypes.c_ulong, ctypes.c_ulong, ctypes.c_ulong, ctypes.c_ulong]
_libc.malloc.restype = ctypes.c_void_p
_libc.malloc.argtypes = [ctypes.c_size_t]
_libc.free.argtypes = [ctypes.c_void_p]


def sleep_until(deadline_ns: int, spec: _Timespec) -> None:
    """Sleep until CLOCK_MONOTONIC reaches ``deadline_ns`` (absolute, so no drift)."""
    spec.tv_sec, spec.tv_nsec = divmod(deadline_ns, 1_000_000_000)
    while _clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, ctypes.byref(spec), None) == 4:
        pass  # EINTR: a signal arrived; sleep again to the same deadline


def parse_module_args(words: list[str]) -> dict[str, str]:
    """LinuxCNC's ``key=value`` loadrt arguments (values may be quoted)."""
    args: dict[str, str] = {}
    for word in words:
        key, sep, value = word.partition("=")
        if not sep or not key:
            raise HalError(f"bad module argument '{word}' (want key=value)")
        args[key] = value.strip('"')
    return args


class _Funct:
    """One HAL function as a thread calls it, with its timing pin and params."""

    __slots__ = ("call", "has_failed", "name", "time", "tmax", "tmax_increased")

    def __init__(self, hal: Hal, comp: str, name: str, call: Callable[[int], None]) -> None:
        self.name = name
        self.call = call
        self.has_failed = False  # raised since it last ran through: said once, E-stop
        self.time = hal.new_pin(comp, f"{name}.time", HAL_S32, HAL_OUT)
        self.tmax = hal.new_param(comp, f"{name}.tmax", HAL_S32, HAL_RW)
        self.tmax_increased = hal.new_param(comp, f"{name}.tmax-increased", HAL_BIT, HAL_RO)


class RtThread(threading.Thread):
    """One periodic HAL thread."""

    def __init__(
        self, host: Host, name: str, period_ns: int, cpu: int | None, *, has_fp: bool = True
    ) -> None:
        super().__init__(name=f"hal-{name}", daemon=True)
        self.host = host
        self.hal_name = name
        self.period = int(period_ns)
        self.cpu = cpu
        self.is_stopping = False
        self.creator = ""
        self.priority = RT_PRIORITY
        #: how early the thread wakes to busy-wait to each deadline
        self.spin_ns = min(host.spin_ns, self.period // SPIN_PERIOD_FRACTION)
        comp = f"__{name}"
        self.comp = comp
        hal = host.hal
        with hal.edit():
            hal.new_component(comp, "rt")
            # slots of the thread's timing pin and parameters
            self.time = hal.new_pin(comp, f"{name}.time", HAL_S32, HAL_OUT)
            self.tmax = hal.new_param(comp, f"{name}.tmax", HAL_S32, HAL_RW)
            self.overruns = hal.new_thread(comp, name, self.period, has_fp=has_fp)
            hal.ready(comp)
        #: when set (benchmarks), each period appends (deadline, start, end) in ns
        self.timing_log: list[tuple[int, int, int]] | None = None

    def _chain(self) -> tuple[int, bool, list[_Funct]]:
        """(metadata generation, is HAL started, this thread's functions in addf order)."""
        gen, meta = self.host.hal.versioned_snapshot()
        info = meta["threads"].get(self.hal_name)
        names = info["functs"] if info else []
        functs = self.host.functs
        return gen, bool(meta["is_running"]), [functs[n] for n in names if n in functs]

    def run(self) -> None:
        self.host.make_realtime(self.cpu, self.priority)
        hal = self.host.hal
        period = self.period
        spec = _Timespec()
        clock = time.monotonic_ns
        deadline = (clock() // period + 1) * period
        gen, is_running, chain = -1, False, []
        q, ptr = hal.q, hal.ptr
        spin = self.spin_ns
        while not self.is_stopping:
            sleep_until(deadline - spin, spec)
            start = clock()
            while start < deadline:  # optional busy wait: trades CPU for wake-up latency
                start = clock()
            if hal.generation != gen:
                gen, is_running, chain = self._chain()
            if is_running:
                before = start
                for entry in chain:
                    try:
                        entry.call(period)
                    except Exception as exc:
                        if not entry.has_failed:
                            entry.has_failed = True
                            self.host.function_failed(entry.name, exc)
                    else:
                        if entry.has_failed:
                            entry.has_failed = False
                    after = clock()
                    spent = min(after - before, S32_MAX)
                    q[ptr[entry.time]] = spent
                    if spent > q[entry.tmax]:
                        q[entry.tmax] = spent
                        q[entry.tmax_increased] = 1
                    before = after
            end = clock()
            if is_running:
                spent = min(end - start, S32_MAX)
                q[ptr[self.time]] = spent
                if spent > q[self.tmax]:
                    q[self.tmax] = spent
            log = self.timing_log
            if log is not None:
                log.append((deadline, start, end))
            deadline += period
            if end > deadline:
                q[self.overruns] += 1
                deadline += ((end - deadline) // period + 1) * period


class LoadedModule:
    def __init__(self, name: str, comp: str, instances: list[Any], functs: list[str]) -> None:
        self.name, self.comp, self.instances, self.functs = name, comp, instances, functs
        self.args = ""
        self.exit: Callable[[], None] | None = None  # a module's rtapi_app_exit, bound


class Host:
    """The realtime host's state: loaded modules, functions and threads."""

    def __init__(
        self,
        hal: Hal,
        *,
        is_rt: bool = True,
        spin_us: int = 0,
        is_cpu_kept_awake: bool = False,
        cpu: int | None = None,
        priority: int = RT_PRIORITY,
    ) -> None:
        self.hal = hal
        self.is_rt = is_rt
        #: wake up this early and busy-wait to the deadline (0, or not realtime: only sleep)
        self.spin_ns = max(int(spin_us), 0) * 1000 if is_rt else 0
        #: hold /dev/cpu_dma_latency at 0 so idle CPUs poll instead of halting
        self.is_cpu_kept_awake = is_cpu_kept_awake
        self._cpu_latency_file: Any = None
        #: the CPU realtime threads run on (None: ``default_rt_cpu()``)
        self.cpu = cpu
        #: SCHED_FIFO priority of the fastest thread
        self.priority = priority
        self.modules: dict[str, LoadedModule] = {}
        self.functs: dict[str, _Funct] = {}
        self.threads: dict[str, RtThread] = {}
        #: the clock period, set by the first thread (LinuxCNC's base period)
        self.base_period: int | None = None
        self._warned: set[str] = set()
        self.is_exiting = threading.Event()
        set_shared_hal(hal)

    def function_failed(self, name: str, exc: Exception) -> None:
        """A HAL function raised: it keeps being called (a disabled function would leave
        what it drives unsupervised, motion's outputs frozen with the amplifiers on), it
        is said once, and the machine goes to E-stop through the safety board."""
        print(f"HAL: function '{name}' failed (machine to E-stop):", file=sys.stderr)
        traceback.print_exception(exc, file=sys.stderr)
        from nml.safety import SafetyBoard

        text = f"HAL function {name} failed: {type(exc).__name__}: {exc}; E-stop"
        board = SafetyBoard.attach()
        if board is not None:
            board.request_estop(text)
            board.close()
        motmod = getattr(self, "motmod", None)  # motion writes to the error channel
        if motmod is not None:
            motmod.pending_errors.append(text)

    # ------------------------------------------------------------ realtime setup
    def warn_once(self, key: str, text: str) -> None:
        if key not in self._warned:
            self._warned.add(key)
            print(text, file=sys.stderr, flush=True)

    def lock_memory(self) -> None:
        """mlockall when the locked-memory limit allows it; otherwise say why (ARCH-017)."""
        if not self.is_rt:
            return
        soft, _ = resource.getrlimit(resource.RLIMIT_MEMLOCK)
        is_privileged = os.geteuid() == 0
        if not is_privileged and soft != resource.RLIM_INFINITY:
            kib = soft // 1024
            self.warn_once(
                "memlock",
                f"RTAPI: Locked memory limit is {kib}KiB, recommended at least "
                f"{RECOMMENDED_MEMLOCK_KIB}KiB (set 'memlock {RECOMMENDED_MEMLOCK_KIB}' in "
                "/etc/security/limits.conf); memory is not locked",
            )
            return
        if _libc.mlockall(MCL_CURRENT | MCL_FUTURE) != 0:
            err = ctypes.get_errno()
            self.warn_once("memlock", f"RTAPI: cannot lock memory: {os.strerror(err)}")
            return
        reserve_heap()

    def keep_cpu_awake(self) -> None:
        """Ask the kernel for zero wake-up latency while the host runs (PM QoS).

        Holding ``/dev/cpu_dma_latency`` open with 0 written keeps idle CPUs in their
        polling state instead of halting: on a VM a halted vCPU goes back to the hypervisor
        and its timer wake-up costs tens of microseconds more. The request lasts as long as
        the file stays open (``release_cpu``).
        """
        if not (self.is_rt and self.is_cpu_kept_awake) or self._cpu_latency_file is not None:
            return
        try:
            handle = CPU_LATENCY_FILE.open("wb", buffering=0)  # held open until release_cpu
            handle.write((0).to_bytes(4, sys.byteorder))
        except OSError as exc:
            self.warn_once("awake", f"RTAPI: cannot keep the CPUs awake: {exc}")
            return
        self._cpu_latency_file = handle

    def release_cpu(self) -> None:
        """Drop the wake-up latency request of ``keep_cpu_awake``."""
        if self._cpu_latency_file is not None:
            self._cpu_latency_file.close()
            self._cpu_latency_file = None

    def prepare(self) -> None:
        """Process-wide realtime setup: lock memory, keep the GC and long GIL holds away."""
        self.lock_memory()
        self.keep_cpu_awake()
        sys.setswitchinterval(0.0001)  # a thread waking on time gets the GIL quickly
        gc.disable()  # no collection pauses inside a period; loadrt freezes what it made
        gc.freeze()

    def make_realtime(self, cpu: int | None, priority: int = RT_PRIORITY) -> None:
        """Run the calling thread on ``cpu`` with SCHED_FIFO where permitted."""
        if not self.is_rt:
            return
        # wake at the deadline, not up to the default 50 µs after it (normal priority only:
        # the kernel gives SCHED_FIFO threads no slack anyway)
        _prctl(PR_SET_TIMERSLACK, 1, 0, 0, 0)
        if cpu is not None:
            try:
                os.sched_setaffinity(0, {cpu})
            except OSError as exc:
                self.warn_once("affinity", f"RTAPI: cannot pin thread to CPU {cpu}: {exc}")
        try:
            os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(priority))
        except (OSError, AttributeError) as exc:
            self.warn_once(
                "fifo",
                f"RTAPI: realtime scheduling (SCHED_FIFO) not permitted ({exc}); "
                "running with normal priority, expect more latency",
            )

    # ------------------------------------------------------------ modules
    @staticmethod
    def import_module(name: str) -> Any:
        """The realtime module ``loadrt NAME`` means: a file given by path, else NAME.py
        in the folders of ``$CNC_HAL_COMPONENTS``, else in ``MODULE_PACKAGES`` (``-`` in
        NAME read as ``_``: ``xyzac-trt-kins``)."""
        if name.endswith(".py") or "/" in name:
            path = Path(name)
            spec = importlib.util.spec_from_file_location(f"halcomp_{path.stem}", path)
            if spec is None or spec.loader is None or not path.is_file():
                raise HalError(f"{name}: component file not found")
            module = importlib.util.module_from_spec(spec)
            spec.loader.exec_module(module)
            return module
        for folder in filter(None, os.environ.get(COMPONENTS_ENV, "").split(os.pathsep)):
            candidate = Path(folder) / f"{name}.py"
            if candidate.is_file():
                return Host.import_module(str(candidate))
        if not name or not all(c.isalnum() or c in "_-" for c in name):
            raise HalError(f"{name}: realtime component not found")
        file_name = name.replace("-", "_")
        for package in MODULE_PACKAGES:
            wanted = f"{package}.{file_name}"
            try:
                module = importlib.import_module(wanted)
            except ModuleNotFoundError as exc:
                if exc.name and wanted.startswith(exc.name):
                    continue  # not in this package
                raise
            if hasattr(module, "rtapi_app_main") or hasattr(module, "COMPONENT"):
                return module
        raise HalError(f"{name}: realtime component not found")

    def loadrt(self, name: str, words: list[str], comp_name: str = "") -> None:
        """Load a realtime module; ``comp_name`` names its HAL component (default: module).

        Everything the module creates is published in one metadata update (or not at all).
        """
        old_functs, old_threads = set(self.functs), set(self.threads)
        try:
            with self.hal.edit():
                self._loadrt(name, words, comp_name)
        except BaseException:
            # the metadata is rolled back; drop what this process made to match it
            for funct in set(self.functs) - old_functs:
                del self.functs[funct]
            for thread in set(self.threads) - old_threads:
                self.stop_thread(thread)
            raise
        gc.collect()
        gc.freeze()

    def _loadrt(self, name: str, words: list[str], comp_name: str) -> None:
        module = self.import_module(name)
        comp_name = comp_name or Path(name).stem
        if comp_name in self.modules:
            raise HalError(f"{comp_name}: module already loaded")
        args = parse_module_args(words)
        if hasattr(module, "rtapi_app_main"):
            self.hal.new_component(comp_name, "rt", args=" ".join(words))
            loaded = LoadedModule(comp_name, comp_name, [], [])
            try:
                module.rtapi_app_main(self, comp_name, args)
            except Exception:
                self._remove(comp_name)
                raise
        elif hasattr(module, "COMPONENT"):
            cls: type[RtComponent] = module.COMPONENT
            loaded = self._load_component(cls, comp_name, args)
        else:
            raise HalError(f"{name}: not a HAL component (no COMPONENT or rtapi_app_main)")
        loaded.args = " ".join(words)
        if hasattr(module, "rtapi_app_exit"):  # LinuxCNC's unload hook of such modules
            loaded.exit = lambda: module.rtapi_app_exit(self, comp_name)
        self.modules[comp_name] = loaded
        with self.hal.edit() as meta:
            # what halcmd's ``save`` prints after ``loadrt NAME``: each argument and a space
            meta["comps"][comp_name]["insmod_args"] = "".join(f"{word} " for word in words)
        self.hal.ready(comp_name)

    def _load_component(
        self, cls: type[RtComponent], comp_name: str, args: dict[str, str]
    ) -> LoadedModule:
        wanted = cls.instances(comp_name, args)
        self.hal.new_component(comp_name, "rt")
        loaded = LoadedModule(comp_name, comp_name, [], [])
        try:
            for inst_name, options in wanted:
                inst = cls.create(self.hal, comp_name, inst_name, options)
                loaded.instances.append(inst)
                for fname, has_fp, method, scope in cls.functs():
                    if scope != "instance":
                        continue
                    full = f"{inst_name}.{fname}" if fname else inst_name
                    self.add_function(comp_name, full, getattr(inst, method), has_fp)
                    loaded.functs.append(full)
            prefix = cls.prefix or comp_name.removeprefix("hal_").replace("_", "-")
            for fname, has_fp, method, scope in cls.functs():
                if scope != "instance":
                    full = fname if scope == "global" else f"{prefix}.{fname}"
                    bound = getattr(cls, method)
                    instances = loaded.instances
                    self.add_function(
                        comp_name, full, lambda period, b=bound, i=instances: b(i, period), has_fp
                    )
                    loaded.functs.append(full)
        except Exception:
            self._remove(comp_name)
            for inst in loaded.instances:
                with contextlib.suppress(Exception):
                    inst.teardown()
            raise
        return loaded

    def add_function(
        self, comp: str, name: str, call: Callable[[int], None], has_fp: bool = True
    ) -> None:
        """Export a function that threads may run (components and special modules use this)."""
        self.hal.new_funct(comp, name, has_fp=has_fp)
        self.functs[name] = _Funct(self.hal, comp, name, call)

    def new_thread(
        self,
        name: str,
        period_ns: int,
        creator: str = "",
        cpu: int | None = None,
        *,
        has_fp: bool = True,
    ) -> RtThread:
        if name in self.hal.meta["threads"]:
            raise HalError(f"duplicate thread name '{name}'")
        if period_ns < 1000:
            raise HalError(f"thread '{name}': period {period_ns} ns is too short")
        # As LinuxCNC: the first thread sets the clock period; later threads must be
        # slower, and run at the nearest whole multiple of the clock period.
        if self.base_period is None:
            self.base_period = period_ns
        if period_ns < self.base_period:
            raise HalError(
                f"HAL_LIB: ERROR: new thread period {period_ns} is less than clock period "
                f"{self.base_period}"
            )
        asked = period_ns
        period_ns = (period_ns + self.base_period // 2) // self.base_period * self.base_period
        newest = list(self.threads.values())[-1].period if self.threads else 0
        if period_ns < newest:
            raise HalError(
                f"HAL_LIB: ERROR: new thread period {asked} is less than existing thread "
                f"period {newest}"
            )
        if cpu is None:
            cpu = self.cpu if self.cpu is not None else default_rt_cpu()
        thread = RtThread(self, name, period_ns, cpu, has_fp=has_fp)
        # threads come fastest first; a faster thread preempts slower ones, as in LinuxCNC
        thread.priority = max(self.priority - len(self.threads), 1)
        thread.creator = creator
        self.threads[name] = thread
        thread.start()
        return thread

    def _remove(self, comp: str) -> None:
        for name, thread in list(self.threads.items()):
            if thread.creator == comp:
                self.stop_thread(name)
        for name in [n for n, f in self.hal.meta["functs"].items() if f["owner"] == comp]:
            self.functs.pop(name, None)
        with contextlib.suppress(HalError):
            self.hal.remove_component(comp)

    def stop_thread(self, name: str) -> None:
        """End a thread and remove it (its functions stay loaded): also for a process that
        calls the functions itself, where an idle thread would only take the GIL."""
        thread = self.threads.pop(name)
        thread.is_stopping = True
        thread.join(timeout=2)
        with contextlib.suppress(HalError):
            self.hal.remove_component(thread.comp)

    def unloadrt(self, name: str) -> None:
        if name not in self.modules:
            raise HalError(f"component '{name}' not loaded")
        loaded = self.modules.pop(name)
        self._remove(name)
        if (loaded.instances or loaded.exit) and self.threads:
            # let every thread finish its current period before the instances go away
            time.sleep(2 * max(t.period for t in self.threads.values()) / 1e9)
        for inst in loaded.instances:
            try:
                inst.teardown()
            except Exception:
                traceback.print_exc()
        if loaded.exit is not None:
            try:
                loaded.exit()
            except Exception:
                traceback.print_exc()

    def unload_all(self) -> None:
        for name in reversed(list(self.modules)):
            self.unloadrt(name)
        for name in list(self.threads):
            self.stop_thread(name)

    # ------------------------------------------------------------ command channel
    def handle(self, request: dict[str, Any]) -> dict[str, Any]:
        command = request.get("cmd")
        try:
            if command == "ping":
                return {"ok": True, "pid": os.getpid()}
            if command == "loadrt":
                self.loadrt(request["name"], list(request.get("args", [])), request.get("comp", ""))
            elif command in ("unloadrt", "unloadall"):
                if command == "unloadrt":
                    self.unloadrt(request["name"])
                else:
                    self.unload_all()
                if not self.modules and not self.threads:
                    # like LinuxCNC's rtapi_app: the host leaves with its last module
                    self.is_exiting.set()
            elif command == "modules":
                return {"ok": True, "modules": {n: m.args for n, m in self.modules.items()}}
            elif command == "exit":
                self.is_exiting.set()
            else:
                return {"ok": False, "error": f"unknown host command '{command}'"}
        except HalError as exc:
            return {"ok": False, "error": str(exc)}
        except Exception as exc:
            traceback.print_exc()
            return {"ok": False, "error": f"{type(exc).__name__}: {exc}"}
        return {"ok": True}

    def serve(self, server: socket.socket) -> None:
        """Answer requests until ``exit`` or a signal.

        The main thread blocks in the kernel between requests, holding no GIL: a waiting
        thread that woke now and then (an accept timeout) could be preempted on a busy CPU
        while holding the GIL, and the servo thread would wait for it for milliseconds.
        Signals wake it through ``signal.set_wakeup_fd``.
        """
        wake_read, wake_write = os.pipe()
        os.set_blocking(wake_write, False)
        previous_fd = signal.set_wakeup_fd(wake_write, warn_on_full_buffer=False)
        try:
            with selectors.DefaultSelector() as selector:
                selector.register(server, selectors.EVENT_READ)
                selector.register(wake_read, selectors.EVENT_READ)
                while not self.is_exiting.is_set():
                    ready = {key.fileobj for key, _ in selector.select()}
                    if wake_read in ready:
                        os.read(wake_read, 512)
                    if server in ready:
                        conn, _ = server.accept()
                        with conn:
                            self._answer(conn)
        finally:
            signal.set_wakeup_fd(previous_fd)
            os.close(wake_read)
            os.close(wake_write)

    def _answer(self, conn: socket.socket) -> None:
        """One client's requests, a JSON object per line each way."""
        conn.settimeout(30)
        stream = conn.makefile("rwb")
        for line in stream:
            try:
                request = json.loads(line)
            except ValueError:
                reply = {"ok": False, "error": "malformed request"}
            else:
                reply = self.handle(request)
            stream.write(json.dumps(reply).encode() + b"\n")
            stream.flush()
            if self.is_exiting.is_set():
                break

    def shutdown(self) -> None:
        with contextlib.suppress(Exception):
            self.unload_all()
        self.release_cpu()


def reserve_heap(size: int = PRE_ALLOC_BYTES) -> None:
    """Make malloc keep what it gets and fault in ``size`` bytes of heap now, as LinuxCNC's
    rtapi_app does: with memory locked, a period that grows the heap (numpy arrays, big
    lists) then finds resident pages instead of taking page faults, and freed memory is
    never handed back to the kernel only to be faulted in again."""
    _libc.mallopt(M_TRIM_THRESHOLD, -1)  # never shrink the heap
    _libc.mallopt(M_MMAP_MAX, 0)  # big blocks from the (locked, kept) heap, not mmap
    _libc.mallopt(M_ARENA_MAX, 1)  # threads too: their own arenas would grow by mmap
    block = _libc.malloc(size)
    if block:
        ctypes.memset(block, 0, size)  # touches every page: resident and locked from now
        _libc.free(block)


def host_environment() -> dict[str, str]:
    """The environment to start the host with: Python objects from malloc's heap.

    Python's own allocator maps 1 MiB arenas as the servo thread's objects grow and unmaps
    them when they empty; with memory locked, each new arena is faulted in at once inside a
    period (hundreds of µs). From malloc, which ``reserve_heap`` keeps and pre-faults, they
    cost no system call. Costs no speed measurably (scripts/bench/tp_bench.py).
    """
    return {**os.environ, "PYTHONMALLOC": os.environ.get("PYTHONMALLOC", "malloc")}


class HostClient:
    """Talks to the realtime host over its socket (halcmd's side); starts it when asked to."""

    def __init__(self) -> None:
        self.address = socket_address()
        self.started: subprocess.Popen[bytes] | None = None

    def is_running(self) -> bool:
        try:
            self.request({"cmd": "ping"})
        except OSError:
            return False
        return True

    def request(self, message: dict[str, Any], timeout: float = 60) -> dict[str, Any]:
        with socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as sock:
            sock.settimeout(timeout)
            sock.connect(self.address)
            sock.sendall(json.dumps(message).encode() + b"\n")
            data = b""
            while not data.endswith(b"\n"):
                chunk = sock.recv(65536)
                if not chunk:
                    raise OSError("realtime host closed the connection")
                data += chunk
        return json.loads(data)

    def ensure(self, stderr: int | TextIO | None = None) -> None:
        """Start ``python -m hal.rtapi_app`` unless one is already running."""
        if self.is_running():
            return
        self.started = subprocess.Popen(
            [sys.executable, "-m", "hal.rtapi_app"],
            env=host_environment(),
            stdin=subprocess.DEVNULL,
            stdout=subprocess.DEVNULL,
            stderr=stderr if stderr is not None else subprocess.DEVNULL,
            start_new_session=True,
        )
        deadline = time.monotonic() + HOST_START_TIMEOUT_S
        while time.monotonic() < deadline:
            if self.started.poll() is not None:
                raise HalError("realtime host exited without becoming ready")
            if self.is_running():
                return
            time.sleep(0.02)
        raise HalError("realtime host did not become ready")

    def call(self, message: dict[str, Any]) -> dict[str, Any]:
        try:
            reply = self.request(message)
        except OSError as exc:
            raise HalError(f"realtime host not reachable: {exc}") from None
        if not reply.get("ok"):
            raise HalError(reply.get("error", "realtime host refused the command"))
        return reply

    def stop(self) -> None:
        """Ask the host to exit and wait for it (when this process started it)."""
        with contextlib.suppress(OSError):
            self.request({"cmd": "exit"})
        deadline = time.monotonic() + 10
        while self.is_running() and time.monotonic() < deadline:
            time.sleep(0.02)
        if self.started is not None:
            with contextlib.suppress(subprocess.TimeoutExpired):
                self.started.wait(timeout=10)


def default_rt_cpu() -> int:
    """Where realtime threads run: the highest isolated CPU (``isolcpus=``), else the last
    one, as LinuxCNC chooses."""
    isolated: list[int] = []
    with contextlib.suppress(OSError, ValueError):
        for part in filter(None, ISOLATED_CPUS.read_text().strip().split(",")):
            first, _, last = part.partition("-")
            isolated.extend(range(int(first), int(last or first) + 1))
    return max(isolated) if isolated else (os.cpu_count() or 1) - 1


def purge_dead_components(hal: Hal) -> list[str]:
    """Remove components whose process is gone (a crashed userspace program or host)."""
    with hal.edit() as meta:
        dead = [name for name, comp in meta["comps"].items() if not is_process_alive(comp["pid"])]
        for name in dead:
            hal.remove_component(name)
    return dead


def release_if_unused(hal: Hal) -> bool:
    """Unlink the HAL segments when no live component is left; True when removed."""
    with hal.edit() as meta:
        purge_dead_components(hal)
        is_unused = not meta["comps"]
    if is_unused:
        hal.destroy()
    return is_unused


def _env_int(name: str, default: int | None) -> int | None:
    text = os.environ.get(name, "")
    if not text:
        return default
    try:
        return int(text)
    except ValueError:
        print(f"rtapi_app: ignoring ${name}={text!r} (not a whole number)", file=sys.stderr)
        return default


def host_options_from_env() -> dict[str, Any]:
    """``Host`` settings: the defaults, changed by the ``$CNC_HAL_*`` knobs of hal/README.md."""
    return {
        "is_rt": os.environ.get(NO_RT_ENV) != "1",
        "spin_us": _env_int(SPIN_ENV, DEFAULT_SPIN_US),
        "is_cpu_kept_awake": _env_int(AWAKE_ENV, 1) != 0,
        "cpu": _env_int(CPU_ENV, None),
        "priority": _env_int(PRIORITY_ENV, RT_PRIORITY),
    }


def main(argv: list[str] | None = None) -> int:
    protect_output()  # a closed stderr pipe must not kill it (cnc/stdio.py)
    options = host_options_from_env()
    parser = argparse.ArgumentParser(prog="rtapi_app", description=__doc__.splitlines()[0])
    parser.add_argument("--no-rt", action="store_true", help="no SCHED_FIFO, no mlockall")
    parser.add_argument(
        "--spin-us",
        type=int,
        default=options["spin_us"],
        help=f"wake this early and busy-wait to each deadline (default ${SPIN_ENV} "
        f"or {DEFAULT_SPIN_US}; 0 only sleeps)",
    )
    opts = parser.parse_args(argv)
    options["spin_us"] = opts.spin_us
    options["is_rt"] = options["is_rt"] and not opts.no_rt
    server = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    try:
        server.bind(socket_address())
    except OSError:
        print("rtapi_app: a realtime host is already running for this instance", file=sys.stderr)
        return 1
    server.listen(8)
    hal = Hal()
    host = Host(hal, **options)
    host.prepare()
    for signum in (signal.SIGTERM, signal.SIGINT, signal.SIGHUP):
        signal.signal(signum, lambda *_: host.is_exiting.set())
    print("rtapi_app: ready", flush=True)
    try:
        host.serve(server)
    finally:
        server.close()
        host.shutdown()
        set_shared_hal(None)
        release_if_unused(hal)
        hal.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
