"""Property-based tests (Hypothesis) of the error contract of every public function.

Every public function of the library's modules, called with valid arguments except one, which is
replaced by an arbitrary value (odd types, NaN, inf, huge and negative numbers, arrays of any shape
and dtype), must either

- return finite output (float arrays and numbers: no NaN, no inf, except where a density is documented
  to be inf: the paper's maps at their vertex), or
- raise ``ValueError`` or ``TypeError`` whose one-line message names the replaced argument,

never another exception, never a warning (``pyproject.toml`` turns RuntimeWarning into an error), and
within a deadline.  A second group feeds every direction function arrays of arbitrary shapes and
dtypes and checks the documented output shape.

Profiles: ``ci`` (the default: ~40 examples per function, a few thousand in all, ~1 minute) and
``thorough`` (``SYMSPHERE_HYPOTHESIS=thorough``: 1000 per function), both derandomised in CI so that
a failure is reproducible; ``SYMSPHERE_HYPOTHESIS_EXAMPLES=N`` sets the count directly.
"""

from __future__ import annotations

import inspect
import math
import os
from datetime import timedelta

import numpy as np
import pytest

hypothesis = pytest.importorskip("hypothesis")
from hypothesis import HealthCheck, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402
from hypothesis.extra import numpy as hnp  # noqa: E402

import symsphere  # noqa: E402
from symsphere import (  # noqa: E402  # noqa: E402
    bins,
    frames,
    harmonics,
    integrands,
    integration,
    peers,
    quality,
    sampling,
    stats,
    symmetry,
    warps,
)
from symsphere import points as points_module  # noqa: E402

_COMMON = dict(
    deadline=timedelta(seconds=5),
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much, HealthCheck.data_too_large],
    database=None,
)
settings.register_profile("ci", max_examples=40, derandomize=True, **_COMMON)
settings.register_profile("thorough", max_examples=1000, **_COMMON)
_examples = os.environ.get("SYMSPHERE_HYPOTHESIS_EXAMPLES")
if _examples:
    settings.register_profile("custom", max_examples=int(_examples), **_COMMON)
settings.load_profile("custom" if _examples else os.environ.get("SYMSPHERE_HYPOTHESIS", "ci"))

_T0_POINT = np.array([[0.3, 0.2, 0.93273791]]) / np.linalg.norm([0.3, 0.2, 0.93273791])
_SAMPLES = symsphere.sample_sphere(480, rng=1)

# Valid values, by parameter name (overridden per function below).
VALID = {
    "n": 48, "n_total": 48, "chunk": 48, "m": 1, "l": 2, "lmax": 3, "a": 2, "b": 0, "c": 0,
    "d": _T0_POINT, "p": _T0_POINT, "uv": np.array([[0.25, 0.5]]), "normal": [0.0, 0.0, 1.0],
    "method": "equal_area", "points": "random", "rng": 1, "dtype": np.float64, "domain": "sphere",
    "coeffs": {(2, 0, 0): 1.0}, "degree": 4, "f": lambda d: np.tanh(d[:, 0]), "pdf": stats.uniform_pdf(),
    "samples": _SAMPLES, "bins": (4, 4), "directions": _SAMPLES[:48], "orbit_size": 48,
    "vertices": warps.T0_VERTICES, "center": [0.0, 0.0, 3.0], "distance": 3.0, "radius": 1.0, "radiance": 1.0,
    "local": np.array([[0.0, 0.6, 0.8]]), "world": np.array([[0.0, 0.6, 0.8]]), "basis": np.eye(3),
    "nx": 0.0, "ny": 0.0, "nz": 1.0, "x": 0.3, "y": 0.2, "z": 0.93273791, "u": 0.3, "v": 0.5,
    "weights": None, "values": [1.0, 0.5, 0.25], "estimates": [[1.0, 1.1], [0.9, 1.0]], "exact": 1.0,
    "quadrature_order": 4, "significance": 0.01, "randomize": False, "replicates": None,
    "confidence_level": 0.95, "floor": 1e-300, "test": "chi2", "per_point": 1,
}  # fmt: skip
OVERRIDES = {
    "square_to_spherical_triangle": dict(a=warps.T0_VERTICES[0], b=warps.T0_VERTICES[1], c=warps.T0_VERTICES[2]),
    "spherical_triangle_to_square": dict(a=warps.T0_VERTICES[0], b=warps.T0_VERTICES[1], c=warps.T0_VERTICES[2]),
    "square_to_spherical_triangle_pdf": dict(a=warps.T0_VERTICES[0], b=warps.T0_VERTICES[1], c=warps.T0_VERTICES[2]),
    "square_to_spherical_rectangle": dict(corner=[-1.0, -1.0, 1.0], edge1=[2.0, 0.0, 0.0], edge2=[0.0, 2.0, 0.0]),
    "spherical_rectangle_to_square": dict(corner=[-1.0, -1.0, 1.0], edge1=[2.0, 0.0, 0.0], edge2=[0.0, 2.0, 0.0]),
    "square_to_spherical_rectangle_pdf": dict(corner=[-1.0, -1.0, 1.0], edge1=[2.0, 0.0, 0.0], edge2=[0.0, 2.0, 0.0]),
    **{
        name: dict(a=warps.T0_VERTICES[0], b=warps.T0_VERTICES[1], c=warps.T0_VERTICES[2], n=[0.0, 0.0, 1.0])
        for name in (
            "projected_solid_angle",
            "square_to_projected_triangle",
            "square_to_projected_triangle_pdf",
            "projected_triangle_to_square",
        )
    },
    "projected_triangle_setup": dict(verts=warps.T0_VERTICES, normal=np.array([0.0, 0.0, 1.0])),
    **{
        name: dict(s=warps.projected_triangle_setup(warps.T0_VERTICES, np.array([0.0, 0.0, 1.0])))
        for name in ("projected_triangle_point", "projected_triangle_uv", "projected_triangle_density")
    },
    "rectangle_frame": dict(x0=-1.0, y0=-1.0, z0=1.0, width=2.0, height=2.0),
    "rectangle_point": dict(
        zip(
            ("solid_angle", "x0", "y0", "z0", "x1", "y1", "zsign", "b0", "b1", "ck", "sk"),
            warps.rectangle_frame(-1.0, -1.0, 1.0, 2.0, 2.0),
            strict=True,
        )
    ),  # fmt: skip
    "fit_slope": dict(n=[48, 96, 192]),
    "cap_discrepancy": dict(points=_SAMPLES[:48]),
    "cap_discrepancy_squared": dict(points=_SAMPLES[:48]),
    "unit_square_points": dict(m=4),
    "fibonacci_points": dict(n=5),
    "fibonacci_point": dict(i=2, n=5),
    "get_warp": dict(name="uniform_sphere"),
    "square_to_concentric_disk_pdf": dict(p=np.array([[0.3, 0.2]])),
    "sample_fibonacci": dict(n=5),
    "sample_gaussian": dict(n=5),
    "sample_classic": dict(n=5),
    "sample_classic_hemisphere": dict(n=5),
    "sample_cosine": dict(n=5),
    "sample_hemisphere": dict(n=24),
    "iter_hemisphere": dict(n_total=24, chunk=24),
    "real_sh": dict(d=_T0_POINT),
    "frame": dict(normal=[0.0, 0.0, 1.0]),
    "get_peer": dict(name="classic"),
    "integrate": dict(normal=None),
    "concentric_disk_to_square": dict(p=np.array([[0.3, 0.2]])),
    "sample_lebedev": dict(n=50),
    "lebedev_weights": dict(n=50),
    "interlace_digits": dict(x=np.array([[0.3, 0.6, 0.2, 0.9]]), factor=2),
}
# Documented to return inf (a density that diverges at a vertex of the paper's maps): finite elsewhere.
MAY_BE_INF = {"square_to_triangle_pdf", "sphere_pdf", "hemisphere_pdf"}
# Functions whose arguments are trusted (documented: "not validated"): the numba-compilable formulas.
# Their valid inputs are still checked for finite output.  frames' and wedge's scalar functions validate
# since the third reliability round (inside kernels they are the bare formulas) and are tested like the others, and below;
# so do the elementwise warps of symsphere.warps, the spherical rectangle's rectangle_frame and rectangle_point included.
TRUSTED = {"triangle_warp", "check_points", "suite", "uniform_pdf",
           "projected_triangle_setup", "projected_triangle_point", "projected_triangle_uv",
           "projected_triangle_density"}  # fmt: skip
MODULES = (symsphere, sampling, symmetry, frames, harmonics, stats, integrands, peers, quality, points_module,
           bins, integration, warps)  # fmt: skip


@pytest.fixture(autouse=True, scope="module")
def _kernels_compiled():
    # Compile (or load from the disk cache) every kernel specialisation before the deadlines apply:
    # a first float32 call may take seconds.
    for dtype in (np.float32, np.float64):
        for points in ("random", "halton"):
            symsphere.sample_sphere(48, points=points, rng=1, dtype=dtype)
            for normal in (None, [0.0, 1.0, 0.0]):
                symsphere.sample_hemisphere(24, normal=normal, points=points, rng=1, dtype=dtype)


def _public_functions():
    seen, found = set(), []
    for module in MODULES:
        for name in getattr(module, "__all__", ()):
            obj = getattr(module, name)
            if inspect.isfunction(obj) and id(obj) not in seen and name != "integrate":
                seen.add(id(obj))
                found.append((name, obj))
    found.append(("integrate", symsphere.integrate))
    return found


FUNCTIONS = _public_functions()


def _valid_arguments(name, function):
    values = {**VALID, **OVERRIDES.get(name, {})}
    arguments = {}
    for parameter in inspect.signature(function).parameters.values():
        if parameter.kind in (parameter.VAR_POSITIONAL, parameter.VAR_KEYWORD):
            continue
        if parameter.name in values:
            arguments[parameter.name] = values[parameter.name]
        elif parameter.default is parameter.empty:
            return None  # a required argument this table does not know: reported by the test below
    return arguments


def _call(function, arguments):
    parameters = inspect.signature(function).parameters
    positional = [arguments[p] for p in arguments if parameters[p].kind is parameters[p].POSITIONAL_OR_KEYWORD]
    keywords = {p: arguments[p] for p in arguments if parameters[p].kind is parameters[p].KEYWORD_ONLY}
    return function(*positional, **keywords)


def _all_finite(result, allow_inf=False):
    if isinstance(result, dict):
        return all(_all_finite(v, allow_inf) for v in result.values())
    if isinstance(result, (tuple, list)):
        return all(_all_finite(v, allow_inf) for v in result)
    if isinstance(result, (float, np.floating)):
        return not math.isnan(result) and (allow_inf or math.isfinite(result))
    if isinstance(result, np.ndarray) and result.dtype.kind in "fc":
        return not np.any(np.isnan(result)) and (allow_inf or bool(np.all(np.isfinite(result))))
    if type(result).__name__ == "SlopeFit" and result.points < 2:
        return True  # fit_slope of fewer than two points: documented NaN
    if hasattr(result, "__dataclass_fields__"):
        return all(_all_finite(getattr(result, f), allow_inf) for f in result.__dataclass_fields__
                   if f not in ("p_value", "standard_error", "confidence_interval", "statistic", "ratio_range"))  # fmt: skip
    return True


class _Opaque:
    def __repr__(self):
        return "<opaque>"


ODD = st.sampled_from([
    None, True, "x", b"x", "", 1.5, -1, 0, 2**70, -(2**70), float("nan"), float("inf"), -float("inf"), 1e308, -1e-320,
    [], [[]], {}, _Opaque(), np.float32(1.0), 1 + 1j, [1, 2], [[1, 2], [3]], np.zeros((0, 3)), np.zeros((0, 2)),
    np.full((2, 3), np.nan), np.full((2, 2), np.inf), np.array(["a", "b", "c"]), np.zeros(3, dtype=object),
    np.ones((2, 3), dtype=np.complex128), np.ones((2, 3), dtype=bool), np.ones((1, 3), dtype=np.int8),
    np.ones((1, 3), dtype=np.float16), np.ones((2, 2, 3)) * 1e200,
])  # fmt: skip
ARRAYS = hnp.arrays(
    dtype=st.sampled_from([np.float64, np.float32, np.float16, np.int64, np.uint8, np.bool_]),
    shape=hnp.array_shapes(min_dims=0, max_dims=4, min_side=0, max_side=4).map(
        lambda s: s if not s or s[-1] in (2, 3) else s + (3,)
    ),
    elements=dict(allow_nan=True, allow_infinity=True, allow_subnormal=False),
)
FLOAT_ARRAYS = st.tuples(
    hnp.arrays(
        dtype=np.float64,
        shape=hnp.array_shapes(min_dims=0, max_dims=4, min_side=0, max_side=4),
        elements=st.one_of(st.floats(-1e30, 1e30), st.sampled_from([np.nan, np.inf, -np.inf, 0.0, 1e30, -1e-30])),
    ),
    st.sampled_from([np.float64, np.float32]),
).map(lambda pair: pair[0].astype(pair[1]))


def _check_contract(name, function, arguments, replaced):
    try:
        result = _call(function, arguments)
        if inspect.isgenerator(result) or hasattr(result, "__next__"):
            result = list(result)
    except (ValueError, TypeError) as exc:
        message = str(exc)
        assert message and "\n" not in message.strip(), f"{name}: not one line: {message!r}"
        assert replaced in message or replaced == "f", (
            f"{name}({replaced}=...): the message does not name it: {message!r}"
        )
        return
    assert _all_finite(result, allow_inf=name in MAY_BE_INF), f"{name}({replaced}=...) returned NaN or inf: {result!r}"


@pytest.mark.parametrize("name, function", FUNCTIONS, ids=[name for name, _ in FUNCTIONS])
def test_valid_arguments_give_finite_output(name, function):
    arguments = _valid_arguments(name, function)
    assert arguments is not None, f"{name}: add its required arguments to VALID"
    result = _call(function, arguments)
    if inspect.isgenerator(result) or hasattr(result, "__next__"):
        result = list(result)
    assert _all_finite(result), name


@pytest.mark.parametrize(
    "name, function",
    [(n, f) for n, f in FUNCTIONS if n not in TRUSTED],
    ids=[n for n, _ in FUNCTIONS if n not in TRUSTED],
)
@given(data=st.data())
def test_one_bad_argument_gives_a_clear_error_or_finite_output(name, function, data):
    arguments = _valid_arguments(name, function)
    replaced = data.draw(st.sampled_from(sorted(arguments)), label="argument")
    arguments[replaced] = data.draw(st.one_of(ODD, ARRAYS), label="value")
    _check_contract(name, function, arguments, replaced)


DIRECTION_FUNCTIONS = [
    ("sphere_pdf", sampling.sphere_pdf, "d", ()),
    ("hemisphere_pdf", sampling.hemisphere_pdf, "d", ()),
    ("square_to_triangle_pdf", warps.square_to_triangle_pdf, "p", ()),
    ("fold", symmetry.fold, "d", None),
    ("orbit", symmetry.orbit, "p", (48, 3)),
    ("real_sh", lambda d: harmonics.real_sh(3, -2, d), "d", ()),
    ("evaluate_polynomial", lambda d: harmonics.evaluate_polynomial({(2, 1, 0): 1.0}, d), "d", ()),
    ("square_to_cosine_hemisphere_pdf", warps.square_to_cosine_hemisphere_pdf, "d", ()),
    ("uniform_sphere_to_square", warps.uniform_sphere_to_square, "d", (2,)),
    ("octahedral_sphere_to_square", warps.octahedral_sphere_to_square, "d", (2,)),
    ("square_to_cosine_wedge_pdf", warps.square_to_cosine_wedge_pdf, "d", ()),
]


@pytest.mark.parametrize("name, function, argument, tail", DIRECTION_FUNCTIONS, ids=[f[0] for f in DIRECTION_FUNCTIONS])
@given(d=FLOAT_ARRAYS)
def test_direction_functions_keep_the_batch_shape(name, function, argument, tail, d):
    # Normalise the finite, non-zero rows so that many inputs are valid; the others stay as drawn.
    if d.ndim and d.shape[-1] == 3:
        with np.errstate(all="ignore"):
            norms = np.linalg.norm(d.astype(np.float64), axis=-1, keepdims=True)
            ok = np.isfinite(norms) & (norms > 1e-30)
            d = np.where(ok, d / np.where(ok, norms, 1.0), d).astype(d.dtype)
    try:
        result = function(d)
    except (ValueError, TypeError) as exc:
        assert f"'{argument}'" in str(exc), f"{name}: {exc}"
        return
    assert _all_finite(result, allow_inf=name in MAY_BE_INF), name
    if tail is not None:
        assert result.shape == d.shape[:-1] + tail, (name, d.shape, result.shape)
        assert result.dtype in (np.float32, np.float64)


# --- the public scalar functions of frames and wedge: any numbers or arrays ----------------------------

SCALAR_FUNCTIONS = [
    ("frame_rows", frames.frame_rows, ("nx", "ny", "nz")),
    ("cosine_wedge_point", warps.cosine_wedge_point, ("u", "v")),
    ("cosine_wedge_density", warps.cosine_wedge_density, ("x", "y", "z")),
    ("cosine_wedge_uv", warps.cosine_wedge_uv, ("x", "y", "z")),
    ("uniform_sphere_point", warps.uniform_sphere_point, ("u", "v")),
    ("uniform_hemisphere_point", warps.uniform_hemisphere_point, ("u", "v")),
    ("concentric_disk_point", warps.concentric_disk_point, ("u", "v")),
    ("cosine_hemisphere_point", warps.cosine_hemisphere_point, ("u", "v")),
    ("octahedral_sphere_point", warps.octahedral_sphere_point, ("u", "v")),
]
SCALARS = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True),
    st.integers(-(2**80), 2**80),
    st.sampled_from([0.0, 1.0, -0.0, 1e-320]),
)


def _scalar_arguments(name, data):
    """Mostly valid arguments (a unit vector of W, a point of the square), sometimes replaced by anything."""
    if name.endswith("_point"):
        values = [data.draw(st.floats(0, 1), label="u"), data.draw(st.floats(0, 1), label="v")]
    else:
        phi = data.draw(st.floats(0, math.pi / 4), label="phi")
        z = data.draw(st.floats(0, 1), label="z")
        r = math.sqrt(max(0.0, 1 - z * z))
        values = [r * math.cos(phi), r * math.sin(phi), z]
    if data.draw(st.booleans(), label="replace one"):
        index = data.draw(st.integers(0, len(values) - 1), label="index")
        strategy = SCALARS if name == "frame_rows" else st.one_of(SCALARS, ODD, FLOAT_ARRAYS, ARRAYS)
        values[index] = data.draw(strategy, label="value")
    return values


@pytest.mark.parametrize("name, function, names", SCALAR_FUNCTIONS, ids=[f[0] for f in SCALAR_FUNCTIONS])
@given(data=st.data())
def test_scalar_functions_validate_like_their_array_twins(name, function, names, data):
    values = _scalar_arguments(name, data)
    try:
        result = function(*values)
    except (ValueError, TypeError) as exc:
        message = str(exc)
        assert "\n" not in message and any(f"'{n}" in message or f"{n}'" in message for n in names), (name, message)
        return
    assert _all_finite(result), (name, values, result)
    if name == "frame_rows":  # rows orthonormal to each other and to n
        basis = np.array([*result, values])
        assert np.allclose(basis @ basis.T, np.eye(3), atol=3e-3), (values, basis)
    else:
        shape = np.broadcast_shapes(*(np.shape(v) for v in values))
        if name == "cosine_wedge_density":
            assert np.shape(result) == shape and np.all(np.asarray(result) >= 0)
        else:
            assert all(np.shape(component) == shape for component in result), (name, values, result)


@given(normal=st.one_of(FLOAT_ARRAYS, ODD, ARRAYS), vectors=st.one_of(FLOAT_ARRAYS, ODD, ARRAYS))
def test_frame_and_its_maps_validate(normal, vectors):
    try:
        basis = frames.frame(normal)
    except (ValueError, TypeError) as exc:
        assert "'normal'" in str(exc), str(exc)
        basis = np.eye(3)
    else:
        assert np.allclose(basis @ basis.T, np.eye(3), atol=3e-3) and np.all(np.isfinite(basis))
    for function, name in ((frames.to_world, "'local'"), (frames.to_local, "'world'")):
        try:
            out = function(vectors, basis)
        except (ValueError, TypeError) as exc:
            assert name in str(exc), str(exc)
            continue
        assert out.shape == np.shape(vectors) and np.all(np.isfinite(out))


# --- the renderer's inputs: images and scene files --------------------------------------------------

JSON = st.recursive(
    st.none()
    | st.booleans()
    | st.integers()
    | st.floats()
    | st.text(max_size=4)
    | st.sampled_from([10**400, -(10**40)]),
    lambda children: st.lists(children, max_size=4) | st.dictionaries(st.text(max_size=4), children, max_size=4),
    max_leaves=12,
)
SCENE_PLACES = [
    ("name",), ("camera", "position"), ("camera", "look_at"), ("camera", "fov"), ("camera", "up"), ("camera", "near"),
    ("materials", "m"), ("materials", "m", "type"), ("materials", "m", "albedo"), ("materials", "m", "emission"),
    ("spheres",), ("spheres", 0, "radius"), ("spheres", 0, "center"), ("spheres", 0, "clip"),
    ("spheres", 0, "material"), ("settings",), ("settings", "max_depth"), ("settings", "epsilon"), ("extra",),
]  # fmt: skip


def _valid_scene():
    return {
        "camera": {"position": [0, 0, 4], "look_at": [0, 0, 0], "fov": 40},
        "materials": {"m": {"type": "diffuse", "albedo": 0.5, "emission": 1}},
        "spheres": [{"center": [0, 0, 0], "radius": 1, "material": "m"}],
    }


@given(place=st.sampled_from(SCENE_PLACES), value=JSON)
def test_scene_from_dict_accepts_or_names_the_field(place, value):
    from symsphere.render import SceneError, scene_from_dict

    data = _valid_scene()
    target = data
    for key in place[:-1]:
        target = target.setdefault(key, {}) if isinstance(key, str) else target[key]
    target[place[-1]] = value
    try:
        scene = scene_from_dict(data, source="fuzz.json")
    except SceneError as exc:
        message = str(exc)
        assert message.startswith("scene file 'fuzz.json': ") and "\n" not in message and len(message) < 600
        return
    arrays = scene.arrays(4, 4)  # the kernels' tables (-inf marks "no clip plane"): no NaN
    assert all(_all_finite(np.asarray(v), allow_inf=True) for v in arrays.values())


@given(image=st.one_of(ODD, ARRAYS, FLOAT_ARRAYS), exposure=st.one_of(st.just(1.0), ODD))
def test_tonemap_returns_8_bit_pixels_or_names_the_argument(image, exposure):
    from symsphere.render import tonemap

    try:
        pixels = tonemap(image, exposure)
    except (ValueError, TypeError) as exc:
        assert "'image'" in str(exc) or "'exposure'" in str(exc), str(exc)
        return
    assert pixels.dtype == np.uint8 and pixels.shape == np.shape(image)
