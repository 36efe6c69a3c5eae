from interpreter import INTERP_OK


def count_calls(self, **words):
    self.calls += 1
    print("call %d" % self.calls)
    return INTERP_OK
