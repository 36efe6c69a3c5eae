# [PYTHON]TOPLEVEL of the remap examples: run once when the interpreter starts. Import here
# the modules the interpreter looks into: remap (the handlers, prologs and epilogs REMAP=
# lines name), and oword or namedparams when you write any.
import remap


def __init__(self):  # noqa: N807 (the name the interpreter calls)
    # once the interpreter is set up: the standard glue's state (the sticky words of
    # cycle_prolog)
    remap.init_stdglue(self)
