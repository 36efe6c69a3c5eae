from emccanon import MESSAGE
from interpreter import INTERP_ERROR, INTERP_OK


def insert_param(self, **words):
    self.params["myname"] = 123
    self.params[1] = 345
    self.params[2] = 678
    MESSAGE("prolog: call_level=%d locals=%s" % (self.call_level, self.params.locals()))
    return INTERP_OK


def retrieve_param(self, **words):
    MESSAGE("epilog: #1=%.1f #2=%.1f" % (self.params[1], self.params[2]))
    try:
        result = self.params["result"]
    except RuntimeError:
        self.set_errormsg("testparam forgot to assign #<result>")
        return INTERP_ERROR
    MESSAGE("epilog: result=%.1f locals=%s" % (result, self.params.locals()))
    return INTERP_OK
