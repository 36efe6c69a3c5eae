from emccanon import MESSAGE
from interpreter import INTERP_ERROR, INTERP_OK


def noop(self, **words):
    return INTERP_OK


def check_return(self, **words):
    """An epilog reading the procedure's return value (REMAP-038)."""
    MESSAGE("check_return: value=%.1f returned=%d" % (self.return_value, self.value_returned))
    if self.return_value < 0:
        self.set_errormsg("M421: the procedure failed with %.1f" % self.return_value)
        return INTERP_ERROR
    return INTERP_OK


def message_string(self, **words):
    MESSAGE("message_string runs")
    return "M422 says no"


def legacy_error(self, **words):
    self.set_errormsg("M423: the old convention")
    return INTERP_ERROR


def raising(self, **words):
    return 1 / 0


def returns_float(self, **words):
    return 2.5
