"""``symsphere_path``: Mitsuba 3's ``path`` estimator with the scheme's directions at Lambertian vertices.

The estimator restates Mitsuba's C++ ``path`` integrator (src/integrators/path.cpp; the primal part of
its Python twin ``prb.py``): next-event estimation with MIS by the power heuristic, Russian roulette
after ``rr_depth`` with survival ``min(max(throughput) eta^2, 0.95)``, ``max_depth`` (-1: unbounded)
and ``hide_emitters`` as Mitsuba defines them (the camera ray passes through area emitters,
``skip_area_emitters``, as Mitsuba 3.9's ``path``).  Only the direction sampled at a Lambertian vertex
(Mitsuba's ``diffuse``, alone or as both sides of ``twosided``) depends on ``strategy``:

``bsdf``
    Mitsuba's own sampling (the BSDF samples itself): ``path`` exactly, in distribution.
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

Base points (``points``) are ``random`` (hashes) or ``sobol`` (Owen-scrambled, index-shuffled Sobol'),
as :mod:`symsphere.render`'s samplers; ``bsdf`` takes the scene sampler's points (choose a QMC sampler
there), so it refuses ``points='sobol'``.  The grouping is the renderer's
(``symsphere.render._integrator.sample_local``): with n = 24 (symmetric) or 8 (symmetric_cosine),
sample s of a pixel is in group g = s // n; at vertex ``depth`` the group shares one base point
B(g, depth) and one offset o(g, depth) uniform in 0..n-1, and sample s takes orbit member
``(s mod n + o) mod n``: the n samples of a group take all n images of B in turn, while each path on
its own gets a uniform member of a fresh base point at every vertex (unbiased path by path).  Every
other BSDF samples itself.  At Lambertian vertices the throughput is ``f cos / p`` with f cos from
the BSDF's ``eval`` (textures, two sides) and p the strategy's density, which MIS uses too.

``render()`` is overridden (as Mitsuba's Python ``ADIntegrator`` does) because the scheme needs the
sample index within the pixel; the whole image is one wavefront (``spp x pixels <= 2^32``).
"""

from __future__ import annotations

import math
import re
from typing import Any, cast

import drjit as dr
import mitsuba as mi

from .._validation import check_choice
from ..warps import METHODS
from . import _lights, _random
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

STRATEGIES = ("bsdf", "cosine", "symmetric", "symmetric_cosine")
POINTS = ("random", "sobol")
GROUP_SIZES = {"bsdf": 1, "cosine": 1, "symmetric": 24, "symmetric_cosine": 8}
# the strategies with groups; they, and cosine with Sobol' points, replace the BSDF's sample at Lambertian
# vertices (bsdf, and cosine with random points, take the BSDF's own sample: see the module docstring)
_SYMMETRIC_STRATEGIES = tuple(strategy for strategy, size in GROUP_SIZES.items() if size > 1)
_COSINE_DENSITY = ("cosine", "symmetric_cosine")  # density |cos| / pi: the weight f cos / p is R
_BASE_U = 0x2545F4914F6CDD1D  # the renderer's tags that split a group key into u and v
_BASE_V = 0x5851F42D4C957F2D
_INV_PI = 1.0 / math.pi


def _mis_weight(pdf_a: Any, pdf_b: Any) -> Any:
    # path.cpp's mis_weight: the power heuristic, 0 where it is not finite
    a2 = dr.square(pdf_a)
    w = a2 / (a2 + dr.square(pdf_b))
    return dr.detach(dr.select(dr.isfinite(w), w, 0.0))


def _bsdf_ids(bsdfs: Any) -> Any:
    """The Dr.Jit registry ids (UInt32) of a ``BSDFPtr`` array: the keys of the Lambertian table."""
    return dr.reinterpret_array(mi.UInt32, bsdfs)


_BRDF_LINE = re.compile(r"^  brdf\[(\d)\] = (\w+)\[", re.MULTILINE)


def lambertian_codes(bsdf: Any) -> int:
    """1 for Mitsuba's ``diffuse``, 2 for a ``twosided`` whose both sides are ``diffuse``, else 0."""
    name = bsdf.class_name()
    if name == "SmoothDiffuse":
        return 1
    if name == "TwoSidedBRDF":
        nested = dict(_BRDF_LINE.findall(str(bsdf)))
        if nested.get("0") == "SmoothDiffuse" and nested.get("1") == "SmoothDiffuse":
            return 2
    return 0


class _PathMethods:
    """The ``symsphere_path`` plugin (see the module docstring); its methods become a subclass of each
    variant's ``mi.SamplingIntegrator`` (:func:`integrator_class`).

    Parameters (scene file or ``load_dict``): ``strategy`` ('bsdf', 'cosine', 'symmetric',
    'symmetric_cosine'; default 'symmetric'), ``points`` ('random', 'sobol'; default 'random'; 'bsdf':
    'random' only),
    ``method`` ('equal_area', 'paper1', 'paper2'; default 'equal_area', for 'symmetric'),
    ``max_depth`` (default -1), ``rr_depth`` (default 5), ``hide_emitters`` (default false),
    ``emitter_sampling`` ('area': Mitsuba's own, the default; 'solid_angle': :mod:`._lights`).
    """

    def __init__(self, props: Any) -> None:
        # the current variant's base (this class is a template: its methods run on that subclass)
        mi.SamplingIntegrator.__init__(cast(mi.SamplingIntegrator, self), props)
        if not dr.is_jit_v(mi.Float):
            raise ValueError(f"symsphere_path runs in Mitsuba's JIT variants (llvm_*, cuda_*), not in {mi.variant()!r}")
        if mi.is_polarized:
            raise ValueError(f"symsphere_path does not support polarized variants ({mi.variant()!r})")
        self.strategy = check_choice(props.get("strategy", "symmetric"), "strategy", STRATEGIES)
        self.points = check_choice(props.get("points", "random"), "points", POINTS)
        self.method = check_choice(props.get("method", "equal_area"), "method", METHODS)
        max_depth = int(props.get("max_depth", -1))
        if max_depth < -1:
            raise ValueError(f"'max_depth' must be -1 (unbounded) or >= 0, got {max_depth}")
        self.max_depth = max_depth if max_depth != -1 else 0xFFFFFFFF
        self.rr_depth = int(props.get("rr_depth", 5))
        if self.rr_depth <= 0:
            raise ValueError(f"'rr_depth' must be > 0, got {self.rr_depth}")
        self.hide_emitters = bool(props.get("hide_emitters", False))
        if self.strategy == "bsdf" and self.points != "random":
            raise ValueError(
                f"'points' must be 'random' for strategy='bsdf' (got {self.points!r}): it takes the scene "
                "sampler's points; choose a QMC sampler there, or points='sobol' with another strategy"
            )
        self.emitter_sampling = check_choice(
            props.get("emitter_sampling", "area"), "emitter_sampling", _lights.EMITTER_SAMPLINGS
        )
        self.group_size = GROUP_SIZES[self.strategy]
        # whether the strategy's own direction replaces the BSDF's sample at Lambertian vertices
        self.replaces_sample = self.strategy in _SYMMETRIC_STRATEGIES or self.points == "sobol"

    def to_string(self) -> str:
        return (
            f"SymspherePath[strategy={self.strategy!r}, points={self.points!r}, method={self.method!r}, "
            f"max_depth={self.max_depth}, rr_depth={self.rr_depth}, hide_emitters={self.hide_emitters}]"
        )

    def aov_names(self) -> list[str]:
        return []

    # --- render ---------------------------------------------------------------------------------

    def render(self, scene: Any, sensor: Any = 0, seed: Any = 0, spp: int = 0, develop: bool = True,
               evaluate: bool = True) -> Any:  # fmt: skip
        if not develop:
            raise ValueError("symsphere_path renders developed images only ('develop' must be True)")
        if isinstance(sensor, int):
            sensor = scene.sensors()[sensor]
        film = sensor.film()
        with dr.suspend_grad():
            sampler = sensor.sampler().clone()
            if spp != 0:
                sampler.set_sample_count(spp)
            spp = sampler.sample_count()
            if spp % self.group_size:
                raise ValueError(
                    f"'spp' must be a multiple of {self.group_size} for strategy={self.strategy!r} "
                    f"(a group of {self.group_size} samples shares a base point), got {spp}"
                )
            sampler.set_samples_per_wavefront(spp)
            film_size = film.crop_size()
            border = film.rfilter().border_size() if film.sample_border() else 0
            film_size = film_size + 2 * border
            wavefront = int(dr.prod(film_size)) * spp
            if wavefront > 2**32:
                raise ValueError(f"spp x pixels = {wavefront} exceeds 2^32: use fewer samples per pixel")
            if isinstance(seed, int):
                seed = dr.opaque(mi.UInt32, seed)  # one kernel for every seed
            sampler.seed(seed, wavefront)
            film.prepare([])

            idx = dr.arange(mi.UInt32, wavefront)
            pixel = idx // spp
            sample_index = idx - pixel * spp
            pos = mi.Vector2i()
            pos.y = pixel // film_size[0]
            pos.x = pixel - pos.y * film_size[0]
            if film.sample_border():
                pos -= border
            pos += mi.Vector2i(film.crop_offset())
            pos_f = mi.Vector2f(pos) + sampler.next_2d()
            scale = dr.rcp(mi.ScalarVector2f(film.crop_size()))
            offset = -mi.ScalarVector2f(film.crop_offset()) * scale
            aperture = sampler.next_2d() if sensor.needs_aperture_sample() else mi.Vector2f(0.5)
            time = sensor.shutter_open()
            if sensor.shutter_open_time() > 0:
                time += sampler.next_1d() * sensor.shutter_open_time()
            wavelength_sample = sampler.next_1d() if mi.is_spectral else 0.5
            ray, ray_weight = sensor.sample_ray_differential(
                time, wavelength_sample, dr.fma(pos_f, scale, offset), aperture
            )
            key = _random.pixel_key(mi.UInt64(seed), pixel)
            table = self._lambertian_table(scene) if self.replaces_sample else None
            lights = _lights.build(scene, self.emitter_sampling)
            spectrum, valid = self._trace(scene, sampler, ray, key, sample_index, table, lights)

            block = film.create_block()
            block.set_coalesce(block.coalesce() and spp >= 4)
            value = spectrum * ray_weight
            if mi.is_spectral:
                rgb = mi.spectrum_to_srgb(value, ray.wavelengths)
            elif mi.is_monochromatic:
                rgb = mi.Color3f(value.x)
            else:
                rgb = value
            alpha = dr.select(valid, mi.Float(1), mi.Float(0))
            channels = [rgb.x, rgb.y, rgb.z] + ([alpha] if mi.has_flag(film.flags(), mi.FilmFlags.Alpha) else [])
            splat = mi.Vector2f(pos) if film.rfilter().is_box_filter() else pos_f
            block.put(splat, channels + [mi.Float(1)])
            film.put_block(block)
            return film.develop()

    def _lambertian_table(self, scene: Any) -> Any:
        """UInt32 table over Dr.Jit's registry ids of the scene's BSDFs: 1 or 2 if Lambertian, else 0."""
        codes: dict[int, int] = {}
        for shape in scene.shapes():
            bsdf = shape.bsdf()
            if bsdf is None:
                continue
            ident = int(_bsdf_ids(mi.BSDFPtr(bsdf))[0])
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
            u = _random.u01(_random.mix64(h ^ _BASE_U))
            v = _random.u01(_random.mix64(h ^ _BASE_V))
        else:
            fu, fv = _random.owen_sobol2(group, vertex_key)
            u, v = _random.fraction(fu), _random.fraction(fv)
        if self.strategy == "cosine":  # points='sobol' (random: the BSDF's own sample); n = 1, group = s
            wo = mi.warp.square_to_cosine_hemisphere(mi.Point2f(u, v))
            return wo, wo.z * _INV_PI
        if self.strategy == "symmetric_cosine":
            x, y, z = orbit_member(*cosine_wedge_point(u, v), member, members=8)
            return mi.Vector3f(x, y, z), z * _INV_PI
        bx, by, bz = triangle_point(u, v, self.method)
        density = triangle_density(bx, by, bz, self.method)
        x, y, z = orbit_member(bx, by, bz, member, members=24)
        return mi.Vector3f(x, y, z), density / n

    def _density(self, wo: Any, wi_z: Any) -> Any:
        """The strategy's density of the local direction *wo* (on the side of wi), for MIS."""
        same_side = wo.z * wi_z > 0
        if self.strategy in _COSINE_DENSITY:  # density |cos| / pi
            return dr.select(same_side, dr.abs(wo.z) * _INV_PI, 0.0)
        if self.method == "equal_area":
            return dr.select(same_side, 1.0 / (2.0 * math.pi), 0.0)
        a, b, c = dr.abs(wo.x), dr.abs(wo.y), dr.abs(wo.z)
        lo_ab, hi_ab = dr.minimum(a, b), dr.maximum(a, b)
        base = (dr.maximum(lo_ab, dr.minimum(hi_ab, c)), dr.minimum(lo_ab, c), dr.maximum(hi_ab, c))
        return dr.select(same_side, triangle_density(*base, self.method) / 24, 0.0)

    # --- the path loop (path.cpp) ------------------------------------------------------------------

    @dr.syntax
    def _trace(
        self, scene: Any, sampler: Any, ray: Any, key: Any, s: Any, table: Any, lights: Any = None
    ) -> tuple[Any, Any]:
        ray = mi.Ray3f(ray)
        # the variant's types (mi.Float & co.), which Mitsuba's stubs cannot name before run time
        throughput: Any = mi.Spectrum(1.0)
        result = mi.Spectrum(0.0)
        eta = mi.Float(1.0)
        depth = mi.UInt32(0)
        valid_ray = mi.Bool((not self.hide_emitters) and scene.environment() is not None)
        prev_si = dr.zeros(mi.Interaction3f)
        prev_bsdf_pdf: Any = mi.Float(1.0)
        prev_bsdf_delta = mi.Bool(True)
        active = mi.Bool(self.max_depth != 0)
        ctx = mi.BSDFContext()
        replaces = self.replaces_sample  # False for bsdf, and cosine with random points: the BSDF's own sample
        light_total = mi.Float64(0.0)  # emitter_sampling='solid_angle': the light choice's normaliser at prev_si

        while active:
            si = scene.ray_intersect(ray, ray_flags=mi.RayFlags.All, coherent=(depth == 0))
            if dr.hint(self.hide_emitters, mode="scalar"):  # Mitsuba's: the camera ray passes through area emitters
                skip = (depth == 0) & si.is_valid() & (si.shape.emitter() != None)  # noqa: E711 - a Dr.Jit comparison
                ray_skip = si.spawn_ray(ray.d)
                after = cast(mi.SamplingIntegrator, self).skip_area_emitters(scene, ray_skip, True, skip)
                si = dr.select(skip, after.compute_surface_interaction(ray_skip, mi.RayFlags.All, skip), si)

            # direct emission, weighted against the previous vertex's emitter sampling
            ds = mi.DirectionSample3f(scene, si=si, ref=prev_si)
            if dr.hint(lights is None, mode="scalar"):
                em_pdf = scene.pdf_emitter_direction(prev_si, ds, ~prev_bsdf_delta)
            else:  # emitter_sampling='solid_angle': the light table's density at prev_si
                em_pdf = lights.pdf_direction(scene, prev_si, si, ds, ~prev_bsdf_delta, light_total)
            mis_bsdf = _mis_weight(prev_bsdf_pdf, em_pdf)
            result = dr.fma(throughput, ds.emitter.eval(si, prev_bsdf_pdf > 0.0) * mis_bsdf, result)

            active_next = (depth + 1 < self.max_depth) & si.is_valid()
            bsdf = si.bsdf(ray)

            # emitter sampling
            active_em = active_next & mi.has_flag(bsdf.flags(), mi.BSDFFlags.Smooth)
            if dr.hint(lights is None, mode="scalar"):
                ds, em_weight = scene.sample_emitter_direction(si, sampler.next_2d(), True, active_em)
            else:
                ds, em_weight, light_total = lights.sample_direction(scene, si, sampler.next_2d(), active_em)
            active_em &= ds.pdf != 0.0
            wo = si.to_local(ds.d)

            sample_1 = sampler.next_1d()
            sample_2 = sampler.next_2d()
            bsdf_val, bsdf_pdf, bsdf_sample, bsdf_weight = bsdf.eval_pdf_sample(
                ctx, si, wo, sample_1, sample_2, active_next
            )

            if dr.hint(replaces, mode="scalar"):
                lambertian = active_next & (dr.gather(mi.UInt32, table, _bsdf_ids(bsdf), active_next) != 0)
                local, pdf_local = self._local_direction(key, s, depth)
                local.z = dr.mulsign(local.z, si.wi.z)
                # A Lambertian BSDF's own (cosine) sample has weight f cos / pdf = its reflectance R at si,
                # whatever the direction (0 where wi is below a one-sided surface, and in the measure-zero
                # event that its own direction has pdf 0), so f cos at `local` is R |z| / pi: no second
                # BSDF evaluation (texture lookup, virtual call) per vertex.
                if dr.hint(self.strategy in _COSINE_DENSITY, mode="scalar"):
                    weight_local = bsdf_weight  # pdf_local = |z| / pi: the weight is R
                else:
                    weight_local = dr.select(
                        pdf_local > 0.0, bsdf_weight * (dr.abs(local.z) * _INV_PI / pdf_local), 0.0
                    )
                bsdf_pdf = dr.select(lambertian, self._density(wo, si.wi.z), bsdf_pdf)
                bsdf_sample.wo = dr.select(lambertian, local, bsdf_sample.wo)
                bsdf_sample.pdf = dr.select(lambertian, pdf_local, bsdf_sample.pdf)
                bsdf_weight = dr.select(lambertian, weight_local, bsdf_weight)

            mis_em = dr.select(ds.delta, 1.0, _mis_weight(ds.pdf, bsdf_pdf))
            result[active_em] = dr.fma(throughput, bsdf_val * em_weight * mis_em, result)

            # BSDF sampling: the next ray and the loop state
            ray = si.spawn_ray(si.to_world(bsdf_sample.wo))
            throughput *= bsdf_weight
            eta *= bsdf_sample.eta
            valid_ray |= active & si.is_valid() & ~mi.has_flag(bsdf_sample.sampled_type, mi.BSDFFlags.Null)
            prev_si = mi.Interaction3f(si)
            prev_bsdf_pdf = bsdf_sample.pdf
            prev_bsdf_delta = mi.has_flag(bsdf_sample.sampled_type, mi.BSDFFlags.Delta)

            # Russian roulette
            depth[si.is_valid()] += 1
            throughput_max = dr.max(mi.unpolarized_spectrum(throughput))
            rr_prob = dr.minimum(throughput_max * dr.square(eta), 0.95)
            rr_active = depth >= self.rr_depth
            rr_continue = sampler.next_1d() < rr_prob
            throughput[rr_active] *= dr.rcp(rr_prob)
            active = active_next & (~rr_active | rr_continue) & (throughput_max != 0.0)

        return dr.select(valid_ray, result, 0.0), valid_ray


_CLASSES: dict[str, type] = {}


def integrator_class() -> type:
    """The ``symsphere_path`` class of the current Mitsuba variant (a subclass of its ``mi.SamplingIntegrator``)."""
    variant = mi.variant()
    if variant is None:
        raise RuntimeError("no Mitsuba variant is set: call mi.set_variant('llvm_ad_rgb') (or another) first")
    if variant not in _CLASSES:
        methods = {k: v for k, v in vars(_PathMethods).items() if k not in ("__dict__", "__weakref__")}
        _CLASSES[variant] = type("SymspherePath", (mi.SamplingIntegrator,), methods)  # nanobind: one base only
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
