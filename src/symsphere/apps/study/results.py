"""The study's measurements as they accumulate (:class:`Results`), their CSV columns, and their seeds.

Every random choice of the study is seeded by ``SeedSequence(seed, spawn_key=(stage, ...))`` with
names turned into integers by :func:`key`, so that a cell's numbers do not depend on which other
cells run.
"""

from __future__ import annotations

import zlib
from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np

from .config import StudyConfig

__all__ = [
    "CHI2_COLUMNS",
    "Progress",
    "Row",
    "CONVERGENCE_COLUMNS",
    "DISCREPANCY_COLUMNS",
    "Results",
    "SUMMARY_COLUMNS",
    "key",
]

CONVERGENCE_COLUMNS = (
    "integrand",
    "domain",
    "sampler",
    "points",
    "k",
    "n",
    "repetitions",
    "rmse",
    "relative_rmse",
    "mean_error",
    "mean_error_se",
    "mean_seconds",
    "median_seconds",
    "rounding_level",
)
"""Columns of ``convergence.csv``: one row per (integrand, sampler, points, n)."""

SUMMARY_COLUMNS = (
    "integrand",
    "domain",
    "sampler",
    "points",
    "status",
    "slope",
    "slope_se",
    "fit_points",
    "n_max",
    "rmse_at_n_max",
    "relative_rmse_at_n_max",
    "median_seconds_at_n_max",
    "efficiency",
    "relative_efficiency",
    "baseline",
)
"""Columns of ``summary.csv``: one row per (integrand, sampler, points)."""

DISCREPANCY_COLUMNS = (
    "sampler",
    "points",
    "k",
    "n",
    "repetitions",
    "discrepancy_rms",
    "discrepancy_min",
    "discrepancy_max",
    "weighted_discrepancy_rms",
    "random_expectation",
)
"""Columns of ``discrepancy.csv``: one row per (sampler, points, N)."""

CHI2_COLUMNS = (
    "sampler",
    "points",
    "domain",
    "reference",
    "n_samples",
    "statistic",
    "dof",
    "p_value",
    "threshold",
    "passed",
)
"""Columns of ``chi2.csv``: one row per test."""


Row = dict[str, Any]
"""A row of a table: column name -> value (str, int, float, bool, or a fit for ``discrepancy_fits``)."""


class Progress(Protocol):
    """The study's progress bar (a ``tqdm``): the two methods the stages call."""

    def set_postfix_str(self, s: str = "", refresh: bool = True) -> None: ...

    def update(self, n: float = 1) -> bool | None: ...


def key(text: str) -> int:
    """A stable non-negative integer for a name (part of a SeedSequence spawn key).

    Examples
    --------
    >>> from symsphere.apps.study.results import key
    >>> key("exp")
    113136155
    """
    return zlib.crc32(text.encode("utf-8"))


@dataclass
class Results:
    """What a study has measured so far: rows of the CSV tables, fits, timings; and its seed."""

    config: StudyConfig
    seed: int
    convergence: list[Row] = field(default_factory=list)
    summary: list[Row] = field(default_factory=list)
    discrepancy: list[Row] = field(default_factory=list)
    discrepancy_fits: list[Row] = field(default_factory=list)
    chi2: list[Row] = field(default_factory=list)
    stage_seconds: dict[str, float] = field(default_factory=dict)
    warp_chi2: dict[str, float] = field(default_factory=dict)  # warp name -> p-value

    def seed_sequence(self, *spawn_key: int) -> np.random.SeedSequence:
        """The seed of one random choice, identified by *spawn_key* (a stage number, then :func:`key` s)."""
        return np.random.SeedSequence(self.seed, spawn_key=tuple(int(k) for k in spawn_key))
