"""``python -m tools.fuzz``: see :mod:`tools.fuzz`."""

import sys

from .driver import main

sys.exit(main())
