"""Independent reference densities and quadratures shared by several test files.

Written from their formulas here, not with the code under test.  (tests/ is on pytest's
``pythonpath``: ``from references import ...``.)
"""

import math

import numpy as np

# --- comparing two implementations of one formula -----------------------------------
#
# The error model every cross-implementation comparison in the tests uses.  numpy's ufuncs run its own
# SIMD code or Intel's SVML (AVX2, AVX-512: chosen at run time per CPU), or libm; a numba kernel and
# Python's ``math`` call libm.  So sin, cos, tan, atan, atan2, asin, acos, exp, log, hypot, power may
# differ in the last bits between two paths, machines and numpy builds.  What the tests assume:
#
# - each of those elementary functions is within ELEMENTARY_ULPS ulps of its exact value, on every
#   path: numpy's accuracy tests (numpy/_core/tests/test_umath_accuracy.py, its umath-validation-set
#   files) allow up to 4 ulps for its SIMD transcendentals; glibc's are within 1-2 (its manual's table);
# - +, -, *, / and sqrt are correctly rounded (IEEE 754): the same operands in the same order give
#   the same bits on every path.  numba compiles without fastmath, so LLVM neither reorders nor
#   contracts a * b + c into an FMA; numpy applies one operation per ufunc call.  Sums whose order
#   differs (matmul, BLAS, with or without FMA) are bounded by GAMMA3 for a 3-term dot product;
# - an ulp of t is at most EPS64 * |t| (EPS32 for float32); relative errors add, to first order, and
#   an input's relative error is multiplied by the function's condition number |t f'(t) / f(t)|.
#
# Two paths that each stay within k ulps of the exact result differ by at most 2 k of them.  The
# numbers below are stated and derived where they are used.
ELEMENTARY_ULPS = 4
EPS64 = float(np.finfo(np.float64).eps)  # 2^-52
EPS32 = float(np.finfo(np.float32).eps)  # 2^-23
GAMMA3 = 1.5  # 3 u / (1 - 3 u) with u = EPS / 2: a 3-term dot product of unit vectors, in EPS, per path


def assert_within_eps(got, expected, k, *, scale=None, eps=EPS64):
    """|got - expected| <= k * eps * scale, elementwise (scale: |expected| by default, i.e. relative).

    For unit vectors pass scale=1 (an absolute bound in units of eps).  Reports the worst ratio.
    """
    got = np.asarray(got, dtype=np.float64)
    expected = np.asarray(expected, dtype=np.float64)
    got, expected = np.broadcast_arrays(got, expected)
    bound = np.broadcast_to(
        k * eps * (np.abs(expected) if scale is None else np.asarray(scale, dtype=np.float64)), got.shape
    )
    excess = np.abs(got - expected) - bound
    worst = np.unravel_index(int(np.argmax(excess)), excess.shape) if excess.size else ()
    assert excess.size == 0 or excess[worst] <= 0, (
        f"differ by {abs(got[worst] - expected[worst]):.3g} > {k} eps = {bound[worst]:.3g} at {worst}: "
        f"{got[worst]!r} vs {expected[worst]!r}"
    )


def scaled_for_load(seconds):
    """A time limit *seconds* (measured on an idle machine) stretched by the 1-minute load average per core.

    The suite runs under pytest-xdist (one worker per core) on machines shared with others: a limit that
    separates "fails fast" from "computes for minutes" must not fail because the cores are busy.
    """
    import os

    return seconds * max(1.0, os.getloadavg()[0] / (os.cpu_count() or 1))


# Linear density on T0: z / int_T0 z d(omega), with int_T0 z = atan(1/sqrt 2) / (2 sqrt 2).
LINEAR_NORM = 2 * math.sqrt(2) / math.atan(1 / math.sqrt(2))


def frame(axis):
    axis = np.asarray(axis, dtype=np.float64)
    axis = axis / np.linalg.norm(axis)
    helper = np.array([1.0, 0.0, 0.0]) if abs(axis[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    t = np.cross(axis, helper)
    t /= np.linalg.norm(t)
    return t, np.cross(axis, t), axis


def cap_rule(axis, cos_lo, cos_hi, n_cos, n_psi):
    """Nodes and weights for the region cos_lo <= w.axis <= cos_hi (GL in cos t x trapezoid in psi)."""
    x, w = np.polynomial.legendre.leggauss(n_cos)
    cos = 0.5 * (cos_hi - cos_lo) * x + 0.5 * (cos_hi + cos_lo)
    wc = 0.5 * (cos_hi - cos_lo) * w
    psi = 2 * np.pi * np.arange(n_psi) / n_psi
    c, p = np.meshgrid(cos, psi, indexing="ij")
    s = np.sqrt(np.maximum(0.0, (1 - c) * (1 + c)))
    t, b, n = frame(axis)
    d = (s * np.cos(p))[..., None] * t + (s * np.sin(p))[..., None] * b + c[..., None] * n
    weights = wc[:, None] * np.full(n_psi, 2 * np.pi / n_psi)
    return d.reshape(-1, 3), weights.ravel()


def in_t0(d):
    x, y, z = d[:, 0], d[:, 1], d[:, 2]
    return (z >= x) & (x >= y) & (y >= 0)


def cosine_pdf(d):
    return np.maximum(d[:, 2], 0) / np.pi


def pole_pdf(d):
    """Density of pole_sampler: 4 x / (pi z^2 (x^2 + y^2)) on T0 (1/sin(theta) at the pole)."""
    x, y, z = d[:, 0], d[:, 1], d[:, 2]
    r2 = x * x + y * y
    inside = in_t0(d) & (r2 > 0)
    safe_r2 = np.where(inside, r2, 1.0)
    safe_z = np.where(inside, z, 1.0)
    return np.where(inside, 4 * x / (np.pi * safe_z**2 * safe_r2), 0.0)


def linear_triangle_pdf(d):
    return np.where(in_t0(d), LINEAR_NORM * d[:, 2], 0.0)


def cmax(phi):
    return np.cos(phi) / np.sqrt(1 + np.cos(phi) ** 2)


def net_t_value(x, m):
    """The smallest t such that every elementary dyadic box of volume 2^-(m - t) holds 2^t of the 2^m points.

    Brute force over every split of the m - t digits among the coordinates: the definition of a
    (t, m, s)-net in base 2, independent of how the points were made.
    """
    n, s = x.shape
    assert n == 2**m
    cells = np.floor(x * 2.0**m).astype(np.int64)  # the leading m digits of each coordinate

    def splits(total, parts):
        if parts == 1:
            yield (total,)
            return
        for first in range(total + 1):
            for rest in splits(total - first, parts - 1):
                yield (first,) + rest

    def box_index(depths):
        index = np.zeros(n, dtype=np.int64)
        for j, k in enumerate(depths):
            index = (index << k) | (cells[:, j] >> (m - k))
        return index

    for t in range(m + 1):
        if all(np.all(np.bincount(box_index(d), minlength=2 ** (m - t)) == 2**t) for d in splits(m - t, s)):
            return t
    raise AssertionError("unreachable: t = m always holds")


# --- the power of a chi-square test ----------------------------------------------------------------
#
# Against an alternative density q (bin probabilities q_i instead of p_i), Pearson's statistic over n
# independent samples is approximately noncentral chi-square with the test's degrees of freedom and
# noncentrality n w^2, w^2 = sum (q_i - p_i)^2 / p_i (Cohen's effect size w).  Example: a density too high by
# a factor 1 + delta on a fraction f of the domain (and too low by delta f / (1 - f) elsewhere) has
# w = delta sqrt(f / (1 - f)); delta = 5 % on a tenth: w = 0.0167.


def chi2_power(n, dof, w, threshold):
    """P(reject) at per-test significance *threshold* (Sidak-corrected) for effect size *w* and n samples."""
    from scipy import stats

    return float(stats.ncx2.sf(stats.chi2.isf(threshold, dof), dof, n * w * w))


def chi2_detectable_w(n, dof, threshold, power=0.99):
    """The smallest effect size w that a chi-square test of n samples rejects with probability *power*."""
    from scipy import optimize

    return float(optimize.brentq(lambda w: chi2_power(n, dof, w, threshold) - power, 1e-6, 10.0))


def assert_power(result, w, power=0.99):
    """The test behind *result* (a symsphere.stats.Chi2Result) rejects an alternative of effect size *w*
    with probability >= *power*: so its sample size is enough for what it must detect."""
    n = int(result.observed.sum())
    got = chi2_power(n, result.dof, w, result.threshold)
    assert got >= power, (
        f"power {got:.3f} < {power} against w = {w} (n = {n}, dof = {result.dof}); "
        f"this n detects w >= {chi2_detectable_w(n, result.dof, result.threshold, power):.4f}"
    )


def raises_naming(call, error, named):
    """*call()* raises *error* whose message matches *named* (the argument it names), with no warning first."""
    import warnings

    import pytest

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(error, match=named):
            call()


def one_line_error(stderr: str) -> str:
    """The one line a command wrote on stderr (no traceback), for the one-line-error tests."""
    # tqdm bars aside, and the line saying numba compiles (a first run with an empty cache)
    lines = [
        line
        for line in stderr.splitlines()
        if line.strip() and "%" not in line and "compiling numba kernels" not in line
    ]
    assert "Traceback" not in stderr, stderr
    assert len(lines) == 1, stderr
    return lines[0]


def writing_in(pid: int, directory, min_size: int = 0) -> bool:
    """Whether process *pid* has a file of at least *min_size* bytes open in *directory*: its output's
    temporary, which on Linux is unnamed (``O_TMPFILE``: /proc shows ``DIR/#inode (deleted)``) and so
    cannot be seen in the directory's listing."""
    import os

    folder = os.path.realpath(directory)
    try:
        descriptors = os.listdir(f"/proc/{pid}/fd")
    except OSError:
        return False
    for descriptor in descriptors:
        try:
            target = os.readlink(f"/proc/{pid}/fd/{descriptor}")
            size = os.stat(f"/proc/{pid}/fd/{descriptor}").st_size
        except OSError:
            continue
        if os.path.dirname(target.removesuffix(" (deleted)")) == folder and size >= min_size:
            return True
    return False


def inject_sigint(monkeypatch, module, name, at_call):
    """Send SIGINT to this process from inside the at_call-th call of module.name (after the call)."""
    import os
    import signal

    real = getattr(module, name)
    calls = []

    def wrapper(*args, **kwargs):
        calls.append(None)
        result = real(*args, **kwargs)
        if len(calls) == at_call:
            os.kill(os.getpid(), signal.SIGINT)
        return result

    monkeypatch.setattr(module, name, wrapper)


def catches(pid: int, signum: int) -> bool:
    """Whether process *pid* has a handler for *signum* (Linux: the SigCgt mask of /proc/PID/status); False
    where that cannot be read.  ``symsphere`` installs its SIGTERM handler when ``main()`` starts, after
    the package's imports: a signal before then ends the process the default way."""
    try:
        with open(f"/proc/{pid}/status") as status:
            for line in status:
                if line.startswith("SigCgt:"):
                    return bool(int(line.split()[1], 16) >> (signum - 1) & 1)
    except OSError:
        pass
    return False
