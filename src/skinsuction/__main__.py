"""``python -m skinsuction``: the command line (same as ``skinsuction``)."""

import sys

from skinsuction.cli import main

sys.exit(main())
