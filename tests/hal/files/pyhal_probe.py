"""Exercise LinuxCNC's Python ``hal`` module and print what it does, line by line.

Run by tests/hal/test_hal_pymodule.py with our ``hal``; its output from LinuxCNC 2.9's
module is lcnc_pyhal_probe_output.txt (see README.md for the command).
"""

import subprocess

import hal


def attempt(label, action):
    try:
        result = action()
    except Exception as exc:
        print(f"{label}: {type(exc).__name__}")
    else:
        print(f"{label}: {result!r}")


def halcmd(*words):
    subprocess.run(["halcmd", *words], check=False)


c = hal.component("probe")
print(repr(c).replace("(", " ").split()[:3])  # (its id differs)
out_f = c.newpin("out-f", hal.HAL_FLOAT, hal.HAL_OUT)
in_f = c.newpin("in-f", hal.HAL_FLOAT, hal.HAL_IN)
io_b = c.newpin("io-b", hal.HAL_BIT, hal.HAL_IO)
out_s = c.newpin("out-s", hal.HAL_S32, hal.HAL_OUT)
out_u = c.newpin("out-u", hal.HAL_U32, hal.HAL_OUT)
par = c.newparam("par", hal.HAL_S32, hal.HAL_RW)
ro = c.newparam("ro", hal.HAL_FLOAT, hal.HAL_RO)
print(type(out_f).__name__, type(par).__name__)
print(out_f.name, out_f.type, out_f.dir, par.is_pin(), len(c))
attempt("duplicate pin", lambda: c.newpin("out-f", hal.HAL_FLOAT, hal.HAL_OUT))
attempt("bad type", lambda: c.newpin("bad", 99, hal.HAL_OUT))
attempt("too long", lambda: c.newpin("x" * 60, hal.HAL_BIT, hal.HAL_OUT))
print("exists", hal.component_exists("probe"), hal.component_exists("nope"))
print("ready before", hal.component_is_ready("probe"))
c.ready()
print("ready after", hal.component_is_ready("probe"))
c["out-f"] = 2.5
attempt("unknown attribute", lambda: setattr(c, "out_s", 3))  # the pin is out-s
attempt("attribute read", lambda: c.par)
c.par = -7
print("par", c["par"], c.par, par.value, par.get())
out_f.value = 1.25
print("out-f", c["out-f"], out_f.get(), hal.get_value("probe.out-f"))
attempt("missing item", lambda: c["nope"])
attempt("s32 overflow", lambda: c.__setitem__("out-s", 1 << 31))
attempt("u32 negative", lambda: c.__setitem__("out-u", -1))
attempt("float from text", lambda: c.__setitem__("out-f", "x"))
c["out-s"] = 7.9
c["out-u"] = True
c["io-b"] = 5
print("converted", c["out-s"], c["out-u"], c["io-b"])
print("getpins", sorted(c.getpins().items()))
item = c.getitem("out-s")
print(repr(item), item.get_name(), item.get(), item.is_pin(), item.get_dir() == hal.HAL_OUT)
print("new_sig", hal.new_sig("sig-f", hal.HAL_FLOAT), hal.new_sig("sig-f", hal.HAL_FLOAT))
attempt("new_sig bad type", lambda: hal.new_sig("sig-x", 99))
print("connect", hal.connect("probe.out-f", "sig-f"), hal.connect("probe.in-f", "sig-f"))
print("connect missing", hal.connect("probe.nope", "sig-f"))
print("in-f", c["in-f"], hal.get_value("sig-f"), hal.pin_has_writer("probe.in-f"))
attempt("pin_has_writer missing", lambda: hal.pin_has_writer("probe.nope"))
print("set_p", hal.set_p("probe.par", "12"), hal.set_p("probe.par", "zz"), c["par"])
attempt("set_p output", lambda: hal.set_p("probe.out-f", "1"))
attempt("set_p linked", lambda: hal.set_p("probe.in-f", "1"))
attempt("set_p ro", lambda: hal.set_p("probe.ro", "1"))
attempt("set_p missing", lambda: hal.set_p("probe.nope", "1"))
halcmd("setp", "probe.io-b", "0")
print("io-b after halcmd", c["io-b"])
print("disconnect", hal.disconnect("probe.in-f"), c["in-f"])
attempt("get_value missing", lambda: hal.get_value("nope"))
pins = [p for p in hal.get_info_pins() if p["NAME"].startswith("probe.")]
print("pins", [(p["NAME"], p["VALUE"], p["DIRECTION"], p["TYPE"]) for p in pins])
sigs = [s for s in hal.get_info_signals() if s["NAME"] == "sig-f"]
print("signals", [(s["NAME"], s["VALUE"], s["DRIVER"], s["TYPE"]) for s in sigs])
params = [p for p in hal.get_info_params() if p["NAME"].startswith("probe.")]
print("params", [(p["NAME"], p["VALUE"], p["DIRECTION"]) for p in params])
w = hal.stream(c, hal.streamer_base + 5, 4, "fbsu")
print(repr(w), w.element_types, w.maxdepth, w.depth, w.writable, w.readable)
for n in range(3):
    w.write((n + 0.5, n % 2, -n, n))
attempt("stream full", lambda: w.write((1.0, 1, 1, 1)))
attempt("stream short tuple", lambda: w.write((1.0,)))
print("after writes", w.depth, w.writable, w.num_overruns)
r = hal.stream(c, hal.streamer_base + 5, "fbsu")
print(repr(r), [r.read() for _ in range(4)], r.sampleno, r.num_underruns)
attempt("stream types mismatch", lambda: hal.stream(c, hal.streamer_base + 5, "ffff"))
attempt("stream missing", lambda: hal.stream(c, hal.streamer_base + 6))
c.exit()
attempt("closed", lambda: c["out-f"])
