"""The convergence study's old import path, kept for users' code: use :mod:`symsphere.apps.study`.

The study moved to :mod:`symsphere.apps.study` and its statistics (:func:`rmse`, :func:`fit_slope`,
:class:`SlopeFit`, :func:`cap_discrepancy`, :func:`cap_discrepancy_squared`) to the library module
:mod:`symsphere.quality`; this module re-exports both.  Nothing in the library imports it.
"""

from .apps.study import *  # noqa: F403
from .apps.study import __all__ as _study_names
from .apps.study.config import FAMILY_SIGNIFICANCE, ROUNDING_LEVEL
from .quality import LOG_FLOOR, SlopeFit, cap_discrepancy, cap_discrepancy_squared, fit_slope, rmse

__all__ = [
    *_study_names,
    "FAMILY_SIGNIFICANCE",
    "LOG_FLOOR",
    "ROUNDING_LEVEL",
    "SlopeFit",
    "cap_discrepancy",
    "cap_discrepancy_squared",
    "fit_slope",
    "rmse",
]
