from emccanon import MESSAGE
from interpreter import INTERP_OK


def g886(self, **words):
    for key in sorted(words):
        MESSAGE("g886: %s=%.4f" % (key, words[key]))
    if "p" in words:
        MESSAGE("the p word is present")
    else:
        MESSAGE("no p word")
    MESSAGE("comment: '%s'" % self.blocks[self.remap_level].comment)
    return INTERP_OK
