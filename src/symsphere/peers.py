"""Peer samplers: the ways of sampling directions a user would pick instead.

Each peer is implemented here from its paper, with the conventions of
:func:`symsphere.sample_sphere`: ``rng=`` takes None, an int, a
``SeedSequence`` or a ``Generator``; ``dtype=`` is float64 or float32 (the
computation is in float64, cast at the end); outputs have shape (n, 3).
Densities are with respect to solid angle.  Where a peer is a map from the
unit square, the map and its inverse are public too (``square_to_*`` and
``*_to_square``, side by side with the pdf, as in pbrt-v4's
``util/sampling.h``), and its sampler takes quasi-Monte Carlo points
(``points=`` 'random', 'stratified', 'sobol', 'halton' or a
``scipy.stats.qmc.QMCEngine`` with ``d == 2``).

========================= =========== ===================================================
peer (key of `PEERS`)     domain      what
========================= =========== ===================================================
``classic``               sphere      z = 1 - 2u, phi = 2 pi v (Archimedes' hat-box map)
``classic_hemisphere``    hemisphere  z = u, phi = 2 pi v
``gaussian``              sphere      normalised standard normal vectors (random only)
``octahedral``            sphere      Clarberg's equal-area octahedral map (JGT 2008)
``octahedral_hemisphere`` hemisphere  its hemisphere variant (the square turned 45 deg)
``fibonacci``             sphere      spherical Fibonacci points (Keinert et al. 2015)
``fibonacci_rotated``     sphere      the same, under a uniformly random rotation
``arvo``                  sphere      Arvo (1995) on T0, then the 48 symmetric images
``cosine``                hemisphere  Shirley-Chiu concentric disk + Malley: cos(theta)/pi
========================= =========== ===================================================

Every map is exact and has no NaN or inf for u, v in {0, 1}, in float64 and
float32.

Arvo versus ``equal_area``: Arvo's algorithm picks a sub-triangle A B C' of
area u * area with C' on the edge AC, then samples the arc from B to C'
uniformly in cos of the distance to B.  With T0's vertices in the order
(A, B, C) = ((0, 0, 1), (1, 0, 1)/sqrt 2, (1, 1, 1)/sqrt 3), as the ``arvo``
peer uses them, the arcs start from (1, 0, 1)/sqrt 2: a different map with the
same (uniform) distribution.  With the order ((1, 0, 1)/sqrt 2, (0, 0, 1),
(1, 1, 1)/sqrt 3) the arcs start from the pole and the map *is*
``square_to_triangle(uv, 'equal_area')``, point by point (to 6e-16 in the
tests): ``equal_area`` is Arvo's map in closed form.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import numpy as np
from scipy.spatial.transform import Rotation

from ._validation import (
    _as_float_array,
    check_choice,
    check_count,
    check_directions,
    check_dtype,
    check_normal,
    check_rng,
    check_uv,
)
from .points import check_points, unit_square_points
from .symmetry import orbit

__all__ = [
    "PEERS",
    "Peer",
    "get_peer",
    # samplers
    "sample_arvo",
    "sample_classic",
    "sample_classic_hemisphere",
    "sample_cosine",
    "sample_fibonacci",
    "sample_gaussian",
    "sample_octahedral",
    "sample_octahedral_hemisphere",
    # maps, inverses and densities
    "square_to_uniform_sphere",
    "uniform_sphere_to_square",
    "uniform_sphere_pdf",
    "square_to_uniform_hemisphere",
    "uniform_hemisphere_to_square",
    "uniform_hemisphere_pdf",
    "square_to_octahedral_sphere",
    "octahedral_sphere_to_square",
    "square_to_octahedral_hemisphere",
    "octahedral_hemisphere_to_square",
    "square_to_concentric_disk",
    "concentric_disk_to_square",
    "square_to_cosine_hemisphere",
    "cosine_hemisphere_to_square",
    "cosine_hemisphere_pdf",
    "square_to_spherical_triangle",
    "spherical_triangle_to_square",
    "spherical_triangle_pdf",
    "fibonacci_points",
    "T0_VERTICES",
]

_INV_4PI = 1.0 / (4.0 * math.pi)
_INV_2PI = 1.0 / (2.0 * math.pi)

T0_VERTICES = np.array(
    [[0.0, 0.0, 1.0], [2**-0.5, 0.0, 2**-0.5], [3**-0.5, 3**-0.5, 3**-0.5]]
)
"""float array (3, 3): the vertices A = (0, 0, 1), B = (1, 0, 1)/sqrt 2, C = (1, 1, 1)/sqrt 3 of T0."""
T0_VERTICES.setflags(write=False)


@dataclass(frozen=True)
class Peer:
    """A registered peer sampler, so that a study can loop over `PEERS`.

    Attributes
    ----------
    name : str
        Key in `PEERS`.
    domain : {'sphere', 'hemisphere'}
        The hemisphere is about (0, 0, 1).
    sampler : callable
        ``sampler(n, *, points, rng, dtype)``; use :meth:`sample`.
    pdf : callable
        Density with respect to solid angle, ``pdf(d)`` for ``d`` of shape
        (..., 3) returns shape (...).  For ``fibonacci`` (deterministic) it is
        the density of its randomly rotated version, 1/(4 pi), so that
        ``mean(f / pdf)`` is the usual equal-weight rule.
    is_random : bool
        Whether the output depends on ``rng`` (False only for ``fibonacci``).
    is_map : bool
        Whether the peer is built on a map of the unit square, so that
        :meth:`sample` accepts every ``points=`` (quasi-Monte Carlo too).
    independent_rows : bool
        Whether the rows of one call are independent samples (False for the
        rotated Fibonacci set and for ``arvo``, whose rows come in orbits of
        48): a chi-square test needs independent rows.
    multiple : int
        ``n`` must be a multiple of this (48 for ``arvo``).
    forward, inverse : callable or None
        The map ``(m, 2) -> (m, 3)`` onto the domain and its inverse (the
        public, validating ``square_to_*`` / ``*_to_square`` functions).  None
        for ``arvo``, whose map is onto T0 (:func:`square_to_spherical_triangle`
        with ``T0_VERTICES``) followed by the 48 images.
    reference : str
        Where the method comes from.
    """

    name: str
    domain: str
    sampler: Callable
    pdf: Callable
    is_random: bool
    is_map: bool
    independent_rows: bool
    multiple: int = 1
    forward: Callable | None = None
    inverse: Callable | None = None
    reference: str = ""

    def sample(self, n, rng=None, dtype=np.float64, points="random"):
        """Draw ``n`` directions; ``points`` other than 'random' needs ``is_map``.

        Examples
        --------
        >>> from symsphere.peers import PEERS
        >>> PEERS["octahedral"].sample(4, rng=0, points="sobol").shape
        (4, 3)
        """
        if not self.is_map and not (isinstance(points, str) and points == "random"):
            raise ValueError(
                f"'points' must be 'random' for the peer {self.name!r}, which is not a map of "
                f"the unit square; got {points!r}"
            )
        return self.sampler(n, points=points, rng=rng, dtype=dtype)


def get_peer(name) -> Peer:
    """The registered :class:`Peer` called *name*; ValueError naming 'peer' otherwise.

    Examples
    --------
    >>> from symsphere.peers import get_peer
    >>> get_peer("cosine").domain
    'hemisphere'
    """
    return PEERS[check_choice(name, "peer", tuple(PEERS))]


# =============================================================================
# Samplers
# =============================================================================


def sample_classic(n, *, points="random", rng=None, dtype=np.float64):
    """Uniform directions on the sphere by z = 1 - 2u, phi = 2 pi v.

    The map of :func:`square_to_uniform_sphere` (pbrt-v4 ``SampleUniformSphere``,
    Mitsuba 3 ``square_to_uniform_sphere``) applied to points of the square.

    Parameters
    ----------
    n : int
        Number of directions, positive.
    points : {'random', 'stratified', 'sobol', 'halton'} or scipy.stats.qmc.QMCEngine
        The points of the unit square (``'stratified'`` needs ``n`` to be a square).
    rng : None, int, numpy.random.SeedSequence or numpy.random.Generator
    dtype : {numpy.float64, numpy.float32}

    Returns
    -------
    ndarray, shape (n, 3)

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere.peers import sample_classic
    >>> d = sample_classic(1000, rng=1)
    >>> d.shape, bool(np.allclose(np.linalg.norm(d, axis=1), 1))
    ((1000, 3), True)
    """
    return _sample_map(_uniform_sphere, n, points, rng, dtype)


def sample_classic_hemisphere(n, *, points="random", rng=None, dtype=np.float64):
    """Uniform directions on the hemisphere z >= 0 by z = u, phi = 2 pi v.

    Parameters and returns as in :func:`sample_classic`.

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere.peers import sample_classic_hemisphere
    >>> bool(np.all(sample_classic_hemisphere(100, rng=2)[:, 2] >= 0))
    True
    """
    return _sample_map(_uniform_hemisphere, n, points, rng, dtype)


def sample_gaussian(n, *, rng=None, dtype=np.float64):
    """Uniform directions on the sphere: normalised standard normal vectors.

    As ``scipy.stats.uniform_direction`` does (Muller 1959, Marsaglia 1972):
    the standard normal distribution in R^3 is rotation invariant, so its
    direction is uniform.  A zero vector (probability 0, but possible in
    floating point) is drawn again.

    Parameters
    ----------
    n : int
    rng : None, int, numpy.random.SeedSequence or numpy.random.Generator
    dtype : {numpy.float64, numpy.float32}

    Returns
    -------
    ndarray, shape (n, 3)

    Examples
    --------
    >>> from symsphere.peers import sample_gaussian
    >>> sample_gaussian(5, rng=0, dtype="float32").dtype
    dtype('float32')
    """
    n = check_count(n, "n")
    dtype = check_dtype(dtype)
    rng = check_rng(rng)
    g = rng.standard_normal((n, 3))
    norm = np.linalg.norm(g, axis=1)
    while np.any(norm == 0):  # pragma: no cover - probability ~ 0
        zero = norm == 0
        g[zero] = rng.standard_normal((int(zero.sum()), 3))
        norm = np.linalg.norm(g, axis=1)
    return (g / norm[:, None]).astype(dtype)


def sample_octahedral(n, *, points="random", rng=None, dtype=np.float64):
    """Uniform directions on the sphere by Clarberg's octahedral map.

    The map of :func:`square_to_octahedral_sphere`; parameters and returns as
    in :func:`sample_classic`.

    Examples
    --------
    >>> from symsphere.peers import sample_octahedral
    >>> sample_octahedral(256, points="sobol", rng=3).shape
    (256, 3)
    """
    return _sample_map(_octahedral_sphere, n, points, rng, dtype)


def sample_octahedral_hemisphere(n, *, points="random", rng=None, dtype=np.float64):
    """Uniform directions on the hemisphere z >= 0 by Clarberg's hemisphere map.

    The map of :func:`square_to_octahedral_hemisphere`; parameters and returns
    as in :func:`sample_classic`.

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere.peers import sample_octahedral_hemisphere
    >>> bool(np.all(sample_octahedral_hemisphere(64, rng=4)[:, 2] >= 0))
    True
    """
    return _sample_map(_octahedral_hemisphere, n, points, rng, dtype)


def sample_cosine(n, *, points="random", rng=None, dtype=np.float64):
    """Cosine-weighted directions on the hemisphere z >= 0 (pdf cos(theta)/pi).

    Shirley & Chiu's concentric map onto the disk, lifted to the hemisphere
    by Malley's method: :func:`square_to_cosine_hemisphere`.  Parameters and
    returns as in :func:`sample_classic`.

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere.peers import sample_cosine
    >>> d = sample_cosine(20000, rng=5)
    >>> round(float(d[:, 2].mean()), 2)      # E[cos theta] = 2/3
    0.67
    """
    return _sample_map(_cosine_hemisphere, n, points, rng, dtype)


def sample_fibonacci(n, *, randomize=False, rng=None, dtype=np.float64):
    """The spherical Fibonacci point set, optionally under a random rotation.

    Point i of n (Keinert et al., "Spherical Fibonacci Mapping", SIGGRAPH Asia
    2015, eq. 2): ``z_i = 1 - (2 i + 1)/n``, ``phi_i = 2 pi frac(i / Phi)`` with
    the golden ratio Phi; see :func:`fibonacci_points`.  The set is
    deterministic.  With ``randomize=True`` it is rotated by one uniformly
    random rotation (``scipy.spatial.transform.Rotation.random``), so that
    every point is marginally uniform and ``4 pi mean(f)`` is an unbiased
    estimate of the integral of f; the points of one set stay dependent.

    Parameters
    ----------
    n : int
    randomize : bool
        Apply a uniformly random rotation drawn from ``rng``.
    rng : None, int, numpy.random.SeedSequence or numpy.random.Generator
        Only used when ``randomize`` is True (but validated always).
    dtype : {numpy.float64, numpy.float32}

    Returns
    -------
    ndarray, shape (n, 3)

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere.peers import sample_fibonacci
    >>> d = sample_fibonacci(10_000)
    >>> f = np.exp(d @ [0.3, -0.5, 0.6])
    >>> a = np.sqrt(0.3**2 + 0.5**2 + 0.6**2)
    >>> bool(abs(4 * np.pi * f.mean() / (4 * np.pi * np.sinh(a) / a) - 1) < 1e-5)
    True
    """
    n = check_count(n, "n")
    dtype = check_dtype(dtype)
    rng = check_rng(rng)
    if not isinstance(randomize, (bool, np.bool_)):
        raise TypeError(f"'randomize' must be a bool, got {type(randomize).__name__}")
    d = _fibonacci(n)
    if randomize:
        d = Rotation.random(rng=rng).apply(d)
    return d.astype(dtype)


def sample_arvo(n, *, points="random", rng=None, dtype=np.float64):
    """Uniform directions on the sphere: Arvo's triangle sampling on T0, then symmetry.

    ``n / 48`` points of the unit square are mapped onto T0 by Arvo's
    algorithm for a general spherical triangle (:func:`square_to_spherical_triangle`
    with ``T0_VERTICES`` in the order A = (0, 0, 1), B = (1, 0, 1)/sqrt 2,
    C = (1, 1, 1)/sqrt 3), and each is replaced by its 48 images
    (:func:`symsphere.orbit`), as :func:`symsphere.sample_sphere` does.

    Parameters
    ----------
    n : int
        A positive multiple of 48.
    points, rng, dtype
        As in :func:`sample_classic` (``'stratified'`` needs ``n/48`` to be a square).

    Returns
    -------
    ndarray, shape (n, 3)
        Row ``48 i + k`` is ``orbit(base_i)[k]``.

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere.peers import sample_arvo
    >>> d = sample_arvo(96, rng=6)
    >>> d.shape, bool(np.allclose(d[:48].sum(axis=0), 0))
    ((96, 3), True)
    """
    n = check_count(n, "n", multiple=48)
    dtype = check_dtype(dtype)
    check_points(points)
    uv = unit_square_points(n // 48, points, rng, per_point=48)
    base = _arvo_forward(uv, *_triangle_setup(T0_VERTICES))
    return orbit(base).reshape(n, 3).astype(dtype)


# =============================================================================
# Maps, inverses, densities
# =============================================================================


def square_to_uniform_sphere(uv):
    """Map the unit square onto the sphere: z = 1 - 2u, phi = 2 pi v.

    Archimedes' hat-box theorem: the area of the zone below height z is
    proportional to z, so a uniform z and a uniform phi give a uniform
    direction.  The radius sin(theta) = 2 sqrt(u (1 - u)), which does not
    cancel near the poles as sqrt(1 - z^2) does.

    Parameters
    ----------
    uv : array_like, shape (..., 2)
        Points of [0, 1]^2.

    Returns
    -------
    ndarray, shape (..., 3)
        Unit directions, in the dtype of *uv* (float64 for integers).

    Examples
    --------
    >>> from symsphere.peers import square_to_uniform_sphere
    >>> square_to_uniform_sphere([[0.0, 0.0], [0.5, 0.0], [1.0, 0.0]])
    array([[ 0.,  0.,  1.],
           [ 1.,  0.,  0.],
           [ 0.,  0., -1.]])
    """
    return _public_forward(_uniform_sphere, uv)


def uniform_sphere_to_square(d):
    """Inverse of :func:`square_to_uniform_sphere`.

    ``u = (1 - z)/2``, evaluated as ``(x^2 + y^2) / (2 (1 + z))`` for z > 0
    (no cancellation near the north pole); ``v = atan2(y, x) / (2 pi)``
    wrapped into [0, 1).  At the poles v = 0.

    Parameters
    ----------
    d : array_like, shape (..., 3)
        Unit directions.

    Returns
    -------
    ndarray, shape (..., 2)

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere.peers import square_to_uniform_sphere, uniform_sphere_to_square
    >>> uv = np.array([0.2, 0.7])
    >>> bool(np.allclose(uniform_sphere_to_square(square_to_uniform_sphere(uv)), uv))
    True
    """
    return _public_inverse(_uniform_sphere_inverse, d)


def uniform_sphere_pdf(d):
    """The uniform density on the sphere, 1/(4 pi), of shape ``d.shape[:-1]``.

    Examples
    --------
    >>> from symsphere.peers import uniform_sphere_pdf
    >>> float(uniform_sphere_pdf([0.0, 0.0, 1.0]) * 4 * 3.141592653589793)
    1.0
    """
    d = check_directions(d, "d")
    return np.full(d.shape[:-1], _INV_4PI)


def square_to_uniform_hemisphere(uv):
    """Map the unit square onto the hemisphere z >= 0: z = u, phi = 2 pi v.

    sin(theta) = sqrt((1 - u)(1 + u)).  pbrt-v4 ``SampleUniformHemisphere``.

    Examples
    --------
    >>> from symsphere.peers import square_to_uniform_hemisphere
    >>> square_to_uniform_hemisphere([[0.0, 0.25], [1.0, 0.0]])
    array([[6.123234e-17, 1.000000e+00, 0.000000e+00],
           [0.000000e+00, 0.000000e+00, 1.000000e+00]])
    """
    return _public_forward(_uniform_hemisphere, uv)


def uniform_hemisphere_to_square(d):
    """Inverse of :func:`square_to_uniform_hemisphere`: u = z, v = phi / (2 pi).

    Examples
    --------
    >>> from symsphere.peers import uniform_hemisphere_to_square
    >>> uniform_hemisphere_to_square([0.0, -1.0, 0.0])
    array([0.  , 0.75])
    """
    return _public_inverse(_uniform_hemisphere_inverse, d, hemisphere=True)


def uniform_hemisphere_pdf(d):
    """The uniform density on the hemisphere z >= 0: 1/(2 pi) there, 0 below.

    Examples
    --------
    >>> from symsphere.peers import uniform_hemisphere_pdf
    >>> uniform_hemisphere_pdf([[0.0, 0.6, 0.8], [0.0, 0.6, -0.8]]) * 2 * 3.141592653589793
    array([1., 0.])
    """
    d = check_directions(d, "d")
    return np.where(d[..., 2] >= 0, _INV_2PI, 0.0)


def square_to_octahedral_sphere(uv):
    """Clarberg's equal-area map of the square onto the sphere (JGT 2008).

    With (a, b) = 2 (u, v) - 1, the square is an unfolded octahedron: the
    diamond |a| + |b| <= 1 is the upper hemisphere, the four corner triangles
    fold onto the lower one.  In each octant the L1 "radius" r (``|a| + |b|``
    inside the diamond, ``2 - |a| - |b|`` outside) sets 1 - |z| = r^2, which is
    equal-area because the area of a triangle with legs r grows like r^2 and
    the polar cap like 1 - |z|; the position along the octant's edge,
    linear in the square, sets the azimuth linearly.  So every octant of the
    square (area 1/8) goes to an octant of the sphere (area pi/2): the
    density is 1/(4 pi).  sin(theta) = r sqrt(2 - r^2), without cancellation.

    Parameters
    ----------
    uv : array_like, shape (..., 2)

    Returns
    -------
    ndarray, shape (..., 3)

    Examples
    --------
    >>> from symsphere.peers import square_to_octahedral_sphere
    >>> square_to_octahedral_sphere([[0.5, 0.5], [1.0, 0.5], [0.0, 0.0]])
    array([[ 0.,  0.,  1.],
           [ 1.,  0.,  0.],
           [-0., -0., -1.]])
    """
    return _public_forward(_octahedral_sphere, uv)


def octahedral_sphere_to_square(d):
    """Inverse of :func:`square_to_octahedral_sphere`.

    r = sqrt(1 - |z|), evaluated as sqrt((x^2 + y^2) / (1 + |z|)); the share
    of the octant's edge is (2/pi) atan2(|y|, |x|); the signs of x and y pick
    the quadrant of the square, the sign of z the diamond or a corner.

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere.peers import octahedral_sphere_to_square, square_to_octahedral_sphere
    >>> uv = np.array([[0.1, 0.8], [0.6, 0.3]])
    >>> bool(np.allclose(octahedral_sphere_to_square(square_to_octahedral_sphere(uv)), uv))
    True
    """
    return _public_inverse(_octahedral_sphere_inverse, d)


def square_to_octahedral_hemisphere(uv):
    """Clarberg's equal-area map of the square onto the hemisphere z >= 0.

    The square [-1, 1]^2 is turned by 45 degrees and shrunk onto the diamond
    |a'| + |b'| <= 1 (a' = (a + b)/2, b' = (b - a)/2, a constant Jacobian of
    1/2), which the upper half of :func:`square_to_octahedral_sphere` lifts
    onto the hemisphere: density 1/(2 pi).

    Examples
    --------
    >>> from symsphere.peers import square_to_octahedral_hemisphere
    >>> square_to_octahedral_hemisphere([[0.5, 0.5], [1.0, 1.0]])
    array([[0., 0., 1.],
           [1., 0., 0.]])
    """
    return _public_forward(_octahedral_hemisphere, uv)


def octahedral_hemisphere_to_square(d):
    """Inverse of :func:`square_to_octahedral_hemisphere`.

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere.peers import octahedral_hemisphere_to_square, square_to_octahedral_hemisphere
    >>> uv = np.array([0.3, 0.9])
    >>> bool(np.allclose(octahedral_hemisphere_to_square(square_to_octahedral_hemisphere(uv)), uv))
    True
    """
    return _public_inverse(_octahedral_hemisphere_inverse, d, hemisphere=True)


def square_to_concentric_disk(uv):
    """Shirley & Chiu's concentric map of the square onto the unit disk (1997).

    With (a, b) = 2 (u, v) - 1, concentric squares go to concentric circles:
    if |a| >= |b|, radius a and angle (pi/4)(b/a); else radius b and angle
    pi/2 - (pi/4)(a/b).  Each of the four triangular sectors is stretched
    uniformly, so the map is area-preserving up to the constant pi/4 per unit
    square area: density 1/pi on the disk.

    Parameters
    ----------
    uv : array_like, shape (..., 2)

    Returns
    -------
    ndarray, shape (..., 2)
        Points of the unit disk.

    Examples
    --------
    >>> from symsphere.peers import square_to_concentric_disk
    >>> square_to_concentric_disk([[0.5, 0.5], [1.0, 0.5], [0.5, 0.0]])
    array([[ 0.,  0.],
           [ 1.,  0.],
           [ 0., -1.]])
    """
    uv = check_uv(uv)
    return _concentric(uv.astype(np.float64)).astype(uv.dtype, copy=False)


def concentric_disk_to_square(p):
    """Inverse of :func:`square_to_concentric_disk`.

    Parameters
    ----------
    p : array_like, shape (..., 2)
        Points of the closed unit disk.

    Returns
    -------
    ndarray, shape (..., 2)

    Examples
    --------
    >>> from symsphere.peers import concentric_disk_to_square
    >>> concentric_disk_to_square([[0.0, 0.0], [0.0, 1.0]])
    array([[0.5, 0.5],
           [0.5, 1. ]])
    """
    arr = _as_float_array(p, "p")
    if arr.ndim == 0 or arr.shape[-1] != 2:
        raise ValueError(f"'p' must have shape (..., 2), got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError("'p' must be finite (no NaN or inf)")
    a64 = arr.astype(np.float64)
    if np.any(np.hypot(a64[..., 0], a64[..., 1]) > 1 + 1e-6):
        raise ValueError("'p' must lie in the closed unit disk")
    return _concentric_inverse(a64).astype(arr.dtype, copy=False)


def square_to_cosine_hemisphere(uv):
    """Cosine-weighted hemisphere: the concentric disk lifted by Malley's method.

    A uniform point (x, y) of the unit disk, lifted vertically to
    z = sqrt(1 - x^2 - y^2), has density (1/pi) cos(theta) in solid angle,
    since the projection onto the disk scales area by cos(theta)
    (Malley's method; pbrt-v4 ``SampleCosineHemisphere``).  z is evaluated
    as sqrt((1 - rho)(1 + rho)), rho = max(|a|, |b|) the disk radius.

    Examples
    --------
    >>> from symsphere.peers import square_to_cosine_hemisphere
    >>> square_to_cosine_hemisphere([[0.5, 0.5], [1.0, 0.5]])
    array([[0., 0., 1.],
           [1., 0., 0.]])
    """
    return _public_forward(_cosine_hemisphere, uv)


def cosine_hemisphere_to_square(d):
    """Inverse of :func:`square_to_cosine_hemisphere`: drop z, invert the disk map.

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere.peers import cosine_hemisphere_to_square, square_to_cosine_hemisphere
    >>> uv = np.array([0.15, 0.65])
    >>> bool(np.allclose(cosine_hemisphere_to_square(square_to_cosine_hemisphere(uv)), uv))
    True
    """
    return _public_inverse(_cosine_hemisphere_inverse, d, hemisphere=True)


def cosine_hemisphere_pdf(d):
    """Density cos(theta)/pi of :func:`square_to_cosine_hemisphere`; 0 for z < 0.

    Examples
    --------
    >>> from symsphere.peers import cosine_hemisphere_pdf
    >>> cosine_hemisphere_pdf([[0.0, 0.0, 1.0], [0.6, 0.0, -0.8]]) * 3.141592653589793
    array([1., 0.])
    """
    d = check_directions(d, "d")
    d64 = d.astype(np.float64)
    return np.maximum(d64[..., 2], 0.0) / (np.linalg.norm(d64, axis=-1) * math.pi)


def square_to_spherical_triangle(uv, a, b, c):
    """Arvo's area-preserving map of the square onto a spherical triangle ABC.

    Arvo, "Stratified sampling of spherical triangles", SIGGRAPH 1995.
    u selects the sub-triangle A B C' of area u * area(ABC), with C' on the
    edge AC: the angle at A is alpha, and the area condition
    alpha + beta' + gamma' - pi = A' together with the spherical law of
    cosines gives cos(b') = |AC'| in closed form (the paper's q).  Then v
    places the point on the arc from B to C' with cos of its distance to B
    uniform on [C'.B, 1], which is uniform in area because the strip between
    two such arcs through B has area proportional to d(cos).

    Parameters
    ----------
    uv : array_like, shape (..., 2)
    a, b, c : array_like of 3 floats
        The vertices (normalised; the triangle must not be degenerate).
        B is the vertex the arcs of the second step start from; u = 0 is the
        edge AB, u = 1 the edge BC, v = 0 the vertex B, v = 1 the edge AC.

    Returns
    -------
    ndarray, shape (..., 3)
        Unit directions in the triangle, with density 1/area.

    Examples
    --------
    >>> from symsphere.peers import T0_VERTICES, square_to_spherical_triangle
    >>> A, B, C = T0_VERTICES
    >>> square_to_spherical_triangle([[0.7, 0.0], [0.0, 1.0], [1.0, 1.0]], A, B, C).round(12) + 0.0
    array([[0.70710678, 0.        , 0.70710678],
           [0.        , 0.        , 1.        ],
           [0.57735027, 0.57735027, 0.57735027]])
    """
    uv = check_uv(uv)
    setup = _triangle_setup(_check_triangle(a, b, c))
    return _arvo_forward(uv.astype(np.float64), *setup).astype(uv.dtype, copy=False)


def spherical_triangle_to_square(d, a, b, c):
    """Inverse of :func:`square_to_spherical_triangle`.

    The arc from B through d meets the edge AC at C' (the intersection of
    the two great circles); u = area(A B C') / area(ABC) and
    v = (1 - d.B) / (1 - C'.B), both differences evaluated as |p - B|^2 / 2.
    At d = B, u = 0 by convention.

    Parameters
    ----------
    d : array_like, shape (..., 3)
        Unit directions in the triangle.
    a, b, c : array_like of 3 floats

    Returns
    -------
    ndarray, shape (..., 2)

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere.peers import T0_VERTICES, spherical_triangle_to_square, square_to_spherical_triangle
    >>> uv = np.array([0.3, 0.6])
    >>> p = square_to_spherical_triangle(uv, *T0_VERTICES)
    >>> bool(np.allclose(spherical_triangle_to_square(p, *T0_VERTICES), uv))
    True
    """
    d = check_directions(d, "d")
    setup = _triangle_setup(_check_triangle(a, b, c))
    return _arvo_inverse(d.astype(np.float64), *setup).astype(d.dtype, copy=False)


def spherical_triangle_pdf(d, a, b, c):
    """Density of :func:`square_to_spherical_triangle`: 1/area inside ABC, 0 outside.

    Inside means on the inner side of the three edges' great circles, with a
    tolerance of 1e-12.  The area is Van Oosterom & Strackee's
    ``2 atan2(|A.(B x C)|, 1 + A.B + B.C + C.A)``.

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere.peers import T0_VERTICES, spherical_triangle_pdf
    >>> spherical_triangle_pdf([[0.3, 0.2, 0.93273791], [0.0, 0.0, -1.0]], *T0_VERTICES) * np.pi
    array([12.,  0.])
    """
    d = check_directions(d, "d")
    verts = _check_triangle(a, b, c)
    A, B, C = verts
    orient = np.sign(np.dot(A, np.cross(B, C)))
    d64 = d.astype(np.float64)
    inside = np.ones(d.shape[:-1], dtype=bool)
    for p, q in ((A, B), (B, C), (C, A)):
        inside &= orient * (d64 @ np.cross(p, q)) >= -1e-12
    return np.where(inside, 1.0 / _triangle_area(A, B, C), 0.0)


def fibonacci_points(n):
    """The n spherical Fibonacci points (Keinert et al. 2015), deterministic.

    ``z_i = 1 - (2 i + 1)/n`` and ``phi_i = 2 pi frac(i (Phi - 1))`` for
    i = 0, ..., n - 1 (1/Phi = Phi - 1).  The fractional part is computed in
    64-bit fixed point: ``i * floor(2^64 (Phi - 1)) mod 2^64`` is an exact
    integer product, so phi_i has an error below 2 pi i 2^-64 (about 3e-10
    at i = 10^9) instead of the ~i 1e-16 of the float64 product.
    sin(theta_i) = sqrt((2 i + 1)(2 n - 2 i - 1))/n, without cancellation.

    Parameters
    ----------
    n : int

    Returns
    -------
    ndarray, shape (n, 3), float64

    Examples
    --------
    >>> from symsphere.peers import fibonacci_points
    >>> fibonacci_points(4).round(6)
    array([[ 0.661438,  0.      ,  0.75    ],
           [-0.713954, -0.654041,  0.25    ],
           [ 0.08465 ,  0.964538, -0.25    ],
           [ 0.402444, -0.524918, -0.75    ]])
    """
    return _fibonacci(check_count(n, "n"))


# =============================================================================
# Registry
# =============================================================================


def _random_only(sampler):
    def wrapped(n, *, points="random", rng=None, dtype=np.float64):
        return sampler(n, rng=rng, dtype=dtype)

    return wrapped


def _fibonacci_sampler(randomize):
    def wrapped(n, *, points="random", rng=None, dtype=np.float64):
        return sample_fibonacci(n, randomize=randomize, rng=rng, dtype=dtype)

    return wrapped


# =============================================================================
# Private helpers: trust their inputs (float64 arrays)
# =============================================================================


def _sample_map(forward, n, points, rng, dtype):
    n = check_count(n, "n")
    dtype = check_dtype(dtype)
    check_points(points)
    return forward(unit_square_points(n, points, rng)).astype(dtype)


def _public_forward(forward, uv):
    uv = check_uv(uv)
    return forward(uv.astype(np.float64)).astype(uv.dtype, copy=False)


def _public_inverse(inverse, d, hemisphere=False):
    d = check_directions(d, "d")
    d64 = d.astype(np.float64)
    if hemisphere and np.any(d64[..., 2] < -1e-12):
        raise ValueError("'d' must have z >= 0 (directions of the hemisphere about (0, 0, 1))")
    return inverse(d64).astype(d.dtype, copy=False)


def _wrap_unit(t):
    """Fold t into [0, 1): -0.25 -> 0.75, and 1 - tiny rounding to 1 -> 0."""
    t = np.where(t < 0, t + 1.0, t)
    return np.where(t >= 1.0, 0.0, t)


# --- elementwise formulas -------------------------------------------------------------
# Each map below is written once, as an elementwise function of (u, v) that numpy applies to
# arrays and numba compiles for scalars (``register_jitable``): the path tracer's kernels
# (symsphere.render._integrator) call the very same formulas.  ``_pick`` is np.where for
# arrays and a conditional expression in numba.

from numba.extending import overload as _overload  # noqa: E402
from numba.extending import register_jitable as _register_jitable  # noqa: E402


def _pick(condition, a, b):
    """``np.where(condition, a, b)``; in numba code, ``a if condition else b`` (scalars)."""
    return np.where(condition, a, b)


@_overload(_pick)
def _pick_scalar(condition, a, b):
    def impl(condition, a, b):
        return a if condition else b

    return impl


@_register_jitable
def uniform_sphere_point(u, v):
    """Elementwise: pbrt-v4 / Mitsuba, z = 1 - 2u, r = sqrt(1 - z^2) = 2 sqrt(u (1 - u)), phi = 2 pi v."""
    z = 1.0 - 2.0 * u
    r = 2.0 * np.sqrt(u * (1.0 - u))
    phi = 2.0 * np.pi * v
    return r * np.cos(phi), r * np.sin(phi), z


@_register_jitable
def uniform_hemisphere_point(u, v):
    """Elementwise: z = u, r = sqrt((1 - u)(1 + u)), phi = 2 pi v (pbrt-v4 SampleUniformHemisphere)."""
    r = np.sqrt((1.0 - u) * (1.0 + u))
    phi = 2.0 * np.pi * v
    return r * np.cos(phi), r * np.sin(phi), u


@_register_jitable
def concentric_disk_point(u, v):
    """Elementwise Shirley & Chiu (1997): concentric squares of [0, 1]^2 -> concentric circles of the disk."""
    a = 2.0 * u - 1.0
    b = 2.0 * v - 1.0
    wide = np.abs(a) >= np.abs(b)
    r = _pick(wide, a, b)
    safe = _pick(r != 0, r, 1.0)
    # angle (pi/4)(b/a) in the wide sectors, pi/2 - (pi/4)(a/b) in the others:
    # x = r cos, y = r sin; for the others cos(pi/2 - t) = sin t.
    t = 0.25 * np.pi * _pick(wide, b, a) / safe
    c, s = np.cos(t), np.sin(t)
    return r * _pick(wide, c, s), r * _pick(wide, s, c)


@_register_jitable
def cosine_hemisphere_point(u, v):
    """Elementwise: the concentric disk lifted to the hemisphere (Malley), z = sqrt((1 - rho)(1 + rho))."""
    x, y = concentric_disk_point(u, v)
    rho = np.maximum(np.abs(2.0 * u - 1.0), np.abs(2.0 * v - 1.0))
    z = np.sqrt(np.maximum((1.0 - rho) * (1.0 + rho), 0.0))
    return x, y, z


def _uniform_sphere(uv):
    return np.stack(uniform_sphere_point(uv[..., 0], uv[..., 1]), axis=-1)


def _uniform_sphere_inverse(d):
    x, y, z = d[..., 0], d[..., 1], d[..., 2]
    # 1 - z = (x^2 + y^2)/(1 + z) for unit d: no cancellation in the north.
    u_north = (x * x + y * y) / (2.0 * (1.0 + np.abs(z)))
    u = np.where(z > 0, u_north, 0.5 * (1.0 - z))
    v = _wrap_unit(np.arctan2(y, x) / (2.0 * np.pi))
    return np.stack([np.clip(u, 0.0, 1.0), v], axis=-1)


def _uniform_hemisphere(uv):
    return np.stack(uniform_hemisphere_point(uv[..., 0], uv[..., 1]), axis=-1)


def _uniform_hemisphere_inverse(d):
    u = np.clip(d[..., 2], 0.0, 1.0)
    v = _wrap_unit(np.arctan2(d[..., 1], d[..., 0]) / (2.0 * np.pi))
    return np.stack([u, v], axis=-1)


def _octant_lift(p, q, upper):
    """Lift the octant point with L1 coordinates (p, q) >= 0, r = p + q <= 1.

    1 - |z| = r^2; azimuth within the quadrant phi = (pi/2) q/r, written as
    cos(phi) = sin((pi/2) p/r), sin(phi) = sin((pi/2) q/r) so that the axes
    (p = 0 or q = 0) come out exactly.  Returns |x|, |y|, z.
    """
    r = p + q
    safe = np.where(r > 0, r, 1.0)
    sin_theta = r * np.sqrt(np.maximum(2.0 - r * r, 0.0))
    ax = sin_theta * np.sin(0.5 * np.pi * p / safe)
    ay = sin_theta * np.sin(0.5 * np.pi * q / safe)
    z = np.where(upper, 1.0 - r * r, r * r - 1.0)
    return ax, ay, z


def _octant_unlift(d):
    """(p, q, upper) of unit directions: the inverse of :func:`_octant_lift`."""
    x, y, z = d[..., 0], d[..., 1], d[..., 2]
    ax, ay = np.abs(x), np.abs(y)
    r = np.sqrt((ax * ax + ay * ay) / (1.0 + np.abs(z)))  # sqrt(1 - |z|)
    r = np.minimum(r, 1.0)
    p = r * np.arctan2(ax, ay) * (2.0 / np.pi)
    q = r * np.arctan2(ay, ax) * (2.0 / np.pi)
    return p, q, z >= 0


def _octahedral_sphere(uv):
    # Clarberg (2008): inner diamond -> upper hemisphere; corner triangles fold below.
    a = 2.0 * uv[..., 0] - 1.0
    b = 2.0 * uv[..., 1] - 1.0
    aa, ab = np.abs(a), np.abs(b)
    upper = aa + ab <= 1.0
    # Outside the diamond the L1 coordinates of the fold are (1 - |b|, 1 - |a|).
    p = np.where(upper, aa, 1.0 - ab)
    q = np.where(upper, ab, 1.0 - aa)
    ax, ay, z = _octant_lift(p, q, upper)
    return np.stack([np.copysign(ax, a), np.copysign(ay, b), z], axis=-1)


def _octahedral_sphere_inverse(d):
    p, q, upper = _octant_unlift(d)
    aa = np.where(upper, p, 1.0 - q)
    ab = np.where(upper, q, 1.0 - p)
    a = np.copysign(aa, d[..., 0])
    b = np.copysign(ab, d[..., 1])
    return np.clip(np.stack([0.5 * (a + 1.0), 0.5 * (b + 1.0)], axis=-1), 0.0, 1.0)


def _octahedral_hemisphere(uv):
    # Turn the square [-1, 1]^2 by 45 degrees onto the diamond, then lift the upper half.
    a = 2.0 * uv[..., 0] - 1.0
    b = 2.0 * uv[..., 1] - 1.0
    s, t = 0.5 * (a + b), 0.5 * (b - a)
    ax, ay, z = _octant_lift(np.abs(s), np.abs(t), True)
    return np.stack([np.copysign(ax, s), np.copysign(ay, t), z], axis=-1)


def _octahedral_hemisphere_inverse(d):
    p, q, _ = _octant_unlift(d)
    s = np.copysign(p, d[..., 0])
    t = np.copysign(q, d[..., 1])
    a, b = s - t, s + t
    return np.clip(np.stack([0.5 * (a + 1.0), 0.5 * (b + 1.0)], axis=-1), 0.0, 1.0)


def _concentric(uv):
    return np.stack(concentric_disk_point(uv[..., 0], uv[..., 1]), axis=-1)


def _concentric_inverse(p):
    x, y = p[..., 0], p[..., 1]
    rho = np.minimum(np.hypot(x, y), 1.0)
    wide = np.abs(x) >= np.abs(y)
    big = np.where(wide, x, y)
    small = np.where(wide, y, x)
    safe = np.where(big != 0, big, 1.0)
    r = np.copysign(rho, big)
    other = r * np.arctan(small / safe) * (4.0 / np.pi)  # (4/pi) * angle * r
    a = np.where(wide, r, other)
    b = np.where(wide, other, r)
    return np.clip(np.stack([0.5 * (a + 1.0), 0.5 * (b + 1.0)], axis=-1), 0.0, 1.0)


def _cosine_hemisphere(uv):
    return np.stack(cosine_hemisphere_point(uv[..., 0], uv[..., 1]), axis=-1)


def _cosine_hemisphere_inverse(d):
    return _concentric_inverse(d[..., :2])


def _fibonacci(n):
    # Keinert et al. (2015): z_i = 1 - (2i + 1)/n, phi_i = 2 pi frac(i / Phi).
    i = np.arange(n, dtype=np.int64)
    odd = (2 * i + 1).astype(np.float64)
    z = 1.0 - odd / n
    sin_theta = np.sqrt(odd * (2 * n - odd)) / n
    # frac(i (Phi - 1)) in 64-bit fixed point: the product wraps mod 2^64 exactly.
    frac_bits = i.astype(np.uint64) * np.uint64(_GOLDEN_FRACTION_BITS)
    frac = (frac_bits >> np.uint64(11)).astype(np.float64) * 2.0**-53
    phi = 2.0 * np.pi * frac
    return np.stack([sin_theta * np.cos(phi), sin_theta * np.sin(phi), z], axis=-1)


# floor(2^64 (Phi - 1)) = floor(2^64 (sqrt 5 - 1)/2), from the exact integer square root.
_GOLDEN_FRACTION_BITS = (math.isqrt(5 << 128) - (1 << 64)) >> 1


def _check_triangle(a, b, c):
    verts = np.stack([check_normal(v, name) for v, name in ((a, "a"), (b, "b"), (c, "c"))])
    if _triangle_area(*verts) < 1e-12:
        raise ValueError(
            "'a', 'b', 'c' must span a non-degenerate spherical triangle "
            "(distinct, not on one great circle)"
        )
    return verts


def _triangle_area(A, B, C):
    # Van Oosterom & Strackee (1983): tan(E/2) = |A.(B x C)| / (1 + A.B + B.C + C.A).
    return 2.0 * math.atan2(abs(float(np.dot(A, np.cross(B, C)))), 1.0 + A @ B + B @ C + C @ A)


def _unit(v):
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def _triangle_setup(verts):
    """Per-triangle constants of Arvo's algorithm: vertices, alpha, cos c, area."""
    A, B, C = (np.asarray(v, dtype=np.float64) for v in verts)
    # Angle at A between the arcs AB and AC, from the tangent vectors at A.
    tb, tc = B - (A @ B) * A, C - (A @ C) * A
    alpha = math.atan2(float(np.linalg.norm(np.cross(tb, tc))), float(tb @ tc))
    return A, B, C, alpha, float(A @ B), _triangle_area(A, B, C)


def _arvo_forward(uv, A, B, C, alpha, cos_c, area):
    # Arvo (1995), Fig. 2: the sub-triangle A B C' of area A' = u * area has
    #   q = cos|AC'| = [cos c (t cos(alpha) - 1) - s sin(alpha)] / D,
    #   D = 1 - t cos(alpha) + s sin(alpha) cos c,  (s, t) = (sin, cos)(A' - alpha)
    # (the paper's q with its common factor sin(alpha) cancelled).  Near A, q -> 1
    # and sqrt(1 - q^2) would lose half the digits, so we use the exact factorisations
    #   1 - q = (1 + cos c)(1 - cos A') / D,
    #   1 + q = (1 - cos c)(1 - cos(A' - 2 alpha)) / D,
    #   D = 2 sin^2(A'/2) - sin(A' - alpha) sin(alpha) (1 - cos c),
    # hence sin|AC'| = 2 sin c |sin(A'/2) sin(A'/2 - alpha)| / D.
    area_hat = uv[..., 0] * area
    half = 0.5 * area_hat
    sin_a = math.sin(alpha)
    one_minus_cos_c = 0.5 * float(np.sum((A - B) ** 2))
    sin_c = float(np.linalg.norm(np.cross(A, B)))
    sin_half = np.sin(half)
    denom = 2.0 * sin_half**2 - np.sin(area_hat - alpha) * sin_a * one_minus_cos_c
    cos_b = 1.0 - (1.0 + cos_c) * 2.0 * sin_half**2 / denom
    sin_b = 2.0 * sin_c * np.abs(sin_half * np.sin(half - alpha)) / denom
    c_perp = _unit(C - (C @ A) * A)
    c_hat = _unit(cos_b[..., None] * A + sin_b[..., None] * c_perp)
    # ... then cos of the distance to B uniform on [C'.B, 1]: w = 1 - cos = v (1 - C'.B).
    one_minus_cb = 0.5 * np.sum((c_hat - B) ** 2, axis=-1)
    w = uv[..., 1] * one_minus_cb
    sin_d = np.sqrt(np.maximum(w * (2.0 - w), 0.0))
    tangent = c_hat - np.sum(c_hat * B, axis=-1, keepdims=True) * B
    norm = np.linalg.norm(tangent, axis=-1, keepdims=True)
    tangent = tangent / np.where(norm > 0, norm, 1.0)
    return (1.0 - w)[..., None] * B + sin_d[..., None] * tangent


def _arvo_inverse(d, A, B, C, alpha, cos_c, area):
    d = _unit(d)
    m = np.cross(B, d)  # normal of the great circle through B and d
    n_ac = np.cross(A, C)
    c_hat = np.cross(m, n_ac)
    norm = np.linalg.norm(c_hat, axis=-1, keepdims=True)
    at_b = norm[..., 0] == 0
    c_hat = c_hat / np.where(norm > 0, norm, 1.0)
    # Of the two antipodal intersections, C' is the one on the arc AC.
    c_hat = np.where((c_hat @ (A + C))[..., None] < 0, -c_hat, c_hat)
    triple = np.abs(np.cross(B, c_hat) @ A)
    sub_area = 2.0 * np.arctan2(triple, 1.0 + A @ B + c_hat @ B + c_hat @ A)
    u = np.where(at_b, 0.0, sub_area / area)
    one_minus_cb = 0.5 * np.sum((c_hat - B) ** 2, axis=-1)
    one_minus_db = 0.5 * np.sum((d - B) ** 2, axis=-1)
    v = np.where(at_b, 0.0, one_minus_db / np.where(at_b, 1.0, one_minus_cb))
    return np.clip(np.stack([u, v], axis=-1), 0.0, 1.0)


def _build_peers():
    peers = [
        Peer("classic", "sphere", sample_classic, uniform_sphere_pdf, True, True, True,
             forward=square_to_uniform_sphere, inverse=uniform_sphere_to_square,
             reference="Archimedes' hat-box map; pbrt-v4 SampleUniformSphere, Mitsuba 3 square_to_uniform_sphere"),
        Peer("classic_hemisphere", "hemisphere", sample_classic_hemisphere, uniform_hemisphere_pdf, True, True, True,
             forward=square_to_uniform_hemisphere, inverse=uniform_hemisphere_to_square,
             reference="pbrt-v4 SampleUniformHemisphere"),
        Peer("gaussian", "sphere", _random_only(sample_gaussian), uniform_sphere_pdf, True, False, True,
             reference="Muller (1959), Marsaglia (1972); scipy.stats.uniform_direction"),
        Peer("octahedral", "sphere", sample_octahedral, uniform_sphere_pdf, True, True, True,
             forward=square_to_octahedral_sphere, inverse=octahedral_sphere_to_square,
             reference="Clarberg, Fast equal-area mapping of the (hemi)sphere using SIMD, JGT 2008"),
        Peer("octahedral_hemisphere", "hemisphere", sample_octahedral_hemisphere, uniform_hemisphere_pdf,
             True, True, True,
             forward=square_to_octahedral_hemisphere, inverse=octahedral_hemisphere_to_square,
             reference="Clarberg, JGT 2008 (hemisphere variant)"),
        Peer("fibonacci", "sphere", _fibonacci_sampler(False), uniform_sphere_pdf, False, False, False,
             reference="Keinert et al., Spherical Fibonacci Mapping, SIGGRAPH Asia 2015"),
        Peer("fibonacci_rotated", "sphere", _fibonacci_sampler(True), uniform_sphere_pdf, True, False, False,
             reference="Keinert et al. 2015, under a uniformly random rotation"),
        Peer("arvo", "sphere", sample_arvo, uniform_sphere_pdf, True, True, False, multiple=48,
             reference="Arvo, Stratified sampling of spherical triangles, SIGGRAPH 1995; on T0, then 48 images"),
        Peer("cosine", "hemisphere", sample_cosine, cosine_hemisphere_pdf, True, True, True,
             forward=square_to_cosine_hemisphere, inverse=cosine_hemisphere_to_square,
             reference="Shirley & Chiu 1997 (concentric map) + Malley's method; pbrt-v4 SampleCosineHemisphere"),
    ]
    return {peer.name: peer for peer in peers}


PEERS = _build_peers()
"""dict name -> :class:`Peer`, in the order of the module docstring's table."""

