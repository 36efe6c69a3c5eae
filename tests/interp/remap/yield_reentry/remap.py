import emccanon
from interpreter import INTERP_EXECUTE_FINISH, INTERP_OK


def body(self, **words):
    self.execute("(body begins)")
    for y in (1, 2):
        self.execute("G0 Y%d" % y)
        yield INTERP_EXECUTE_FINISH
        self.execute("(body: y=%.1f)" % self.current_y)
    self.execute("(body ends)")


def prolog(self, **words):
    self.execute("G0 X5")
    yield INTERP_EXECUTE_FINISH
    self.params["x_then"] = self.current_x
    yield INTERP_OK


def epilog(self, **words):
    self.execute(
        "(epilog: x_then=%.1f from the procedure %.1f)"
        % (self.params["x_then"], self.params["seen"])
    )
    self.execute("G0 Z2")
    yield INTERP_EXECUTE_FINISH
    self.execute("(epilog: z=%.1f)" % self.current_z)


def wait_input(self, **words):
    """PY-017: wait for digital input 00, then read it after synch."""
    emccanon.WAIT(0, 1, 2, 5.0)
    yield INTERP_EXECUTE_FINISH
    emccanon.MESSAGE("input 00 = %d" % emccanon.GET_EXTERNAL_DIGITAL_INPUT(0, 0))


def yields_ok(self, **words):
    emccanon.MESSAGE("yields_ok before")
    yield INTERP_OK
    emccanon.MESSAGE("never here")
