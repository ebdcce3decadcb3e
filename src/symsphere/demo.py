"""The demo's old import path, kept for users' code: use :mod:`symsphere.apps.demo`.

Nothing in the library imports it.
"""

from .apps.demo import DEMO_FILES, FAMILY_SIGNIFICANCE, run_demo

__all__ = ["run_demo", "DEMO_FILES", "FAMILY_SIGNIFICANCE"]
