"""Small kernels for the tests and the documentation: the integrator's scalar functions over arrays.

Each runs one function of the path tracer (as the kernel, which LLVM inlines it into) -- the samplers
(:func:`~symsphere.render._directions.sample_local`,
:func:`~symsphere.render._directions.bsdf_pdf`), the intersection
(:func:`~symsphere.render._integrator.intersect`), the emitters
(:func:`~symsphere.render._emitters.sample_emitter`,
:func:`~symsphere.render._emitters.emitter_pdf`) and the Sobol' points
(:func:`~symsphere._random.owen_sobol.owen_sobol2`,
:func:`~symsphere._random.owen_sobol.owen_sobol_interlaced`) -- over many inputs, so that
the tests see exactly what the kernel computes.  Call :func:`prepare_kernels`
before the first of them runs.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .._numba_cache import invalidate_if_changed
from .._random.hashes import path_state, pixel_key
from .._random.owen_sobol import interlace_fractions, owen_sobol2, owen_sobol_interlaced, sobol_coordinate
from .._threads import route_compiles
from . import _integrator
from ._directions import bsdf_pdf, fixed_sampler, is_cosine, sample_local
from ._emitters import emitter_pdf, sample_emitter
from ._integrator import KERNEL_OPTIONS, intersect, plain_spheres

__all__ = [
    "bsdf_pdfs",
    "emitter_pdfs",
    "emitter_samples",
    "first_hits",
    "interlaced_points",
    "pattern_directions",
    "prepare_kernels",
    "sobol_points",
]


@njit(**KERNEL_OPTIONS)
def pattern_directions(sampler, code, full, seed, pixel, depth, samples):
    """Local directions, weights and pdfs (columns x, y, z, weight, pdf) of samples 0..samples-1 of *pixel*.

    The same :func:`~symsphere.render._directions.sample_local` the integrator calls, with each sample's
    own stream advanced as if its path had reached *depth* with no other
    random draws; for the symmetric samplers the stream is not used.
    """
    out = np.empty((samples, 5))
    key = pixel_key(seed, pixel)
    for s in range(samples):
        state = path_state(key, s)
        x, y, z, weight, pdf, state = sample_local(
            sampler, fixed_sampler(sampler), is_cosine(sampler), code, full, key, s, depth, state
        )
        out[s, 0] = x
        out[s, 1] = y
        out[s, 2] = z
        out[s, 3] = weight
        out[s, 4] = pdf
    return out


@njit(**KERNEL_OPTIONS)
def bsdf_pdfs(sampler, code, full, directions):
    """:func:`~symsphere.render._directions.bsdf_pdf` of each local unit direction (rows of *directions*)."""
    out = np.empty(directions.shape[0])
    for i in range(directions.shape[0]):
        out[i] = bsdf_pdf(
            fixed_sampler(sampler), is_cosine(sampler), code, full, directions[i, 0], directions[i, 1], directions[i, 2]
        )
    return out


@njit(**KERNEL_OPTIONS)
def first_hits(origins, directions, spheres, quads, eps):
    """:func:`~symsphere.render._integrator.intersect` for each ray: (t, object index) arrays."""
    count = origins.shape[0]
    ts = np.empty(count)
    hits = np.empty(count, dtype=np.int64)
    scratch = np.empty(max(spheres.shape[1], quads.shape[1], 1))
    plain = plain_spheres(spheres)
    for i in range(count):
        ts[i], hits[i] = intersect(
            origins[i, 0], origins[i, 1], origins[i, 2], directions[i, 0], directions[i, 1], directions[i, 2],
            spheres, plain, quads, eps, scratch, np.inf,
        )  # fmt: skip
    return ts, hits


@njit(**KERNEL_OPTIONS)
def emitter_samples(point, obj, seed, count, spheres, quads):
    """*count* :func:`~symsphere.render._emitters.sample_emitter` draws from *point* (stream *seed*).

    Columns wx, wy, wz, distance, pdf, ok.
    """
    out = np.empty((count, 6))
    state = np.uint64(seed)
    for i in range(count):
        wx, wy, wz, dist, pdf, ok, state = sample_emitter(
            point[0], point[1], point[2], obj, state, spheres, quads, True, True, True, True
        )
        out[i, 0], out[i, 1], out[i, 2], out[i, 3], out[i, 4], out[i, 5] = wx, wy, wz, dist, pdf, ok
    return out


@njit(**KERNEL_OPTIONS)
def emitter_pdfs(point, obj, ts, cosines, spheres, quads):
    """:func:`~symsphere.render._emitters.emitter_pdf` from *point* of hits of *obj* at distances *ts*.

    *cosines*: |cos| between each ray and the emitter's normal at the hit.
    """
    out = np.empty(ts.shape[0])
    for i in range(ts.shape[0]):
        out[i] = emitter_pdf(
            point[0], point[1], point[2], obj, ts[i], cosines[i], spheres, quads, True, True, True, True
        )
    return out


@njit(**KERNEL_OPTIONS)
def sobol_points(count, key):
    """The first *count* points of the Owen-scrambled 2D Sobol' sequence with 64-bit *key*."""
    out = np.empty((count, 2))
    for i in range(count):
        out[i, 0], out[i, 1] = owen_sobol2(i, key)
    return out


@njit(**KERNEL_OPTIONS)
def interlaced_points(count, key, factor, scrambled):
    """The first *count* interlaced Sobol' points (factor 2 or 3): scrambled with *key*, or not (key unused).

    Scrambled: :func:`~symsphere._random.owen_sobol.owen_sobol_interlaced`, as the
    kernel draws them.  Unscrambled: the reference, natural-order points
    ``interlace_fractions(sobol_coordinate(i, 0), ...)``.
    """
    out = np.empty((count, 2))
    for i in range(count):
        if scrambled:
            out[i, 0], out[i, 1] = owen_sobol_interlaced(i, key, factor)
        else:
            x = [sobol_coordinate(i, d) for d in range(6)]
            if factor == 2:
                out[i, 0] = interlace_fractions(x[0], x[1], x[1], 2)
                out[i, 1] = interlace_fractions(x[2], x[3], x[3], 2)
            else:
                out[i, 0] = interlace_fractions(x[0], x[1], x[2], 3)
                out[i, 1] = interlace_fractions(x[3], x[4], x[5], 3)
    return out


_ready = False


def prepare_kernels() -> None:
    """Before the first kernel of this module runs: :func:`symsphere.render._integrator.prepare_kernels`,
    and the same disk-cache guard for this module's kernels (they inline the integrator's functions).
    """
    global _ready
    if not _ready:
        _integrator.prepare_kernels()
        invalidate_if_changed(first_hits)
        _ready = True


route_compiles(globals())  # the first compile of each numba function here: interruptible (_threads)
