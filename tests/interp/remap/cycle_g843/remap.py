from stdglue import *

_words_of_cycle = {}


def g842(self, **words):
    """A cycle in Python alone: the words merge into those of the cycle's earlier blocks."""
    block = self.blocks[self.remap_level]
    remap = block.executing_remap
    if block.g_modes[1] == remap.motion_code:
        _words_of_cycle[remap.name] = {}
        text = "*" + remap.name
    else:
        text = remap.name
    _words_of_cycle[remap.name].update(words)
    for key in sorted(_words_of_cycle[remap.name]):
        text += " %s%.1f" % (key, _words_of_cycle[remap.name][key])
    MESSAGE(text)
    self.motion_mode = remap.motion_code
    return INTERP_OK
