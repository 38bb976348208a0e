"""``python -m ptlab``: the ``ptlab`` command (``ptlab.cli``)."""

import sys

from ptlab.cli import main

if __name__ == "__main__":
    sys.exit(main())
