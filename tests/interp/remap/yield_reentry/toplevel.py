import remap
