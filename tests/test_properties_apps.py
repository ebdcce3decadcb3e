"""Property-based tests (Hypothesis) of the error contract of symsphere.render, symsphere.distributed and
symsphere.io, and a census: every public function and class of every public module is property-tested
here or in ``tests/test_properties.py``, or listed in ``EXCLUDED`` with the reason.

The contract is that of ``tests/test_properties.py``: called with valid arguments except one, replaced
by an arbitrary value, a function returns finite output of the documented shape and dtype or raises
``ValueError``/``TypeError`` naming the replaced argument on one line; never another exception, never
a warning, within a deadline.  Functions that touch files may also raise ``OSError`` for a path the
operating system refuses (a missing directory, a directory where a file is wanted), and ``connect``
raises ``ConnectionError`` when no scheduler answers: both documented.

Cost: renders are 4 x 3 pixels with 2 samples, files go to a temporary directory (which is also the
working directory, so that a relative name lands there), and one in-process Dask ``LocalCluster``
(``processes=False``, one worker) serves the module with fewer examples per test (a quarter).
Profiles as in ``tests/test_properties.py`` (``ci`` by default; ``SYMSPHERE_HYPOTHESIS=thorough``,
``SYMSPHERE_HYPOTHESIS_EXAMPLES=N``).
"""

from __future__ import annotations

import contextlib
import dataclasses
import importlib
import inspect
import os
import pathlib
import pkgutil
from datetime import timedelta

import numpy as np
import pytest

hypothesis = pytest.importorskip("hypothesis")
from hypothesis import HealthCheck, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402
from test_properties import ARRAYS, FLOAT_ARRAYS, FUNCTIONS, ODD, _all_finite  # noqa: E402

import symsphere  # noqa: E402
from symsphere import io  # noqa: E402
from symsphere import render as rd  # noqa: E402
from symsphere.points import BLOCK  # noqa: E402

EXAMPLES = settings().max_examples
FEW = settings(max_examples=max(4, EXAMPLES // 4), deadline=timedelta(seconds=30),
               suppress_health_check=list(HealthCheck))  # fmt: skip
ALL_CHECKS = settings(suppress_health_check=list(HealthCheck))


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    """A temporary working directory for the module: relative names such as 'x' land here."""
    path = tmp_path_factory.mktemp("properties")
    previous = os.getcwd()
    os.chdir(path)
    yield path
    os.chdir(previous)


@pytest.fixture(scope="module")
def tiny():
    """A 4 x 3, 2-sample render (compiles the kernels before the deadlines apply) and its plan."""
    result = rd.render("furnace", width=4, height=3, spp=2, seed=1)
    plan = rd.plan_passes("furnace", 4, 3, 2, strategy="symmetric", points="sobol", seed=1)
    return result, plan


# Odd path-like values besides ODD's: a directory, a file in a missing directory, wrong suffixes.
PATHS = st.sampled_from(["", ".", "/", "missing/x.png", "x.txt", "x", "x.PNG", pathlib.Path("."), "\0x"])
IMAGE = np.full((3, 4, 3), 0.25)


# A Material's fields have the names of the scene files in messages (as a scene file's user reads them);
# a SceneError about scene_from_dict's data names the field of the data ("scene file 'x': missing [camera]").
ALIASES = {
    "kind": ("kind", "type"),
    "color": ("color", "albedo", "reflectance", "tint"),
    "data": ("data", "scene file"),
}


def _contract(name, call, arguments, replaced, allow=(), allow_inf=False):
    """Call; a ValueError/TypeError must name *replaced* on one line; else the result must be finite."""
    try:
        result = call(**arguments)
    except (ValueError, TypeError) as exc:
        message = str(exc)
        assert message and "\n" not in message.strip(), f"{name}: not one line: {message!r}"
        names = ALIASES.get(replaced, (replaced,))
        assert any(n in message for n in names), f"{name}({replaced}=...): the message does not name it: {message!r}"
        return None
    except allow:
        return None
    assert _all_finite(result, allow_inf), f"{name}({replaced}=...) returned NaN or inf: {result!r}"
    return result


def _draw(data, arguments, strategies=None):
    replaced = data.draw(st.sampled_from(sorted(arguments)), label="argument")
    strategy = (strategies or {}).get(replaced, st.one_of(ODD, ARRAYS))
    arguments[replaced] = data.draw(strategy, label="value")
    return replaced


# --- symsphere.render: images ---------------------------------------------------------------------


@given(c=st.one_of(ODD, ARRAYS, FLOAT_ARRAYS))
def test_linear_to_srgb_is_finite_or_names_c(c):
    try:
        out = rd.linear_to_srgb(c)
    except (ValueError, TypeError) as exc:
        assert "'c'" in str(exc), str(exc)
        return
    assert out.shape == np.shape(c) and out.dtype == np.float64 and np.all(np.isfinite(out))


def test_linear_to_srgb_rejects_nan_and_inf():
    for bad in (np.nan, np.inf, -np.inf):
        with pytest.raises(ValueError, match="'c' must be finite"):
            rd.linear_to_srgb([0.5, bad])


IMAGE_WRITERS = [
    ("save_png", rd.save_png, "x.png"),
    ("save_pfm", rd.save_pfm, "x.pfm"),
    ("save_npy", rd.save_npy, "x.npy"),
    ("save_image", rd.save_image, "x.pfm"),
]


@pytest.mark.parametrize("name, function, target", IMAGE_WRITERS, ids=[w[0] for w in IMAGE_WRITERS])
@ALL_CHECKS
@given(data=st.data())
def test_image_writers_write_or_name_the_argument(folder, name, function, target, data):
    arguments = {"path": target, "image": IMAGE}
    if "exposure" in inspect.signature(function).parameters:
        arguments["exposure"] = 1.0
    replaced = _draw(data, arguments, {"path": st.one_of(ODD, PATHS), "image": st.one_of(ODD, ARRAYS, FLOAT_ARRAYS)})
    result = _contract(name, function, arguments, replaced, allow=OSError)
    if result is not None:
        assert pathlib.Path(result).is_file()


@ALL_CHECKS
@given(data=st.data())
def test_save_image_set_writes_all_or_names_the_argument(folder, data):
    arguments = {"paths": ["s.png", "s.pfm"], "image": IMAGE, "exposure": 1.0}
    paths = st.one_of(ODD, PATHS, st.lists(st.one_of(ODD, PATHS), max_size=3), st.just(["d.npy", "./d.npy"]))
    replaced = _draw(data, arguments, {"paths": paths})
    _contract("save_image_set", rd.save_image_set, arguments, replaced, allow=OSError)
    assert not list(folder.glob(".*.tmp")), "a temporary was left behind"


@ALL_CHECKS
@given(content=st.one_of(st.binary(max_size=64), st.builds(
    lambda head, body: head + body,
    st.sampled_from([b"PF\n2 1\n-1.0\n", b"Pf\n1 1\n1.0\n", b"PF 1 1 -1 ", b"PF\n-1 2\n-1\n", b"PF\n1e9 1e9\n-1\n",
                     b"PF\n2 1\nnan\n", b"PF\n99999999999999999999 1\n-1\n", b"PF\n1 1\n0\n"]),
    st.binary(max_size=40))))  # fmt: skip
def test_load_pfm_reads_or_says_what_is_wrong(folder, content):
    path = folder / "fuzz.pfm"
    path.write_bytes(content)
    try:
        image = rd.load_pfm(path)
    except ValueError as exc:
        assert "fuzz.pfm" in str(exc) and "\n" not in str(exc), str(exc)
        return
    assert image.dtype == np.float32 and image.ndim == 3 and image.shape[2] in (1, 3)


@given(path=st.one_of(ODD, PATHS))
def test_load_pfm_and_load_scene_name_a_bad_path(folder, path):
    for function in (rd.load_pfm, rd.load_scene):
        try:
            function(path)
        except (ValueError, TypeError) as exc:
            message = str(exc)  # names the argument, or the file that is not a PFM/scene file
            assert "'path'" in message or "scene file" in message or repr(str(path)) in message, message
        except OSError:
            pass  # a missing file, a directory: the operating system's word


# --- symsphere.render: scenes and materials ---------------------------------------------------------

_CAMERA = dict(position=(0.0, 0.0, 4.0), direction=(0.0, 0.0, -1.0), fov=40.0, up=(0.0, 1.0, 0.0), near=0.0)
_SPHERE = dict(center=(0.0, 0.0, 0.0), radius=1.0, material="m", clip=None)
_QUAD = dict(corner=(-1.0, -1.0, -2.0), edge1=(2.0, 0.0, 0.0), edge2=(0.0, 2.0, 0.0), material="m")
_HALF = dict(point=(0.0, 0.0, 0.0), normal=(0.0, 1.0, 0.0))
_MATERIAL = dict(
    kind="diffuse", color=(0.5, 0.5, 0.5), transmittance=(0.0, 0.0, 0.0), ior=1.5, emission=(1.0, 1.0, 1.0)
)


def _scene(camera=None, sphere=None, quad=None, material=None, **settings_):
    return rd.Scene(
        name="fuzz",
        camera=camera or rd.Camera(**_CAMERA),
        materials={"m": material or rd.Material(**_MATERIAL)},
        spheres=(sphere or rd.Sphere(**_SPHERE),),
        quads=(quad,) if quad is not None else (),
        **settings_,
    )


def _camera(**kw):
    return _scene(camera=rd.Camera(**kw))


def _sphere(**kw):
    return _scene(sphere=rd.Sphere(**kw))


def _quad(**kw):
    return _scene(quad=rd.Quad(**kw))


def _half(**kw):
    return _scene(sphere=rd.Sphere(**{**_SPHERE, "clip": rd.HalfSpace(**kw)}))


def _material(**kw):
    return _scene(material=rd.Material(**kw))


def _scene_settings(**kw):
    return _scene(**kw)


def _factory(function):
    def call(**kw):
        material = function(**kw)
        assert isinstance(material, rd.Material)
        return _scene(material=material)

    return call


# name, function (for the census), valid arguments, call: a Scene, or a Material that must build one.
SCENE_PARTS = [
    ("Camera", rd.Camera, _CAMERA, _camera),
    ("Sphere", rd.Sphere, _SPHERE, _sphere),
    ("Quad", rd.Quad, _QUAD, _quad),
    ("HalfSpace", rd.HalfSpace, _HALF, _half),
    ("Material", rd.Material, _MATERIAL, _material),
    ("Scene", rd.Scene, dict(background=(0.0, 0.0, 0.0), epsilon=None, rr_depth=5, max_depth=64), _scene_settings),
    ("diffuse", rd.diffuse, dict(albedo=0.5, emission=0.0), _factory(rd.diffuse)),
    ("translucent", rd.translucent, dict(reflectance=0.3, transmittance=0.3, emission=0.0), _factory(rd.translucent)),
    ("mirror", rd.mirror, dict(reflectance=0.9), _factory(rd.mirror)),
    ("dielectric", rd.dielectric, dict(ior=1.5, tint=1.0), _factory(rd.dielectric)),
    ("furnace", rd.furnace, dict(albedo=0.5, emission=1.0, translucent=False), rd.furnace),
    ("get_scene", rd.get_scene, dict(scene="cornell"), rd.get_scene),
    ("scene_from_dict", rd.scene_from_dict, dict(
        data={"camera": {"position": [0, 0, 4], "look_at": [0, 0, 0], "fov": 40},
              "materials": {"m": {"type": "diffuse", "albedo": 0.5}},
              "spheres": [{"center": [0, 0, 0], "radius": 1, "material": "m"}]},
        source="fuzz.json", default_name="scene"), rd.scene_from_dict),
]  # fmt: skip


@pytest.mark.parametrize("name, function, valid, call", SCENE_PARTS, ids=[p[0] for p in SCENE_PARTS])
@given(data=st.data())
def test_scene_parts_build_a_finite_scene_or_name_the_field(name, function, valid, call, data):
    arguments = dict(valid)
    replaced = _draw(data, arguments, {"scene": st.one_of(ODD, PATHS)})
    try:
        scene = _contract(name, call, arguments, replaced, allow=OSError if name == "get_scene" else ())
    except AssertionError:
        raise
    if scene is not None:
        arrays = scene.arrays(4, 3)  # the kernels' tables (-inf marks "no clip plane"): no NaN
        assert all(_all_finite(np.asarray(v), allow_inf=True) for v in arrays.values()), name


@pytest.mark.parametrize("function", [rd.cornell, rd.translucent_scene, rd.furnace], ids=lambda f: f.__name__)
def test_builtin_scenes_are_finite(function):
    arrays = function().arrays(8, 6)
    assert all(_all_finite(np.asarray(v), allow_inf=True) for v in arrays.values())


# --- symsphere.render: rendering ----------------------------------------------------------------------

RENDER = dict(scene="furnace", width=4, height=3, spp=2, strategy="symmetric", points="sobol", method=None,
              pixel_filter="box", seed=1, threads=1, progress=False, integrator="path")  # fmt: skip


@ALL_CHECKS
@given(data=st.data())
def test_render_gives_a_finite_image_or_names_the_argument(folder, tiny, data):
    arguments = dict(RENDER)
    replaced = _draw(data, arguments, {"scene": st.one_of(ODD, PATHS)})
    result = _contract("render", rd.render, arguments, replaced, allow=OSError)
    if result is not None:
        assert result.image.shape == (result.height, result.width, 3) and result.image.dtype == np.float64


@ALL_CHECKS
@given(data=st.data())
def test_plan_and_render_passes_name_the_argument(folder, tiny, data):
    _, plan = tiny
    plan_arguments = {k: v for k, v in RENDER.items() if k not in ("threads", "progress")}
    replaced = _draw(data, plan_arguments, {"scene": st.one_of(ODD, PATHS)})
    # a plan holds the kernels' scene tables, where -inf marks "no clip plane": NaN is still an error
    _contract("plan_passes", rd.plan_passes, plan_arguments, replaced, allow=OSError, allow_inf=True)
    arguments = dict(plan=plan, first_pass=0, stop_pass=1)
    replaced = _draw(data, arguments)
    images = _contract("render_passes", rd.render_passes, arguments, replaced)
    if images is not None:
        assert all(image.shape == (3, 4, 3) for image in images)


@ALL_CHECKS
@given(data=st.data())
def test_write_outputs_writes_the_set_or_names_the_argument(folder, tiny, data):
    result, _ = tiny
    arguments = dict(result=result, out="w.png", exposure=1.0)
    replaced = _draw(data, arguments, {"out": st.one_of(ODD, PATHS)})
    _contract("write_outputs", rd.write_outputs, arguments, replaced, allow=OSError)
    assert not list(folder.glob(".*.tmp")), "a temporary was left behind"


# --- symsphere.io -------------------------------------------------------------------------------------


def _enter(manager):
    def call(**kw):
        with manager(**kw) as temporary:
            if isinstance(temporary, list):
                for t in temporary:
                    t.write_text("x")
            elif temporary.is_dir():
                (temporary / "f").write_text("x")
            else:
                temporary.write_text("x")
        return None

    return call


def _blocks(out):
    return [symsphere.sample_sphere(48, rng=1)]


IO_FUNCTIONS = [
    ("atomic_path", io.atomic_path, dict(path="a.txt"), _enter(io.atomic_path)),
    ("atomic_paths", io.atomic_paths, dict(paths=["a.txt", "b.txt"]), _enter(io.atomic_paths)),
    ("atomic_directory", io.atomic_directory, dict(path="adir", replaceable={"f"}), _enter(io.atomic_directory)),
    ("check_suffix", io.check_suffix, dict(path="d.npy", name="path"), io.check_suffix),
    ("save_directions", io.save_directions, dict(path="d.npy", directions=symsphere.sample_sphere(48, rng=1),
                                                 name="path"), io.save_directions),
    ("stream_directions", io.stream_directions, dict(path="e.csv", n=48, dtype=np.float32, blocks=_blocks, name="path",
                                                     progress=None), io.stream_directions),
    ("remove_stale_temporaries", io.remove_stale_temporaries, dict(path="a.txt"), io.remove_stale_temporaries),
]  # fmt: skip


@pytest.mark.parametrize("name, function, valid, call", IO_FUNCTIONS, ids=[f[0] for f in IO_FUNCTIONS])
@ALL_CHECKS
@given(data=st.data())
def test_io_writes_or_names_the_argument(folder, name, function, valid, call, data):
    arguments = dict(valid)
    paths = st.one_of(ODD, PATHS)
    replaced = _draw(data, arguments, {"path": paths, "paths": st.one_of(paths, st.lists(paths, max_size=3)),
                                       "blocks": st.one_of(ODD, st.sampled_from(_BAD_BLOCKS))})  # fmt: skip
    _contract(name, call, arguments, replaced, allow=OSError)
    assert not list(folder.glob(".*.tmp")), "a temporary was left behind"


_BAD_BLOCKS = [
    lambda out: [np.zeros((47, 3))],  # too few
    lambda out: [np.zeros((48, 3))] * 2,  # too many
    lambda out: [np.zeros((48, 2))],  # wrong shape
    lambda out: [np.zeros((48, 3))],  # zero rows: not directions
    lambda out: [np.full((48, 3), np.nan)],
    lambda out: 5,  # not iterable
    lambda out: [None],
]


# --- symsphere.distributed ------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def client():
    pytest.importorskip("distributed")
    from distributed import Client, LocalCluster

    cluster = LocalCluster(n_workers=1, threads_per_worker=1, processes=False, dashboard_address=":0")
    dask_client = Client(cluster)
    yield dask_client
    dask_client.close()
    cluster.close()


def _computed(function):
    def call(**kw):
        array = function(**kw)
        computed = array.compute(scheduler="sync")
        assert computed.shape == array.shape == (kw["n"], 3) and computed.dtype == array.dtype
        return computed

    return call


# A client replaced by None would start a process cluster per example: the valid case of
# tests/test_distributed.py covers None.  Valid timeouts above a second and valid worker counts are
# left out for the same reason (a wait, a cluster per example).
NOT_NONE = st.one_of(ODD, ARRAYS).filter(lambda v: v is not None)


def _distributed_cases(client):
    from symsphere import distributed as dist

    return {
        "sample_sphere": (dict(n=48, chunks=48 * BLOCK, method="equal_area", points="random", rng=1,
                               dtype=np.float64), _computed(dist.sample_sphere)),
        "sample_hemisphere": (dict(n=24, chunks=24 * BLOCK, normal=[0.0, 1.0, 0.0], method="equal_area",
                                   points="halton", rng=1, dtype=np.float32), _computed(dist.sample_hemisphere)),
        "integrate": (dict(f=lambda d: d[:, 2] ** 2, client=client, chunk_blocks=1, progress=False, n=48, rng=1,
                           domain="sphere", replicates=None), dist.integrate),
        "render": (dict(scene="furnace", client=client, passes_per_task=1, progress=False, width=4, height=3,
                        spp=2, seed=1), dist.render),
        "connect": (dict(address="tcp://127.0.0.1:1", timeout=0.2), dist.connect),
        "local_client": (dict(workers=0), dist.local_client),
        "close_client": (dict(client=5), dist.close_client),
    }  # fmt: skip


DISTRIBUTED = ["sample_sphere", "sample_hemisphere", "integrate", "render", "connect", "local_client", "close_client"]


def _starts_a_cluster_or_waits(name, replaced, value):
    if replaced == "client" and value is None:
        return True
    if name == "local_client" and (value is None or (isinstance(value, (int, np.integer)) and 0 < value < 2**56)):
        return True
    if name == "connect" and replaced == "timeout" and isinstance(value, (int, float, np.number)):
        return not isinstance(value, bool) and value > 1
    return False


@pytest.mark.parametrize("name", DISTRIBUTED)
@FEW
@given(data=st.data())
def test_distributed_gives_finite_output_or_names_the_argument(folder, tiny, client, name, data):
    valid, call = _distributed_cases(client)[name]
    arguments = dict(valid)
    replaced = data.draw(st.sampled_from(sorted(arguments)), label="argument")
    value = data.draw(st.one_of(ODD, ARRAYS, PATHS) if replaced == "scene" else st.one_of(ODD, ARRAYS), label="value")
    hypothesis.assume(not _starts_a_cluster_or_waits(name, replaced, value))
    arguments[replaced] = value
    _contract(name, call, arguments, replaced, allow=(ConnectionError, OSError) if name == "connect" else
              OSError if replaced == "scene" else ())  # fmt: skip


def test_distributed_valid_arguments_give_the_local_result(client):
    from distributed import Client

    from symsphere import distributed as dist

    cases = _distributed_cases(client)
    for name in ("sample_sphere", "sample_hemisphere"):
        arguments, call = cases[name]
        local = getattr(symsphere, name)(**{k: v for k, v in arguments.items() if k != "chunks"})
        assert np.array_equal(call(**arguments), local), name
    arguments, call = cases["integrate"]
    local = symsphere.integrate(
        **{k: v for k, v in arguments.items() if k not in ("client", "chunk_blocks", "progress")}
    )
    result = call(**arguments)
    assert np.array_equal(result.integral, local.integral) and np.array_equal(
        result.standard_error, local.standard_error, equal_nan=True
    )
    arguments, call = cases["render"]
    image = call(**arguments).image
    assert image.shape == (3, 4, 3) and np.all(np.isfinite(image))
    with pytest.raises(ConnectionError, match="127.0.0.1:1"):
        dist.connect("tcp://127.0.0.1:1", timeout=0.2)
    own = Client(client.cluster.scheduler_address, timeout=10)  # a second client of the same cluster
    dist.close_client(own)
    assert own.status == "closed" and client.status == "running"


# --- the census ------------------------------------------------------------------------------------------

# Public names that are not property-tested, and why.  A new public function or class must be added to a
# property test or here.
EXCLUDED = {
    # records the library returns; users read them, they do not build them
    "symsphere.IntegrationResult": "a result record (integrate returns it)",
    "symsphere.stats.Chi2Result": "a result record (chi2_test returns it)",
    "symsphere.quality.SlopeFit": "a result record (fit_slope returns it)",
    "symsphere.peers.Peer": "a registry record (PEERS, get_peer)",
    "symsphere.warps.Warp": "a registry record (WARPS, get_warp, triangle_warp)",
    "symsphere.integrands.Integrand": "a registry record (INTEGRANDS, suite)",
    "symsphere.points.BasePoints": "a point source the samplers build from 'points' (tested through them)",
    "symsphere.render.RenderResult": "a result record (render returns it; write_outputs is tested with one)",
    "symsphere.render.RenderSettings": "the settings record that RenderPlan and RenderResult share (test_renderer)",
    "symsphere.render.RenderPlan": "built by plan_passes (tested); render_passes gets one",
    "symsphere.render.SceneError": "the exception type itself",
    "symsphere.Scheme": "the engine behind sample_sphere/sample_hemisphere/iter_* (property-tested through them: "
    "each is one call on a fresh Scheme); its own bad arguments and methods in tests/test_sampling.py",
}
# Whole modules left out: the applications.  Their contract (one line on stderr, exit status 2 for bad
# arguments, never a traceback) is tested through symsphere.apps.cli.main in tests/apps/ (hostile scene
# files, --timeout nan, --exposure inf, signals, full disks in test_cli.py; every verb's bad options);
# their internals run only with arguments the applications build.
EXCLUDED_MODULES = {
    "symsphere.apps": "the applications: tested through the command line (tests/apps/)",
    "symsphere.mitsuba": "Dr.Jit functions of Mitsuba's array types, not numpy inputs: tested in tests/mitsuba (values "
    "against numpy, chi-square, parameter errors)",
}


def _excluded_module(name):
    return any(name == m or name.startswith(m + ".") for m in EXCLUDED_MODULES)


def _tested_objects():
    tested = [f for _, f in FUNCTIONS] + [rd.tonemap, rd.linear_to_srgb, rd.load_pfm, rd.load_scene]
    tested += [f for _, f, _ in IMAGE_WRITERS] + [rd.save_image_set, rd.render, rd.plan_passes, rd.render_passes]
    tested += [rd.write_outputs, rd.cornell, rd.translucent_scene] + [p[1] for p in SCENE_PARTS]
    tested += [f[1] for f in IO_FUNCTIONS]
    with contextlib.suppress(ImportError):
        from symsphere import distributed as dist

        tested += [getattr(dist, name) for name in DISTRIBUTED]
    return {id(obj) for obj in tested}


def _public_callables():
    """(qualified name, object) of every function and class in the __all__ of every public module."""
    names = ["symsphere"] + [
        info.name for info in pkgutil.walk_packages(symsphere.__path__, "symsphere.")
        if not any(part.startswith("_") for part in info.name.split("."))
    ]  # fmt: skip
    found, seen = [], set()
    for module_name in names:
        module = importlib.import_module(module_name)
        for name in getattr(module, "__all__", ()):
            obj = getattr(module, name)
            if (inspect.isfunction(obj) or inspect.isclass(obj)) and id(obj) not in seen:
                seen.add(id(obj))
                found.append((f"{obj.__module__}.{obj.__qualname__}", f"{module_name}.{name}", obj))
    return found


def test_every_public_function_is_property_tested_or_excluded():
    tested = _tested_objects()
    missing = [shown for _, shown, obj in _public_callables()
               if id(obj) not in tested and shown not in EXCLUDED and not _excluded_module(shown)]  # fmt: skip
    assert not missing, f"not property-tested and not in EXCLUDED (say why): {missing}"
    stale = [name for name in EXCLUDED if name not in {s for _, s, _ in _public_callables()}]
    assert not stale, f"EXCLUDED names what is no longer public: {stale}"


def test_the_census_counts_what_docs_reliability_states():
    counted = [shown for _, shown, obj in _public_callables() if id(obj) in _tested_objects()]
    assert len(counted) >= 100, len(counted)


def test_dataclass_records_are_excluded_only_if_they_are_records():
    for name in EXCLUDED:
        module_name, _, attr = name.rpartition(".")
        obj = getattr(importlib.import_module(module_name), attr)
        assert inspect.isfunction(obj) or inspect.isclass(obj), name
        if inspect.isclass(obj) and not issubclass(obj, BaseException) and name.startswith("symsphere.render"):
            assert dataclasses.is_dataclass(obj), name
