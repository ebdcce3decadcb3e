"""``python -m symsphere``: the same as the ``symsphere`` command (:func:`symsphere.apps.cli.main`)."""

import sys

from .apps.cli import main

if __name__ == "__main__":
    sys.exit(main())
