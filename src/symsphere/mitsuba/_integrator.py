"""``symsphere_path``: Mitsuba 3's ``path`` estimator with the scheme's directions at Lambertian vertices.

The estimator restates Mitsuba's C++ ``path`` integrator (src/integrators/path.cpp; the primal part of
its Python twin ``prb.py``): next-event estimation with MIS by the power heuristic, Russian roulette
after ``rr_depth`` with survival ``min(max(throughput) eta^2, 0.95)``, ``max_depth`` (-1: unbounded)
and ``hide_emitters`` as Mitsuba defines them (the camera ray passes through area emitters,
``skip_area_emitters``, as Mitsuba 3.9's ``path``).  Only the direction sampled at a Lambertian vertex
(Mitsuba's ``diffuse``, alone or as both sides of ``twosided``) depends on ``strategy``:

``bsdf``
    Mitsuba's own sampling (the BSDF samples itself): with ``emitter_sampling='area'``, ``path`` exactly.
``cosine``
    Cosine-weighted (Shirley-Chiu + Malley, ``mi.warp.square_to_cosine_hemisphere``).  With ``points``
    ``random`` this is exactly how Mitsuba's ``diffuse`` samples itself, from the same 2D sample (and
    ``twosided`` with the same flip), so the strategy takes the BSDF's own sample: the image of ``bsdf``
    at the same seed, bit for bit (tested; restating it at the vertex ran at 0.92-1.02x ``bsdf``'s
    paths/s for the same numbers).  With ``sobol`` the 2D point of sample s at a vertex is point s of
    the Owen-scrambled Sobol' sequence of that (pixel, vertex): QMC cosine sampling without the symmetry,
    the control that tells the scheme's Sobol' points from its orbits.
``symmetric``
    The paper's scheme, uniform: orbits of the 24 hemisphere maps (:func:`symsphere.orbit`) of a base
    point mapped onto T0 by ``method`` (:func:`symsphere.warps.square_to_triangle`).
``symmetric_cosine``
    The 8 z-keeping images (:data:`symsphere.warps.WEDGE_MAPS`) of a cosine-weighted base point of the
    wedge (:func:`symsphere.warps.square_to_cosine_wedge`).

With ``emitter_sampling`` ``'solid_angle'`` (the default), ``'cosine'`` or ``'projected'`` (a light table,
:mod:`._lights`) the MIS differs at diffuse vertices (BSDF flags diffuse only, no glossy or delta part):
there the table's emitters are sampled by light sampling alone (weight 1), and a BSDF-sampled ray that finds
one of them counts 0; other emitters keep the power heuristic (but where the table is one small light, as a
``rectangle``, seen small from the vertex or from behind its plane, in a scene where light sampling alone saves
no last ray, that vertex is Mitsuba's: :meth:`._lights.LightTable.hand_far_lanes`).  At every other vertex all emitters are
sampled as Mitsuba's ``path`` samples them, with its MIS (so no hit needs the table's density, and a scene
whose every BSDF is glossy renders as ``path`` bit for bit); the technique of a vertex depends only on its
BSDF.  The two weights of each (vertex, emitter) pair still sum to 1, and light sampling covers every
direction in which a front-facing table triangle is seen (its density is positive there), so the estimator
is unbiased; by solid angle, light sampling alone at a diffuse vertex leaves only the cosine's variation
over the light, which MIS with the cosine-weighted BSDF sample barely lowers.  In a scene whose every BSDF is
diffuse and whose every emitter is in the table, no hit needs the light sampling's density, and the ray from
a vertex whose next vertex is the last (``max_depth``) is not traced: it can only find emission weighted 0.

Base points (``points``) are ``random`` (hashes) or ``sobol`` (Owen-scrambled, index-shuffled Sobol'),
as :mod:`symsphere.render`'s samplers; ``bsdf`` takes the scene sampler's points (choose a QMC sampler
there), so it refuses ``points='sobol'``.  The grouping is the renderer's
(``symsphere.render._directions.sample_local``): with n = 24 (symmetric) or 8 (symmetric_cosine),
sample s of a pixel is in group g = s // n; at vertex ``depth`` the group shares one base point
B(g, depth) and one offset o(g, depth) uniform in 0..n-1, and sample s takes orbit member
``(s mod n + o) mod n``: the n samples of a group take all n images of B in turn, while each path on
its own gets a uniform member of a fresh base point at every vertex (unbiased path by path).  Every
other BSDF samples itself.  At Lambertian vertices the throughput is ``f cos / p`` with f cos from
the BSDF's ``eval`` (textures, two sides) and p the strategy's density, which MIS uses too.

The class is a subclass of Mitsuba's Python ``RBIntegrator`` (the base of ``prb``): ``render``,
``render_forward`` and ``render_backward`` are Mitsuba's, around :meth:`sample`, which is ``prb``'s
interface: in primal mode the path.cpp estimator above (the same float operations, so ``bsdf`` is
``path`` at the same seed), in forward and backward mode path replay backpropagation (Vicini et al.
2021) of the same paths: detached sampling (no strategy's density depends on a scene parameter), the
derivative of f cos at every vertex and of the emitters' radiance; like ``prb`` (and its
limitations: no geometric derivatives), without the terms of moving geometry.  The scheme needs the
sample index within the pixel: ``prepare`` (which also sets the sample count: rounded up to the group
size, with one warning) and ``sample_rays`` record this render's layout of the wavefront (one
wavefront, ``spp x pixels <= 2^32``); called by another integrator (``aov``), :meth:`sample` groups
consecutive lanes instead, keyed from the scene's sampler.
"""

from __future__ import annotations

from typing import Any

import drjit as dr
import mitsuba as mi

from .._constants import BASE_U, BASE_V, INV_2PI, INV_PI
from .._strategies import SAMPLING_STRATEGIES, words
from .._validation import check_choice
from ..warps import METHODS
from . import _lights, _random
from ._bsdfs import all_diffuse, all_lambertian, bsdf_ids, diffuse_only, lambertian_codes
from ._collector import TRACING, collector_paused
from ._warps import cosine_wedge_point, orbit_member, triangle_density, triangle_point

__all__ = [
    "STRATEGIES",
    "POINTS",
    "GROUP_SIZES",
    "integrator_class",
    "register",
    "on_variant_change",
    "lambertian_codes",
]

# the registry's words that symsphere_path takes (symsphere._strategies: the renderer's too)
STRATEGIES = words("plugin")
POINTS = tuple(dict.fromkeys(p for s in STRATEGIES for p in SAMPLING_STRATEGIES[s].plugin_points))
GROUP_SIZES = {strategy: SAMPLING_STRATEGIES[strategy].group for strategy in STRATEGIES}
# the strategies with groups; they, and cosine with Sobol' points, replace the BSDF's sample at Lambertian
# vertices (bsdf, and cosine with random points, take the BSDF's own sample: see the module docstring)
_SYMMETRIC_STRATEGIES = tuple(strategy for strategy, size in GROUP_SIZES.items() if size > 1)
_COSINE_DENSITY = ("cosine", "symmetric_cosine")  # density |cos| / pi: the weight f cos / p is R
_INV_PI = INV_PI
_REPLACE_GRAD: Any = dr.replace_grad  # its stub says it returns None


def _mis_weight(pdf_a: Any, pdf_b: Any) -> Any:
    # path.cpp's mis_weight: the power heuristic, 0 where it is not finite
    a2 = dr.square(pdf_a)
    w = a2 / (a2 + dr.square(pdf_b))
    return dr.detach(dr.select(dr.isfinite(w), w, 0.0))


class _PathMethods:
    """The ``symsphere_path`` plugin (see the module docstring and docs/reference/mitsuba-plugin.md); its methods
    become a subclass of each variant's ``RBIntegrator`` (:func:`integrator_class`)."""

    hide_emitters: bool  # the C++ base's, read from the properties
    skip_area_emitters: Any  # the C++ base's

    def __init__(self, props: Any) -> None:
        if not dr.is_jit_v(mi.Float):
            raise ValueError(f"symsphere_path runs in Mitsuba's JIT variants (llvm_*, cuda_*), not in {mi.variant()!r}")
        if mi.is_polarized:
            raise ValueError(f"symsphere_path does not support polarized variants ({mi.variant()!r})")
        strategy = check_choice(props.get("strategy", "symmetric"), "strategy", STRATEGIES)
        points = check_choice(props.get("points", "random"), "points", POINTS)
        method = check_choice(props.get("method", "equal_area"), "method", METHODS)
        max_depth = int(props.get("max_depth", -1))
        if max_depth < -1:
            raise ValueError(f"'max_depth' must be -1 (unbounded) or >= 0, got {max_depth}")
        rr_depth = int(props.get("rr_depth", 5))
        if rr_depth <= 0:
            raise ValueError(f"'rr_depth' must be > 0, got {rr_depth}")
        if strategy == "bsdf" and points != "random":
            raise ValueError(
                f"'points' must be 'random' for strategy='bsdf' (got {points!r}): it takes the scene "
                "sampler's points; choose a QMC sampler there, or points='sobol' with another strategy"
            )
        emitter_sampling = check_choice(
            props.get("emitter_sampling", "solid_angle"), "emitter_sampling", _lights.EMITTER_SAMPLINGS
        )
        # the variant's RBIntegrator (the class's only base): reads max_depth (default 6 there) and rr_depth
        # again, valid by now, and hide_emitters (the C++ base's property)
        type(self).__mro__[1].__init__(self, props)  # type: ignore[misc]
        self.strategy, self.points, self.method = strategy, points, method
        self.emitter_sampling = emitter_sampling
        self.max_depth = max_depth if max_depth != -1 else 0xFFFFFFFF
        self.rr_depth = rr_depth
        self.group_size = GROUP_SIZES[strategy]
        # whether the strategy's own direction replaces the BSDF's sample at Lambertian vertices
        self.replaces_sample = strategy in _SYMMETRIC_STRATEGIES or points == "sobol"
        self._pending: tuple[Any, int] | None = None  # (seed, spp) of the last prepare()
        self._layout: tuple[int, Any, Any] | None = None  # (width, pixel key, sample index) of this render
        self._warned: set[tuple[int, int, str]] = set()

    def to_string(self) -> str:
        return (
            f"SymspherePath[strategy={self.strategy!r}, points={self.points!r}, method={self.method!r}, "
            f"emitter_sampling={self.emitter_sampling!r}, max_depth={self.max_depth}, rr_depth={self.rr_depth}, "
            f"hide_emitters={self.hide_emitters}]"
        )

    def aov_names(self) -> list[str]:
        return []

    # --- sample counts and the lanes' layout (ADIntegrator's prepare() and sample_rays()) ---------------

    def prepare(self, sensor: Any, seed: Any = 0, spp: int = 0, aovs: Any = ()) -> tuple[Any, int]:
        """ADIntegrator.prepare with the sample count of :meth:`_sample_count` and an opaque seed."""
        film = sensor.film()
        sampler = sensor.sampler().clone()
        spp = self._sample_count(sampler, spp)
        sampler.set_samples_per_wavefront(spp)
        film_size = film.crop_size()
        if film.sample_border():
            film_size += 2 * film.rfilter().border_size()
        wavefront = int(dr.prod(film_size)) * spp
        if wavefront > 2**32:
            _fail(f"spp x pixels = {wavefront} exceeds 2^32 (one wavefront): use fewer samples per pixel")
        if isinstance(seed, int):
            seed = dr.opaque(mi.UInt32, seed)  # one kernel for every seed
        sampler.seed(seed, wavefront)
        film.prepare(list(aovs))
        self._pending = (seed, spp)
        return sampler, spp

    def _sample_count(self, sampler: Any, spp: int) -> int:
        """The samples per pixel rendered for the request *spp* (0: the scene sampler's), set on *sampler*.

        Rounded up to a multiple of the group size if the sampler takes that count; a sampler that rounds
        counts itself (stratified, ldsampler: squares or powers of 2; orthogonal: squares of primes) may
        not: then its own count for the request is used and the samples after its last whole group form a
        partial group (unbiased: every sample is a uniform member of its base point's orbit).  One
        warning per (request, result, sampler) and integrator, through Mitsuba's log, where the count
        is not the request or not a multiple of the group.
        """
        requested = int(spp) if spp else int(sampler.sample_count())
        if requested <= 0:
            _fail(f"'spp' must be > 0, got {requested}")
        n = self.group_size
        own = _taken_count(sampler, requested)
        chosen = own
        if own % n:
            rounded = _taken_count(sampler, -(-own // n) * n)
            if rounded % n == 0:
                chosen = rounded
        if chosen != int(sampler.sample_count()):
            level = mi.log_level()
            mi.set_log_level(mi.LogLevel.Error)  # this method's warning says what the sampler did
            try:
                sampler.set_sample_count(chosen)
            finally:
                mi.set_log_level(level)
        name = sampler.class_name()
        if (chosen != requested or chosen % n) and (requested, chosen, name) not in self._warned:
            self._warned.add((requested, chosen, name))
            what = f"{chosen} samples per pixel" + (f" instead of {requested}" if chosen != requested else "")
            why = f"a group of {n} samples shares a base point with strategy={self.strategy!r}"
            if chosen % n:
                why += (
                    f"; the {name} takes {chosen}, not a multiple of {n}, so the last group of each pixel has "
                    f"{chosen % n} (unbiased, the symmetry in whole groups only)"
                )
            _warn(f"rendering {what} ({why})")
        return chosen

    def sample_rays(self, scene: Any, sensor: Any, sampler: Any) -> Any:
        """ADIntegrator.sample_rays, and the layout of its wavefront: lane = pixel x spp + sample index."""
        rays = type(self).__mro__[1].sample_rays(self, scene, sensor, sampler)  # type: ignore[attr-defined]
        if self.replaces_sample and self._pending is not None:
            seed, spp = self._pending
            film = sensor.film()
            film_size = film.crop_size()
            if film.sample_border():
                film_size += 2 * film.rfilter().border_size()
            width = int(dr.prod(film_size)) * spp
            idx = dr.arange(mi.UInt32, width)
            pixel = idx // spp
            self._layout = (width, _random.pixel_key(mi.UInt64(seed), pixel), idx - pixel * spp)
        return rays

    def render(self, scene: Any, sensor: Any = 0, seed: Any = 0, spp: int = 0, develop: bool = True,
               evaluate: bool = True) -> Any:  # fmt: skip
        try:
            return type(self).__mro__[1].render(self, scene, sensor, seed, spp, develop, evaluate)  # type: ignore[attr-defined]
        finally:
            self._layout = None  # a later nested sample() must not take this render's layout

    def render_forward(self, scene: Any, params: Any, sensor: Any = 0, seed: Any = 0, spp: int = 0) -> Any:
        try:
            return type(self).__mro__[1].render_forward(self, scene, params, sensor, seed, spp)  # type: ignore[attr-defined]
        finally:
            self._layout = None

    def render_backward(self, scene: Any, params: Any, grad_in: Any, sensor: Any = 0, seed: Any = 0,
                        spp: int = 0) -> None:  # fmt: skip
        try:
            type(self).__mro__[1].render_backward(self, scene, params, grad_in, sensor, seed, spp)  # type: ignore[attr-defined]
        finally:
            self._layout = None

    def _lanes(self, sampler: Any, width: int) -> tuple[Any, Any]:
        """(pixel key, sample index) of each lane: this render's layout, or, when another integrator calls
        sample() (``aov``, ``moment``: Mitsuba's C++ render, lane = pixel x spp + sample), groups of
        consecutive lanes keyed by a random number of the scene sampler drawn at the group's first lane."""
        if self._layout is not None and self._layout[0] == width:
            return self._layout[1], self._layout[2]
        lane = dr.arange(mi.UInt32, width)
        s = lane % self.group_size
        hi = mi.UInt64(mi.UInt32(sampler.next_1d() * 2.0**24))
        lo = mi.UInt64(mi.UInt32(sampler.next_1d() * 2.0**24))
        key = _random.mix64((hi << 24) | lo)
        dr.eval(key)
        return dr.gather(mi.UInt64, key, lane - s), s

    def _lambertian_table(self, scene: Any) -> Any:
        """UInt32 table over Dr.Jit's registry ids of the scene's BSDFs: 1 or 2 if Lambertian, else 0."""
        codes: dict[int, int] = {}
        for shape in scene.shapes():
            bsdf = shape.bsdf()
            if bsdf is None:
                continue
            ident = int(bsdf_ids(mi.BSDFPtr(bsdf))[0])
            codes[ident] = lambertian_codes(bsdf)
        size = max(codes, default=0) + 1
        values = [0] * size
        for ident, code in codes.items():
            values[ident] = code
        return mi.UInt32(values)

    # --- directions at Lambertian vertices ------------------------------------------------------------

    def _local_direction(self, key: Any, s: Any, depth: Any) -> tuple[Any, Any]:
        """(direction about +z, its density) of the strategy at vertex *depth* for sample *s*."""
        n = self.group_size
        group = s // n
        vertex_key = _random.mix64(key ^ (mi.UInt64(depth) * _random.GOLDEN + n))  # (pixel, vertex, n)
        h = _random.mix64(vertex_key ^ ((mi.UInt64(group) + 1) * _random.ODD))  # ... and group
        member = s - n * group + _random.below(h, n)  # (s mod n + offset) mod n
        member = dr.select(member >= n, member - n, member)
        if self.points == "random":
            u = _random.u01(_random.mix64(h ^ BASE_U))
            v = _random.u01(_random.mix64(h ^ BASE_V))
        else:
            fu, fv = _random.owen_sobol2(group, vertex_key)
            u, v = _random.fraction(fu), _random.fraction(fv)
        if self.strategy == "cosine":  # points='sobol' (random: the BSDF's own sample); n = 1, group = s
            wo = mi.warp.square_to_cosine_hemisphere(mi.Point2f(u, v))
            return wo, wo.z * INV_PI
        if self.strategy == "symmetric_cosine":
            x, y, z = orbit_member(*cosine_wedge_point(u, v), member, members=8)
            return mi.Vector3f(x, y, z), z * INV_PI
        bx, by, bz = triangle_point(u, v, self.method)
        density = triangle_density(bx, by, bz, self.method)
        x, y, z = orbit_member(bx, by, bz, member, members=24)
        return mi.Vector3f(x, y, z), density / n

    def _density(self, wo: Any, wi_z: Any) -> Any:
        """The strategy's density of the local direction *wo* (on the side of wi), for MIS."""
        same_side = wo.z * wi_z > 0
        if self.strategy in _COSINE_DENSITY:  # density |cos| / pi
            return dr.select(same_side, dr.abs(wo.z) * INV_PI, 0.0)
        if self.method == "equal_area":
            return dr.select(same_side, INV_2PI, 0.0)
        a, b, c = dr.abs(wo.x), dr.abs(wo.y), dr.abs(wo.z)
        lo_ab, hi_ab = dr.minimum(a, b), dr.maximum(a, b)
        base = (dr.maximum(lo_ab, dr.minimum(hi_ab, c)), dr.minimum(lo_ab, c), dr.maximum(hi_ab, c))
        return dr.select(same_side, triangle_density(*base, self.method) / 24, 0.0)

    # --- next-event estimation: one place, so that another light-sampling technique can replace it -----

    def _sample_emitter(
        self,
        scene: Any,
        si: Any,
        sampler: Any,
        active: Any,
        primal: bool,
        lights: Any,
        alone: Any = None,
        cosine: Any = None,
        cosine_only: bool = False,
    ) -> tuple[Any, Any, Any, Any]:
        """Next-event estimation at *si*: (direction sample ``ds``, emitter weight Le / pdf, the lanes where
        the sample is valid, the lanes whose sample is the light table's: None without a table).
        ``ds.pdf`` (solid angle) and ``ds.delta`` feed the MIS weight against the BSDF's direction; at a
        BSDF-sampled hit the density is ``scene.pdf_emitter_direction``'s wherever it is needed.

        Without a light table (``emitter_sampling='area'``, or a scene without rectangle or mesh lights)
        Mitsuba's emitter sampling (area measure converted to solid angle, one 2D sample); with one, at the
        lanes *alone* (diffuse vertices) the table's choice of a triangle by solid angle x radiance and a
        uniform direction in its solid angle (:mod:`._lights`), elsewhere Mitsuba's.  Detached; in a
        differential mode the weight's derivative is re-attached as ``prb`` does (emitter parameters:
        radiance, textures), without the terms of moving geometry.
        """
        if dr.hint(lights is None, mode="scalar"):
            ds, em_weight = scene.sample_emitter_direction(si, sampler.next_2d(), True, active)
            ours = None
        else:
            ds, em_weight, ours = lights.sample_direction(
                scene, si, sampler.next_2d(), active, table=alone, cos=cosine, only=cosine_only
            )
        active = active & (ds.pdf != 0.0)
        if not primal:
            with dr.resume_grad():
                em_val = scene.eval_emitter_direction(si, ds, active)
                inv_pdf = dr.select(ds.pdf != 0.0, dr.rcp(ds.pdf), 0.0)
                em_weight = _REPLACE_GRAD(em_weight, em_val * dr.detach(inv_pdf))
        return ds, em_weight, active, ours

    # --- the path loop (path.cpp; in a differential mode, prb's path replay) ---------------------------

    @dr.syntax
    def sample(self, mode: Any, scene: Any, sampler: Any, ray: Any, δL: Any = None, state_in: Any = None,
               active: Any = True, **kwargs: Any) -> tuple[Any, Any, list[Any], Any]:  # fmt: skip
        """``ADIntegrator.sample``: radiance (primal), or its derivative (forward) / adjoint (backward)."""
        primal = mode == dr.ADMode.Primal
        replaces = self.replaces_sample  # False for bsdf, and cosine with random points: the BSDF's own sample
        key, s, table = None, None, None
        if replaces:
            key, s = self._lanes(sampler, dr.width(ray))
            table = self._lambertian_table(scene)
        lights: Any = _lights.build(scene, self.emitter_sampling)
        # At a diffuse vertex the table's emitters are sampled by light sampling alone (weight 1; a BSDF-
        # sampled ray that finds one of them counts 0): see the module docstring.  In a scene whose every BSDF is diffuse
        # and whose every emitter is in the table, no BSDF hit needs the light sampling's density, and the
        # ray of a vertex whose next vertex is the last can find nothing that counts: it is not traced.
        only_table = lights is not None and lights.covers_all and all_diffuse(scene)
        # emitter_sampling='projected' (and 'cosine'): at Lambertian vertices (the shading normal is the BSDF's)
        # the table samples by projected solid angle (or near it); everywhere, when every BSDF is Lambertian
        projected = lights is not None and lights.projected
        lambertian_ids = self._lambertian_table(scene) if projected else None
        cosine_only = projected and only_table and all_lambertian(scene)
        # a tiny table far from p (or p behind it): Mitsuba's own sampling with its MIS, where no last ray is
        # saved (the table's "by power, then by area" there is Mitsuba's sampling without the MIS)
        far_lanes: Any = lights.hand_far_lanes(scene) if lights is not None and not only_table else None
        prev_alone = mi.Bool(False)  # the previous vertex sampled the table's emitters alone
        ray = mi.Ray3f(dr.detach(ray))
        # the variant's types (mi.Float & co.), which Mitsuba's stubs cannot name before run time
        throughput: Any = mi.Spectrum(1.0)
        L: Any = mi.Spectrum(0.0 if primal else state_in)
        δL = mi.Spectrum(δL if δL is not None else 0.0)
        eta = mi.Float(1.0)
        depth = mi.UInt32(0)
        valid_ray = mi.Bool((not self.hide_emitters) and scene.environment() is not None)
        prev_si = dr.zeros(mi.Interaction3f)
        prev_bsdf_pdf: Any = mi.Float(1.0)
        prev_bsdf_delta = mi.Bool(True)
        active = mi.Bool(active) & (self.max_depth != 0)
        ctx = mi.BSDFContext()

        while active:
            if dr.hint(replaces, mode="scalar"):
                # first: it needs only the sample and the depth, and its chain of dependent multiplies
                # (hashes, Owen scramble) can then overlap the trace call instead of waiting after the BSDF's
                local, pdf_local = self._local_direction(key, s, depth)
            si = scene.ray_intersect(ray, ray_flags=mi.RayFlags.All, coherent=(depth == 0))
            if dr.hint(self.hide_emitters, mode="scalar"):  # Mitsuba's: the camera ray passes through area emitters
                skip = (depth == 0) & si.is_valid() & (si.shape.emitter() != None)  # noqa: E711 - a Dr.Jit comparison
                ray_skip = si.spawn_ray(ray.d)
                after = self.skip_area_emitters(scene, ray_skip, True, skip)
                si = dr.select(skip, after.compute_surface_interaction(ray_skip, mi.RayFlags.All, skip), si)

            # direct emission, weighted against the previous vertex's emitter sampling
            ds = mi.DirectionSample3f(scene, si=si, ref=prev_si)
            if dr.hint(only_table, mode="scalar"):  # after the camera ray, every hit is weighted 0 below
                mis_bsdf: Any = mi.Float(1.0)
            else:
                em_pdf = scene.pdf_emitter_direction(prev_si, ds, ~prev_bsdf_delta)
                mis_bsdf = _mis_weight(prev_bsdf_pdf, em_pdf)
            # with every emitter the table's, a hit after a diffuse vertex is always on one of them
            if dr.hint(only_table or (lights is not None and lights.covers_all), mode="scalar"):
                mis_bsdf = dr.select(prev_alone, 0.0, mis_bsdf)
            elif dr.hint(lights is not None, mode="scalar"):
                mis_bsdf = dr.select(prev_alone & lights.holds(si, prev_alone), 0.0, mis_bsdf)
            shown = prev_bsdf_pdf > 0.0
            if dr.hint(self.hide_emitters, mode="scalar"):  # a hidden environment behind the camera ray
                shown &= (depth != 0) | si.is_valid()
            with dr.resume_grad(when=not primal):
                emitted = ds.emitter.eval(si, shown)
            if dr.hint(primal, mode="scalar"):
                L = dr.fma(throughput, emitted * mis_bsdf, L)

            active_next = (depth + 1 < self.max_depth) & si.is_valid()
            bsdf = si.bsdf(ray)

            # emitter sampling
            flags = bsdf.flags()
            active_em = active_next & mi.has_flag(flags, mi.BSDFFlags.Smooth)
            alone = active_em & diffuse_only(flags) if lights is not None else mi.Bool(False)
            if dr.hint(far_lanes is not None, mode="scalar"):
                alone &= ~far_lanes(mi.Vector3f(si.p))
            cosine = None
            if dr.hint(projected, mode="scalar"):
                cosine = alone & (dr.gather(mi.UInt32, lambertian_ids, bsdf_ids(bsdf), alone) != 0)
            ds, em_weight, active_em, ours = self._sample_emitter(
                scene, si, sampler, active_em, primal, lights, None if only_table else alone, cosine, cosine_only
            )
            wo = si.to_local(ds.d)

            sample_1 = sampler.next_1d()
            sample_2 = sampler.next_2d()
            bsdf_val, bsdf_pdf, bsdf_sample, bsdf_weight = bsdf.eval_pdf_sample(
                ctx, si, wo, sample_1, sample_2, active_next
            )

            if dr.hint(replaces, mode="scalar"):
                lambertian = active_next & (dr.gather(mi.UInt32, table, bsdf_ids(bsdf), active_next) != 0)
                local.z = dr.mulsign(local.z, si.wi.z)
                # A Lambertian BSDF's own (cosine) sample has weight f cos / pdf = its reflectance R at si,
                # whatever the direction (0 where wi is below a one-sided surface, and in the measure-zero
                # event that its own direction has pdf 0), so f cos at `local` is R |z| / pi: no second
                # BSDF evaluation (texture lookup, virtual call) per vertex.
                if dr.hint(self.strategy in _COSINE_DENSITY, mode="scalar"):
                    weight_local = bsdf_weight  # pdf_local = |z| / pi: the weight is R
                else:
                    weight_local = dr.select(pdf_local > 0.0, bsdf_weight * (dr.abs(local.z) * INV_PI / pdf_local), 0.0)
                bsdf_pdf = dr.select(lambertian, self._density(wo, si.wi.z), bsdf_pdf)
                bsdf_sample.wo = dr.select(lambertian, local, bsdf_sample.wo)
                bsdf_sample.pdf = dr.select(lambertian, pdf_local, bsdf_sample.pdf)
                bsdf_weight = dr.select(lambertian, weight_local, bsdf_weight)

            mis_em = dr.select(ds.delta, 1.0, _mis_weight(ds.pdf, bsdf_pdf))
            if dr.hint(lights is not None, mode="scalar"):
                mis_em = dr.select(alone & ours, 1.0, mis_em)
            if dr.hint(primal, mode="scalar"):
                L[active_em] = dr.fma(throughput, bsdf_val * em_weight * mis_em, L)
            else:
                # path replay: the emission and direct light of this vertex, now with derivatives, are taken
                # off the primal estimate; what remains arrives through the sampled direction
                with dr.resume_grad():
                    Le = throughput * emitted * mis_bsdf
                    bsdf_val_em = bsdf.eval(ctx, si, wo, active_em)
                    Lr_dir = dr.select(active_em, throughput * bsdf_val_em * em_weight * mis_em, 0.0)
                L = L - Le - Lr_dir

            # BSDF sampling: the next ray and the loop state
            ray = si.spawn_ray(si.to_world(bsdf_sample.wo))
            throughput *= bsdf_weight
            eta *= bsdf_sample.eta
            valid_ray |= active & si.is_valid() & ~mi.has_flag(bsdf_sample.sampled_type, mi.BSDFFlags.Null)
            prev_si = mi.Interaction3f(si)
            prev_bsdf_pdf = bsdf_sample.pdf
            prev_bsdf_delta = mi.has_flag(bsdf_sample.sampled_type, mi.BSDFFlags.Delta)
            prev_alone = alone

            # Russian roulette
            depth[si.is_valid()] += 1
            throughput_max = dr.max(mi.unpolarized_spectrum(throughput))
            rr_prob = dr.minimum(throughput_max * dr.square(eta), 0.95)
            rr_active = depth >= self.rr_depth
            rr_continue = sampler.next_1d() < rr_prob
            throughput[rr_active] *= dr.rcp(rr_prob)
            active = active_next & (~rr_active | rr_continue) & (throughput_max != 0.0)
            if dr.hint(only_table, mode="scalar"):  # the next vertex is the last: only emission, weighted 0
                active &= ~(alone & (depth + 1 >= self.max_depth))

            if dr.hint(not primal, mode="scalar"):
                # the sampling is detached (its density has no parameters), so the derivative of what
                # arrives through the sampled direction is L times the relative derivative of f cos there
                with dr.resume_grad():
                    bsdf_val_next = bsdf.eval(ctx, si, bsdf_sample.wo, active_next)
                    Lo = Le + Lr_dir + L * dr.relative_grad(bsdf_val_next)
                    if dr.hint(mode == dr.ADMode.Backward, mode="scalar"):
                        dr.backward_from(δL * Lo)
                    else:
                        δL += dr.forward_to(Lo)

        if dr.hint(primal, mode="scalar"):
            L = dr.select(valid_ray, L, 0.0)
        return (L if primal else δL), valid_ray, [], L


def _taken_count(sampler: Any, count: int) -> int:
    """The sample count *sampler* takes when asked for *count* (on a clone, without its log message)."""
    probe = sampler.clone()
    level = mi.log_level()
    mi.set_log_level(mi.LogLevel.Error)
    try:
        probe.set_sample_count(count)
    finally:
        mi.set_log_level(level)
    return int(probe.sample_count())


def _fail(message: str) -> None:
    """Raise ValueError(*message*), logged first: ``mi.render`` runs the integrator inside ``dr.custom``,
    which re-raises every error as "error while performing a custom differentiable operation (see
    above)"; the log line is what is above."""
    _warn(message)
    raise ValueError(message)


def _warn(message: str) -> None:
    """A warning in Mitsuba's log (as its samplers' when they round a sample count)."""
    log: Any = mi.Log  # typed as an object by Mitsuba's stubs
    log(mi.LogLevel.Warn, f"symsphere_path: {message}")


_CLASSES: dict[str, type] = {}


def integrator_class() -> type:
    """The ``symsphere_path`` class of the current Mitsuba variant: a subclass of its ``RBIntegrator``
    (Mitsuba's Python base of ``prb``: ``render``, ``render_forward``, ``render_backward``), or of
    ``mi.SamplingIntegrator`` in the variants without one (scalar: the constructor refuses them)."""
    variant = mi.variant()
    if variant is None:
        raise RuntimeError("no Mitsuba variant is set: call mi.set_variant('llvm_ad_rgb') (or another) first")
    if variant not in _CLASSES:
        common = getattr(mi.ad.integrators, "common", None)  # the variant's module (none in scalar variants)
        base = common.RBIntegrator if common is not None else mi.SamplingIntegrator
        methods = {k: v for k, v in vars(_PathMethods).items() if k not in ("__dict__", "__weakref__")}
        methods.update({name: collector_paused(methods[name]) for name in TRACING})
        _CLASSES[variant] = type("SymspherePath", (base,), methods)  # nanobind: one base only
    return _CLASSES[variant]


def register() -> None:
    """Register ``symsphere_path`` with Mitsuba for the current variant.

    In a scalar or polarized variant the plugin is registered too, and loading it raises the
    ValueError that says which variants it runs in.
    """
    mi.register_integrator("symsphere_path", lambda props: integrator_class()(props))


def on_variant_change(old: str | None, new: str | None) -> None:
    """Mitsuba's variant callback: register ``symsphere_path`` for every variant set after import."""
    if new is not None:
        register()
