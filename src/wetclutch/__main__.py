"""``python -m wetclutch``: the same command line as the ``wetclutch`` console script."""

import sys

from .cli import main

sys.exit(main())
