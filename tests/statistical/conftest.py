"""Statistical tests of the scheme as a whole (chi-square uniformity against independent references).

Every test in this folder is marked ``statistical``: ``pytest -m statistical`` runs them alone,
``pytest -m "not statistical"`` leaves them out.  Each file states its significance level and its
Sidak correction.  The statistical tests of one module (a map's chi-square, a peer's) stay beside
that module's other tests, also marked.
"""

import pytest


def pytest_collection_modifyitems(config, items):
    for item in items:
        if "statistical" in item.path.parts:
            item.add_marker(pytest.mark.statistical)
