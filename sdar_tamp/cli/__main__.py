"""``python -m sdar_tamp.cli``: the ``sdar`` program."""

import sys

from sdar_tamp.cli import main

sys.exit(main())
