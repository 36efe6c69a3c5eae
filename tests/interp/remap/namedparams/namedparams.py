def _pi(self):
    return 3.1415926535


def _twice_feed(self):
    return 2 * self.feed_rate


def _an_int(self):
    return 42


def _broken(self):
    return "the named parameter _broken is broken"


def _line(self):
    return -1.0


def not_a_parameter(self):
    return 1.0
