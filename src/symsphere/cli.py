"""The ``symsphere`` command's old import path, kept for users' code: use :mod:`symsphere.apps.cli`.

Nothing in the library imports it.
"""

import sys

from .apps.cli import build_parser, main

__all__ = ["main", "build_parser"]

if __name__ == "__main__":
    sys.exit(main())
