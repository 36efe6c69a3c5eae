import remap


def __init__(self):
    remap.init_stdglue(self)
