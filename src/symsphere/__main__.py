"""``python -m symsphere``: the same as the ``symsphere`` command."""

import sys

from .cli import main

if __name__ == "__main__":
    sys.exit(main())
