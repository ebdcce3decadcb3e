"""Number formatting shared by the applications' reports (the demo's and the study's)."""

from __future__ import annotations

import math

__all__ = ["format_p"]


def format_p(p: float) -> str:
    """A p-value for a report: 3 significant digits, ``'< 1e-300'`` for 0, ``'n/a'`` for NaN.

    ``scipy.stats.chi2.sf`` underflows to 0 below about 1e-308, so 0 means "smaller than any
    printed value", not an exact 0.

    Examples
    --------
    >>> from symsphere.apps._format import format_p
    >>> format_p(0.012345), format_p(0.0), format_p(float("nan"))
    ('0.0123', '< 1e-300', 'n/a')
    """
    if math.isnan(p):
        return "n/a"
    return "< 1e-300" if p == 0 else f"{p:.3g}"
