import emccanon


def square(self, x):
    return x * x


def count(self, *args):
    emccanon.MESSAGE("count: %d arguments" % len(args))
    return float(len(args))


def count_int(self, *args):
    return len(args)


def nothing(self, *args):
    pass


def shadowed(self, *args):
    emccanon.MESSAGE("the Python shadowed() runs, not shadowed.ngc")
    return 7.5


def refuses(self, *args):
    return "refuses: no way"
