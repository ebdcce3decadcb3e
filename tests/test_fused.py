"""Fused integration: compiled integrands evaluated inside the kernel give the numpy path's result.

The reference is the numpy path (``integrate`` with a numpy ``f``): the same estimator and
error bar, so the results must agree to rounding (relative 1e-12) for every map, point set,
domain and normal.  The kernel's only differences (the order of the sums, the batch-merged
sum of squared deviations) are rounding-level; see symsphere._fused.
"""

import mpmath
import numpy as np
import pytest
from numba import njit
from scipy.stats import qmc

import symsphere as ss
from symsphere import METHODS, integrate
from symsphere._testing import integrand_kernels
from symsphere.integrands import INTEGRANDS
from symsphere.points import BLOCK

vexp = integrand_kernels.vexp

A = np.array([0.7, -0.4, 0.5])


@njit
def exp_xyz(x, y, z):
    return np.exp(0.7 * x - 0.4 * y + 0.5 * z)


@njit
def exp_vector(w):
    return np.exp(w[0] * A[0] + w[1] * A[1] + w[2] * A[2])


def exp_numpy(w):
    return np.exp(w @ A)


def _close(fused, reference, rtol=1e-12):
    assert fused.n_evaluations == reference.n_evaluations and fused.n_units == reference.n_units
    assert fused.unit == reference.unit
    np.testing.assert_allclose(fused.integral, reference.integral, rtol=rtol, atol=0)
    scale = np.abs(reference.integral)  # replicate errors of smooth integrands cancel: rounding of |I|
    np.testing.assert_allclose(fused.standard_error, reference.standard_error, rtol=1e-9, atol=1e-12 * scale)


# The tests of exp_xyz and exp_vector on one xdist worker (Makefile: --dist loadgroup): a user's compiled f is
# compiled into a kernel per map in each process that runs it (numba cannot cache it on disk), once here.
_USER_F = pytest.mark.xdist_group("fused_user_f")


@_USER_F
@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize(
    "domain, normal, points",
    [
        ("sphere", None, "random"),
        ("sphere", None, "stratified"),
        ("sphere", None, "sobol"),
        ("sphere", None, "halton"),
        ("hemisphere", None, "random"),
        ("hemisphere", None, "sobol"),
        ("hemisphere", [0.3, 0.4, -0.5], "random"),
        ("hemisphere", [0.3, 0.4, -0.5], "stratified"),
    ],
)
def test_fused_equals_numpy_path(method, domain, normal, points):
    count = 48 if domain == "sphere" else 24
    kwargs = dict(domain=domain, normal=normal, n=count * (2 * BLOCK + 100), method=method, points=points, rng=11)
    if points != "random":
        kwargs["replicates"] = 4
        kwargs["n"] = count * 4 * (48**2 if points == "stratified" else 2**12)
    reference = integrate(exp_numpy, **kwargs)
    _close(integrate(exp_xyz, **kwargs), reference)
    _close(integrate(exp_vector, **kwargs), reference)


@_USER_F
def test_fused_with_an_engine():
    reference = integrate(exp_numpy, n=48 * 1024, points=qmc.Sobol(d=2, rng=4))
    fused = integrate(exp_xyz, n=48 * 1024, points=qmc.Sobol(d=2, rng=4))
    assert fused.unit == "run" and np.isnan(fused.standard_error)
    np.testing.assert_allclose(fused.integral, reference.integral, rtol=1e-12)


@_USER_F
def test_fused_does_not_depend_on_threads():
    from numba import get_num_threads, set_num_threads

    kwargs = dict(n=48 * (3 * BLOCK + 17), rng=2)
    many = integrate(exp_xyz, **kwargs)
    threads = get_num_threads()
    try:
        set_num_threads(1)
        one = integrate(exp_xyz, **kwargs)
    finally:
        set_num_threads(threads)
    assert one == many  # bit for bit


@pytest.mark.parametrize("name", ["exp", "exp_hemisphere", "cap", "quad_light", "shifted_cubic4", "sh4_0"])
def test_suite_integrands_fused(name):
    g = INTEGRANDS[name]
    count = 48 if g.domain == "sphere" else 24
    kwargs = dict(domain=g.domain, n=count * 3 * BLOCK, rng=5)
    _close(integrate(g, **kwargs), integrate(g.f, **kwargs), rtol=1e-11)


def _directions(g):
    return ss.sample_hemisphere(24 * 40, rng=3) if g.domain == "hemisphere" else ss.sample_sphere(48 * 20, rng=3)


def _spec_in_python(g):
    """g's kernel as Python: the same code numba compiles (the polynomial's chain of register_jitable
    functions, which stay Python functions, or evaluate's Python source) with g's constants."""
    kind, params, chain = g.kernel.symsphere_spec
    if kind == integrand_kernels.POLYNOMIAL:
        return chain
    return lambda x, y, z: integrand_kernels.evaluate.py_func(kind, params, x, y, z)


@pytest.mark.parametrize("name", sorted(INTEGRANDS))
def test_suite_kernels_equal_f(name):
    # Every integrand's kernel (its formula with its constants, run as Python) is f.  Numba's compile of the
    # formulas is checked below, once per formula: compiling each of the 37 kernels on its own costs ~18 CPU-s
    # that no other test needs (the fused kernels inline the same spec: test_suite_integrands_fused).
    g = INTEGRANDS[name]
    assert g.kernel is not None
    d = _directions(g)
    values = np.array([_spec_in_python(g)(*w) for w in d])
    np.testing.assert_allclose(values, g.f(d), rtol=1e-12, atol=1e-13)


# One integrand of each formula, and two polynomials: a shift and three terms, and a constant term (zero exponents).
_COMPILED = ("cap", "cosine", "exp", "phong", "quad_light", "sphere_light", "shifted_sh4_0", "shifted_cubic4")


def test_compiled_cases_cover_every_formula():
    assert {INTEGRANDS[name].kernel.symsphere_spec[0] for name in _COMPILED} == set(integrand_kernels.KINDS)


@pytest.mark.parametrize("name", _COMPILED)
def test_compiled_suite_kernel_equals_its_python(name):
    g = INTEGRANDS[name]
    d = _directions(g)
    python = np.array([_spec_in_python(g)(*w) for w in d])
    compiled = np.array([g.kernel(*w) for w in d])
    np.testing.assert_allclose(compiled, python, rtol=1e-14, atol=1e-15)
    np.testing.assert_allclose(compiled, g.f(d), rtol=1e-12, atol=1e-13)


def test_vexp_within_two_ulps_of_exact():
    # Against the exact value (mpmath, 80 bits), not numpy's exp (libm on AVX2 machines, numpy's
    # own AVX-512 code elsewhere: another implementation).  The bound, 2 ulps: t = k ln2 + r with
    # |r| <= ln2/2 (Cody-Waite: r's error below 1e-19, exp's condition |r| <= 0.35 keeps it there);
    # Horner's rule for the Taylor polynomial to r^13 (remainder < 4e-18 = 0.04 ulp): the last step's
    # "+ 1" and "* r" round at most u = eps/2 each, an earlier step's roundings are damped by |r| per
    # later step, so the absolute error is below u (e^|r| + 2 * 1.2 |r| / (1 - |r|)) < 2.7 u, i.e.
    # < 3.8 u = 1.9 ulps relative to exp(r) >= e^-0.35; the product by 2^k is exact (t >= -708: no
    # subnormals).  Measured: 1.08 ulps; libm's exp: 0.51.
    mpmath.mp.prec = 80
    t = np.concatenate([np.linspace(-708, 709, 200_001), np.random.default_rng(0).normal(0, 3, 100_000)])[::7]
    got = np.array([vexp(x) for x in t])
    error = np.array(
        [float(abs(mpmath.mpf(g) - mpmath.exp(x))) for g, x in zip(got.tolist(), t.tolist(), strict=False)]
    )
    assert np.all(error <= 2 * np.spacing(got)), float(np.max(error / np.spacing(got)))
    assert np.isfinite(vexp(1e6)) and vexp(-1e6) >= 0


def test_compiled_f_errors():
    @njit
    def two(x, y):
        return x + y

    @njit
    def pair(x, y, z):
        return (x, y)

    @njit
    def blows_up(x, y, z):
        return np.sqrt(x)  # NaN for x < 0

    with pytest.raises(TypeError, match="f\\(x, y, z\\) or f\\(w\\)"):
        integrate(two, n=48)
    with pytest.raises(TypeError, match="one real number"):
        integrate(pair, n=48)
    with pytest.raises(ValueError, match="non-finite"):
        integrate(blows_up, n=48 * 16, rng=0)


@pytest.mark.slow
@pytest.mark.xdist_group("dask")  # a local Dask cluster: with the other cluster tests (Makefile: --dist loadgroup)
def test_distributed_ships_the_fused_kernel(dask_client):
    """distributed.integrate with a compiled f: bit for bit the single-process fused result."""
    from symsphere import distributed

    kwargs = dict(n=48 * (3 * BLOCK + 5), rng=8)
    single = integrate(exp_xyz, **kwargs)
    for chunk_blocks in (1, 2):
        result = distributed.integrate(exp_xyz, client=dask_client, chunk_blocks=chunk_blocks, **kwargs)
        assert result == single
    result = distributed.integrate(INTEGRANDS["exp"], client=dask_client, **kwargs)
    assert result == integrate(INTEGRANDS["exp"], **kwargs)


@pytest.mark.parametrize("name, points", [("exp", "random"), ("cap", "sobol"), ("exp_hemisphere", "stratified")])
def test_specialised_kernel_equals_generic(name, points):
    """A suite integrand runs the specialised (cached) kernel; the generic one gives the same bits."""
    g = INTEGRANDS[name]
    generic = njit(error_model="numpy")(g.kernel.py_func)  # no symsphere_spec: the generic kernel
    count = 48 if g.domain == "sphere" else 24
    orbits = {"stratified": 65**2, "sobol": 2 * BLOCK}.get(points, BLOCK + 3)  # per replicate: more than one block
    kwargs = dict(domain=g.domain, n=count * 8 * orbits, points=points, rng=4)
    assert integrate(g, **kwargs) == integrate(generic, **kwargs)


CACHED_RUN = """
import symsphere
from symsphere._testing import fused
from symsphere.integrands import INTEGRANDS
result = symsphere.integrate(INTEGRANDS["exp"], n=48 * 100, rng=1)
(kernel,) = fused.specialised_kernels()
print(result.integral, sum(kernel.stats.cache_hits.values()), sum(kernel.stats.cache_misses.values()))
"""


@pytest.mark.slow
def test_suite_kernel_cached_across_processes(tmp_path):
    """The suite's fused kernel is compiled once, then loaded from numba's disk cache by a new process."""
    import os
    import subprocess
    import sys

    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path))
    runs = []
    for _ in range(2):
        out = subprocess.run([sys.executable, "-c", CACHED_RUN], env=env, capture_output=True, text=True, timeout=600)
        assert out.returncode == 0, out.stderr
        runs.append(out.stdout.split())
    (first_value, first_hits, first_misses), (second_value, second_hits, second_misses) = runs
    assert first_value == second_value
    assert (first_hits, first_misses) == ("0", "1") and (second_hits, second_misses) == ("1", "0")
