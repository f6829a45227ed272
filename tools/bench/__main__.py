"""``python -m tools.bench SUITE [options]``: see :mod:`tools.bench`."""

import sys

from tools.bench import main

sys.exit(main())
