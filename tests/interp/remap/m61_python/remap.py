from stdglue import *
