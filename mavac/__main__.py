"""``python -m mavac``: the command line of :mod:`mavac.cli`."""

import sys

from .cli import main

sys.exit(main())
