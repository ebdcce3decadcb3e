"""The ways to sample a direction at a path vertex, in one vocabulary: ``strategy`` x ``points`` x ``method``.

One registry, :data:`SAMPLING_STRATEGIES`, answers "what can I pass" for the numba renderer
(:func:`symsphere.render.render`, ``symsphere render``) and the Mitsuba plugin ``symsphere_path``
(which first spoke these words); the convergence study speaks them too (its strategies are
``symmetric`` and the peers of :data:`symsphere.peers.PEERS`, by name).

- ``strategy``: how a direction is drawn (the orbit pattern, i.i.d. orbit members, the classic maps, or
  the BSDF's own sampling);
- ``points``: where its base points (the 2D points mapped onto the sphere) come from: a name of
  :data:`symsphere.POINT_SETS`, as for :func:`symsphere.sample_sphere`;
- ``method``: the map onto T0 (:data:`symsphere.METHODS`), for the strategies that map onto T0.

The renderer's earlier ``sampler=`` names joined two or three of these words into one (and reused map
names, ``equal_area``, ``paper1``, for the i.i.d. orbit samplers); :data:`SAMPLER_SPELLINGS` gives each
its words, and :func:`from_sampler` turns a deprecated spelling into them with the warning's text.

Examples
--------
>>> from symsphere._strategies import SAMPLING_STRATEGIES, from_sampler
>>> SAMPLING_STRATEGIES["symmetric_cosine"].render_points
('sobol', 'random', 'sobol_interlaced2', 'sobol_interlaced3')
>>> from_sampler("symmetric_cosine_sobol", None)
('symmetric_cosine', 'sobol', None, "sampler='symmetric_cosine_sobol' is deprecated; use strategy='symmetric_cosine', points='sobol'")
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

from ._validation import check_choice, short_repr
from .warps import METHODS

__all__ = [
    "SAMPLER_SPELLINGS",
    "SAMPLING_STRATEGIES",
    "Strategy",
    "check_words",
    "from_sampler",
    "legacy_sampler",
    "resolve",
    "words",
]


@dataclass(frozen=True, kw_only=True)
class Strategy:
    """A way to draw a direction at a vertex, and who takes it with which base points.

    Attributes
    ----------
    name : str
        The ``strategy`` word.
    summary : str
        One line: what it draws.
    group : int
        Samples of a pixel that share one base point on the hemisphere (the orbit's members taken in
        turn; twice as many through Lambertian transmission in the renderer); 1: independent samples.
    takes_method : bool
        Whether it maps base points onto T0, with ``method``.
    render_points : tuple of str
        The base points the numba renderer takes, its default first; () if the renderer does not
        offer the strategy.
    plugin_points : tuple of str
        The same for ``symsphere_path``.
    """

    name: str
    summary: str
    group: int
    takes_method: bool
    render_points: tuple[str, ...]
    plugin_points: tuple[str, ...]


_SYMMETRIC_POINTS = ("sobol", "random", "sobol_interlaced2", "sobol_interlaced3")
_ROWS = (  # name, group, takes_method, render_points, plugin_points, summary; sorted by name (every listing's order)
    ("bsdf", 1, False, (), ("random",), "the BSDF samples itself (Mitsuba's own sampling)"),
    ("cosine", 1, False, ("random",), ("random", "sobol"), "cosine-weighted, i.i.d. (Shirley-Chiu disk + Malley)"),
    ("orbit", 1, True, ("random",), (), "a base point mapped onto T0, a uniformly random orbit member; i.i.d."),
    ("symmetric", 24, True, _SYMMETRIC_POINTS, ("random", "sobol"), "the paper's scheme: the 24 orbit members of "
     "a base point mapped onto T0, taken in turn by a group of samples"),
    ("symmetric_cosine", 8, False, _SYMMETRIC_POINTS, ("random", "sobol"), "the 8 z-keeping images of a "
     "cosine-weighted base point of the wedge 0 <= phi <= pi/4, taken in turn"),
    ("uniform", 1, False, ("random",), (), "classic uniform directions, i.i.d."),
)  # fmt: skip

SAMPLING_STRATEGIES: dict[str, Strategy] = {
    row[0]: Strategy(
        name=row[0], group=row[1], takes_method=row[2], render_points=row[3], plugin_points=row[4], summary=row[5]
    )
    for row in _ROWS
}
"""dict: strategy name -> :class:`Strategy`, the one registry of the ways to sample at a vertex."""

SAMPLER_SPELLINGS: dict[str, tuple[str, str, str | None]] = {
    "symmetric": ("symmetric", "random", None),
    "symmetric_sobol": ("symmetric", "sobol", None),
    "equal_area": ("orbit", "random", "equal_area"),
    "paper1": ("orbit", "random", "paper1"),
    "paper2": ("orbit", "random", "paper2"),
    "uniform": ("uniform", "random", None),
    "cosine": ("cosine", "random", None),
    "symmetric_cosine": ("symmetric_cosine", "random", None),
    "symmetric_cosine_sobol": ("symmetric_cosine", "sobol", None),
    "symmetric_sobol_interlaced2": ("symmetric", "sobol_interlaced2", None),
    "symmetric_sobol_interlaced3": ("symmetric", "sobol_interlaced3", None),
    "symmetric_cosine_sobol_interlaced2": ("symmetric_cosine", "sobol_interlaced2", None),
    "symmetric_cosine_sobol_interlaced3": ("symmetric_cosine", "sobol_interlaced3", None),
}
"""dict: the renderer's deprecated ``sampler=`` names -> (strategy, points, method); method None: the
one given with the sampler (the symmetric samplers took ``method``), or none."""


def words(program: str) -> tuple[str, ...]:
    """The strategies *program* (``'render'`` or ``'plugin'``) takes, in the registry's order."""
    return tuple(s.name for s in SAMPLING_STRATEGIES.values() if _points_of(s, program))


def _points_of(strategy: Strategy, program: str) -> tuple[str, ...]:
    return strategy.render_points if program == "render" else strategy.plugin_points


def from_sampler(sampler: object, method: object) -> tuple[str, str, str | None, str]:
    """The words of the deprecated ``sampler=`` spelling *sampler* (with its *method*), and the warning.

    Returns (strategy, points, method, message); raises ValueError for a name that was never a sampler,
    or a method given to a sampler that did not take one (as the renderer always did).
    """
    if not isinstance(sampler, str) or sampler not in SAMPLER_SPELLINGS:
        raise ValueError(f"'sampler' must be one of {', '.join(SAMPLER_SPELLINGS)}; got {short_repr(sampler)}")
    strategy, points, implied = SAMPLER_SPELLINGS[sampler]
    if method is not None and implied is not None:
        raise ValueError(
            f"'method' does not apply to sampler={sampler!r}, which is named after its map; leave it out "
            f"(or use strategy={strategy!r}, method=...)"
        )
    if method is not None and not SAMPLING_STRATEGIES[strategy].takes_method:
        raise ValueError(f"'method' does not apply to sampler={sampler!r}; leave it out")
    new = f"strategy={strategy!r}, points={points!r}" + (f", method={implied!r}" if implied else "")
    return (
        strategy,
        points,
        implied if implied is not None else _method_or_none(method),
        (f"sampler={sampler!r} is deprecated; use {new}"),
    )


def _method_or_none(method: object) -> str | None:
    if method is not None and not isinstance(method, str):
        raise TypeError(f"'method' must be a str or None; got {short_repr(method)}")
    return method


def check_words(strategy: object, points: object, method: object, program: str) -> tuple[str, str, str | None]:
    """(strategy, points, method) checked for *program* (``'render'`` or ``'plugin'``), defaults filled in.

    *points* None: the strategy's default for *program* (the renderer: ``'sobol'`` for the symmetric
    strategies, else ``'random'``); *method* None: ``'equal_area'`` for the strategies that map onto T0,
    and stays None for the others (which refuse one).

    Examples
    --------
    >>> from symsphere._strategies import check_words
    >>> check_words("symmetric", None, None, "render")
    ('symmetric', 'sobol', 'equal_area')
    >>> check_words("cosine", "sobol", None, "render")
    Traceback (most recent call last):
        ...
    ValueError: 'sobol' is not a valid points for strategy='cosine' in the renderer; use one of {'random'}
    """
    name = str(check_choice(strategy, "strategy", words(program)))
    record = SAMPLING_STRATEGIES[name]
    allowed = _points_of(record, program)
    where = "the renderer" if program == "render" else "symsphere_path"
    checked = (
        allowed[0] if points is None else str(check_choice(points, f"points for strategy={name!r} in {where}", allowed))
    )
    given = _method_or_none(method)
    if record.takes_method:
        given = check_choice("equal_area" if given is None else given, "method", METHODS)
    elif given is not None:
        takers = ", ".join(s.name for s in SAMPLING_STRATEGIES.values() if s.takes_method and _points_of(s, program))
        raise ValueError(f"'method' applies only to the strategies {takers}; leave it out for strategy={name!r}")
    return name, checked, given


def legacy_sampler(strategy: str, points: str, method: str | None) -> str | None:
    """The deprecated ``sampler=`` name of these words, None if there is none."""
    for sampler, (s, p, m) in SAMPLER_SPELLINGS.items():
        if (s, p) == (strategy, points) and m in (None, method):
            return sampler
    return None


def resolve(
    sampler: object, strategy: object, points: object, method: object, program: str, stacklevel: int
) -> tuple[str, str, str | None]:
    """The checked words of a call that may use the deprecated *sampler* (then a DeprecationWarning).

    *strategy* is the caller's, whose default is ``'symmetric'``: given with *sampler*, another
    strategy or any *points* is refused (two spellings of one choice).  *stacklevel* is that of
    :func:`warnings.warn` counted from here (2: this function's caller).
    """
    if sampler is not None:
        if points is not None or strategy != "symmetric":
            raise ValueError("give 'strategy' and 'points', or the deprecated 'sampler', not both")
        strategy, points, method, message = from_sampler(sampler, method)
        warnings.warn(message, DeprecationWarning, stacklevel=stacklevel + 1)
    return check_words(strategy, points, method, program)
