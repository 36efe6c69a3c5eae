import remap


def __init__(self):
    self.calls = 0
    print(
        "__init__: task=%d call_level=%d remap_level=%d"
        % (self.task, self.call_level, self.remap_level)
    )


def __delete__(self):
    print("__delete__ after %d calls" % self.calls)
