import sys

from cnc.cli import main

sys.exit(main())
