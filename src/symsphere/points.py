"""Point sets on the unit square: the inputs of the maps.

``'random'``      independent uniform points from a numpy ``Generator``;
``'stratified'``  a jittered sqrt(m) x sqrt(m) grid, one point per cell (m must be a square);
``'sobol'``       scrambled Sobol' points (``scipy.stats.qmc.Sobol``); scipy warns when m
                  is not a power of 2, since the balance properties need it;
``'halton'``      scrambled Halton points (``scipy.stats.qmc.Halton``);
any ``scipy.stats.qmc.QMCEngine`` with ``d == 2``, used as given (its state advances).
"""

from __future__ import annotations

import math

import numpy as np
from scipy.stats import qmc

from ._validation import check_choice, check_count, check_rng

__all__ = ["POINT_SETS", "unit_square_points"]

POINT_SETS = ("random", "stratified", "sobol", "halton")


def unit_square_points(m, points="random", rng=None, *, per_point=1):
    """Draw *m* points of the unit square.

    Parameters
    ----------
    m : int
        Number of points.
    points : {'random', 'stratified', 'sobol', 'halton'} or scipy.stats.qmc.QMCEngine
        The point set; an engine must have ``d == 2``.
    rng : None, int, numpy.random.SeedSequence or numpy.random.Generator
        Randomness for the random points, the jitter, or the scrambling.
    per_point : int
        How many outputs the caller makes from each point (48 or 24); only
        used to phrase errors in terms of the caller's ``n``.

    Returns
    -------
    ndarray, shape (m, 2), float64

    Examples
    --------
    >>> from symsphere.points import unit_square_points
    >>> unit_square_points(4, "stratified", rng=0).shape
    (4, 2)
    """
    m = check_count(m, "m")
    engine = check_points(points)
    rng = check_rng(rng)
    if engine is not None:
        return np.asarray(engine.random(m), dtype=np.float64)
    if points == "random":
        return rng.random((m, 2))
    if points == "stratified":
        return _jittered_grid(m, rng, per_point)
    engine_class = qmc.Sobol if points == "sobol" else qmc.Halton
    return engine_class(d=2, scramble=True, rng=rng).random(m)


def check_points(points):
    """Validate *points*; return the engine if it is a QMCEngine, else None."""
    if isinstance(points, qmc.QMCEngine):
        if points.d != 2:
            raise ValueError(f"'points' engine must have d=2 (points of the unit square), got d={points.d}")
        return points
    if not isinstance(points, str):
        raise TypeError(
            f"'points' must be one of {set(POINT_SETS)} or a scipy.stats.qmc.QMCEngine, "
            f"got {type(points).__name__}"
        )
    check_choice(points, "points", POINT_SETS)
    return None


def _jittered_grid(m, rng, per_point):
    side = math.isqrt(m)
    if side * side != m:
        options = [c for c in (side * side, (side + 1) ** 2) if c > 0]
        if per_point > 1:
            sizes = " or ".join(f"n={per_point * c}" for c in options)
            got = f"n={per_point * m} gives {m} (n/{per_point})"
        else:
            sizes = " or ".join(str(c) for c in options)
            got = f"got {m}"
        raise ValueError(f"points='stratified' needs a square number of base points; {got}; use {sizes}")
    cells = np.arange(m)
    corner = np.stack([cells // side, cells % side], axis=-1)
    return (corner + rng.random((m, 2))) / side
