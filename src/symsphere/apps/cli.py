"""The ``symsphere`` command: sample directions to a file, or run the demo.

Examples
--------
::

    symsphere sample --n 4800 --seed 1 --out directions.npy
    symsphere sample --n 4800 --domain hemisphere --normal 0 1 0 --out hemi.csv
    symsphere demo --out symsphere-demo
    symsphere render --scene cornell --width 256 --height 192 --spp 96 --sampler symmetric_sobol --out img.png
    symsphere --version

Exit status: 0 on success, 2 for invalid arguments (the message names the
argument), 1 when the output cannot be written, 130 on Ctrl-C (SIGINT), 143 on
SIGTERM (``kill``, ``timeout``, batch schedulers, containers) and 129 on SIGHUP.
Every error is one line on stderr, never a traceback (set the environment
variable ``SYMSPHERE_TRACEBACK=1`` to see one for an unexpected error).  No
partial output file is ever left behind: the files of a run appear together,
complete, or not at all.  A signal that arrives before the output files are
renamed into place rolls them back (exit 130/143/129, nothing written); one that
arrives once the renames have begun lets the command finish: the files are
complete, it exits 0 and says so on stderr.  Outputs must be regular files (or
new names): a device, a FIFO or a directory at ``--out`` is refused before any
work.  Work estimated to take more than a day is refused unless ``--allow-long``.
"""

from __future__ import annotations

import argparse
import contextlib
import math
import os
import signal
import sys
import threading
import time
import warnings
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from types import FrameType
from typing import Any, NoReturn, cast

import numpy as np

from .. import IntegrationResult, __version__, integrate, iter_hemisphere, iter_sphere
from .._typing import FloatArray
from .._validation import (
    MAX_PATHS,
    MAX_PIXELS,
    check_count,
    check_nonnegative,
    check_output_path,
    check_rtol,
    check_seed,
    check_size,
    file_kind,
)
from ..integrands import INTEGRANDS, Integrand
from ..io import DIRECTION_SUFFIXES, check_suffix, stream_directions
from ..points import BLOCK, POINT_SETS
from ..warps import METHODS
from ._notices import compile_notice
from .demo import run_demo
from .study import add_study_parser

__all__ = ["main", "build_parser"]

_DOMAINS = ("sphere", "hemisphere")
_DTYPES = ("float64", "float32")
_DEMO_DEFAULT_N = 48 * 2**14
_DISTRIBUTED_EXTRA = "symsphere[distributed]"
_Blocks = Callable[["FloatArray | None"], Iterator["FloatArray"]]  # stream_directions' blocks(out)


class _UsageError(Exception):
    """An invalid combination of arguments that argparse cannot express."""


class _Terminated(KeyboardInterrupt):
    """SIGTERM or SIGHUP, raised in the main thread like Ctrl-C, so that the same clean-up runs."""

    def __init__(self, signum: int) -> None:
        super().__init__(signum)
        self.signum = signum


_CLEAN_EXIT_SIGNALS = tuple(getattr(signal, name) for name in ("SIGTERM", "SIGHUP") if hasattr(signal, name))


def _raise_terminated(signum: int, frame: FrameType | None) -> NoReturn:
    if signum == signal.SIGINT:
        raise KeyboardInterrupt
    raise _Terminated(signum)


class _Outputs:
    """The files (or directory) a verb writes, and whether they are in place: a late signal then ends in success."""

    def __init__(self) -> None:
        self.paths: list[Path] = []
        self.before: list[tuple[int, int] | None] = []
        self.done = False

    def watch(self, paths: Sequence[str | os.PathLike[str]]) -> None:
        """Call just before the write: remember what is at *paths* now (followed through symbolic links)."""
        self.paths = [Path(p) for p in paths]
        self.before = [_identity(p) for p in self.paths]

    def complete(self) -> bool:
        """Whether the write has put every file in place (each name now points at a new file)."""
        if self.done:
            return True
        after = [_identity(p) for p in self.paths]
        return bool(self.paths) and all(a is not None and a != b for a, b in zip(after, self.before, strict=False))


def _identity(path: Path) -> tuple[int, int] | None:
    try:
        info = os.stat(path)
    except OSError:
        return None
    return info.st_dev, info.st_ino


_LONG_SECONDS = 86400.0  # work estimated beyond a day needs --allow-long
_FASTEST_DIRECTIONS_PER_SECOND = 1e9  # sample: 40x the 2.3e7/s measured to a file (docs/results/reliability.md)
_FASTEST_EVALUATIONS_PER_SECOND = 1e9  # integrate: 17x the 59 M/s measured (docs/results/bench-integrate.md); a pilot
_FASTEST_PATHS_PER_THREAD = 1e7  # render: 4x the best 2.5 Mpaths/s per thread (docs/results/render-performance.md)


def _check_duration(seconds: float, what: str, args: argparse.Namespace) -> None:
    """Refuse work estimated beyond a day unless --allow-long was given (a usage error, before any work)."""
    if seconds > _LONG_SECONDS and not args.allow_long:
        raise _UsageError(
            f"{what} is estimated to take at least {_duration(seconds)}; add --allow-long to run it anyway"
        )


def _add_allow_long(verb: argparse.ArgumentParser) -> None:
    verb.add_argument(
        "--allow-long", action="store_true",
        help="run even if the work is estimated to take more than a day (refused otherwise, before any work)",
    )  # fmt: skip


@contextlib.contextmanager
def _signals_as_interrupts(pending: list[int]) -> Iterator[None]:
    """While the command runs, SIGINT raises KeyboardInterrupt and SIGTERM, SIGHUP _Terminated (the main
    thread only: signal's rule), and every signal is also recorded in *pending*.

    Python runs a handler at any bytecode, also inside a callback from C (numba's compiler calls back into
    Python through ctypes), where the exception is printed as "Exception ignored" and dropped: the run went
    on and exited 0 with a traceback.  Such a lost interrupt stays in *pending*; :func:`_check_pending` raises
    it again at the next safe point (each block written, the end of a render), and the unraisable-exception
    hook stays quiet about it.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def handler(signum: int, frame: FrameType | None) -> None:
        pending.append(signum)
        _raise_terminated(signum, frame)

    def unraisable(report: sys.UnraisableHookArgs, previous_hook: Callable[..., object] = sys.unraisablehook) -> None:
        if not (isinstance(report.exc_type, type) and issubclass(report.exc_type, KeyboardInterrupt)):
            previous_hook(report)

    previous = {signum: signal.signal(signum, handler) for signum in (signal.SIGINT, *_CLEAN_EXIT_SIGNALS)}
    previous_hook, sys.unraisablehook = sys.unraisablehook, unraisable
    try:
        yield
    finally:
        sys.unraisablehook = previous_hook
        for signum, old in previous.items():
            signal.signal(signum, old)


def _check_pending(args: argparse.Namespace) -> None:
    """Raise a signal that arrived but whose exception was lost (see _signals_as_interrupts)."""
    if args.pending:
        _raise_terminated(args.pending[0], None)


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``symsphere`` command (one sub-parser per verb).

    Returns
    -------
    argparse.ArgumentParser
        Verbs ``sample``, ``integrate``, ``study``, ``render`` and ``demo``; the parsed
        namespace has the verb in ``verb`` and its function in ``handler`` (what :func:`main`
        calls).

    Examples
    --------
    >>> from symsphere.apps.cli import build_parser
    >>> args = build_parser().parse_args(["sample", "--n", "4800", "--out", "d.npy"])
    >>> args.verb, args.n, args.domain, args.method, args.points, args.seed
    ('sample', 4800, 'sphere', 'equal_area', 'random', None)
    >>> build_parser().parse_args(["integrate", "--integrand", "exp", "--n", "480", "--workers", "2"]).workers
    2
    """
    parser = argparse.ArgumentParser(
        prog="symsphere",
        description="Exactly uniform, 48-fold symmetric sampling of the sphere and hemisphere.",
        epilog="'symsphere VERB --help' lists each verb's options and their choices.",
    )
    parser.add_argument("--version", action="version", version=f"symsphere {__version__}")
    verbs = parser.add_subparsers(dest="verb", metavar="{sample,integrate,study,render,demo}")

    sample = verbs.add_parser(
        "sample",
        help="write N directions to a .npy or .csv file",
        description=(
            "Write N unit directions, one per row (x, y, z), drawn by the 48-fold (hemisphere: "
            "24-fold) symmetric scheme.  Rows 48i..48i+47 (24i..24i+23) are the orbit of one "
            "point of the fundamental triangle.  The file appears only when complete."
        ),
    )
    sample.add_argument(
        "--n", type=int, required=True,
        help="number of directions: a multiple of 48 (hemisphere: 24); symsphere.sample_sphere takes any n",
    )  # fmt: skip
    sample.add_argument("--domain", choices=_DOMAINS, default="sphere", help="default: %(default)s")
    sample.add_argument(
        "--method",
        choices=METHODS,
        default="equal_area",
        help="map from the unit square onto the triangle; only equal_area is uniform (default: %(default)s)",
    )
    sample.add_argument(
        "--points",
        choices=POINT_SETS,
        default="random",
        help="base points of the unit square (stratified needs N/48 to be a square; default: %(default)s)",
    )
    sample.add_argument("--seed", type=int, default=None, help="non-negative integer; default: fresh entropy")
    sample.add_argument(
        "--out",
        required=True,
        metavar="FILE",
        help=f"output file; its suffix chooses the format: {', '.join(DIRECTION_SUFFIXES)}",
    )
    sample.add_argument(
        "--normal",
        type=float,
        nargs=3,
        metavar=("X", "Y", "Z"),
        default=None,
        help="pole of the hemisphere (only with --domain hemisphere; default: 0 0 1)",
    )
    sample.add_argument("--dtype", choices=_DTYPES, default="float64", help="default: %(default)s")
    sample.add_argument(
        "--chunk",
        type=int,
        default=None,
        help="directions generated and written at a time, a multiple of 48 (hemisphere: 24); "
        "memory stays at one chunk for any N (default: 48 * 2**16)",
    )
    _add_allow_long(sample)
    _add_cluster_options(sample)
    sample.set_defaults(handler=_run_sample)

    integrate = verbs.add_parser(
        "integrate",
        help="integrate a closed-form test integrand, with an error bar",
        description=(
            "Integrate one of the closed-form test integrands of symsphere.integrands over its domain "
            "(sphere or hemisphere) with the symmetric scheme, and print the estimate, its standard "
            "error and confidence interval, and the exact value.  With --workers or --scheduler the "
            "work runs on a Dask cluster and gives the identical result."
        ),
    )
    integrate.add_argument(
        "--integrand", required=True, metavar="NAME",
        help=f"one of: {', '.join(sorted(INTEGRANDS))} (symsphere.integrands.INTEGRANDS; docs/reference/integrands.md)",
    )  # fmt: skip
    integrate.add_argument(
        "--n",
        type=int,
        default=None,
        help="evaluations: a multiple of 48 (hemisphere: 24); with --rtol/--atol the first stage's (optional)",
    )
    integrate.add_argument(
        "--method", choices=(*METHODS, "auto", "fibonacci", "lebedev"), default="equal_area",
        help="map onto the triangle (every map unbiased), or rotated-rule families; auto: a pilot picks (default: %(default)s)",
    )  # fmt: skip
    integrate.add_argument("--points", choices=POINT_SETS, help="default: random (auto: sobol_interlaced3)")
    integrate.add_argument(
        "--replicates", type=int, default=None,
        help="independent randomisations of stratified and QMC points; the error bar needs 2 or more (default 8)",
    )  # fmt: skip
    integrate.add_argument("--seed", type=int, default=None, help="non-negative integer; default: fresh entropy")
    integrate.add_argument("--rtol", type=float, default=None, help="relative tolerance: double n until it is met")
    integrate.add_argument("--atol", type=float, default=None, help="absolute tolerance: double n until it is met")
    integrate.add_argument(
        "--n-max", type=int, default=None, help="with --rtol/--atol: the largest n (default 48 * 2**24)"
    )
    _add_allow_long(integrate)
    _add_cluster_options(integrate)
    integrate.set_defaults(handler=_run_integrate)

    demo = verbs.add_parser(
        "demo",
        help="chi-square tests of the three maps, written up as report.md, figure.png and render.png",
        description=(
            f"Sample the sphere and the hemisphere with every map ({', '.join(METHODS)}), run chi-square "
            "tests against the uniform density (and the paper's maps against their own density), render "
            "a small Cornell box with the symmetric scheme, and write report.md, figure.png and render.png "
            "into DIR.  An existing DIR is replaced only if it holds nothing but an earlier demo's output."
        ),
    )
    demo.add_argument("--out", default="symsphere-demo", metavar="DIR", help="output directory (default: %(default)s)")
    demo.add_argument(
        "--n",
        type=int,
        default=_DEMO_DEFAULT_N,
        help="directions per sample, a multiple of 48; 4800 runs in seconds (default: %(default)s)",
    )
    demo.add_argument("--seed", type=int, default=0, help="default: %(default)s")
    demo.add_argument("--no-progress", action="store_true", help="do not show a progress bar")
    demo.set_defaults(handler=_run_demo)

    render = verbs.add_parser(
        "render",
        help="path-trace a scene with a chosen direction sampler; write PNG, PFM and NPY",
        description=(
            "Path-trace a built-in scene (cornell: smallpt's Cornell box; furnace; translucent) or a "
            ".toml/.json scene file, sampling directions at diffuse vertices with SAMPLER, on all cores.  "
            "Writes the tone-mapped sRGB image to --out (.png) and the linear HDR mean radiance next to "
            "it (.pfm and .npy, same stem).  Every file appears only when complete."
        ),
    )
    render.add_argument("--scene", default="cornell", help="cornell, furnace, translucent, a .toml/.json file, or a "
                        "Mitsuba 3 .xml file (rendered with symsphere_path; needs the extra 'mitsuba'); "
                        "furnace prints its mean radiance against the exact value (default: %(default)s)")  # fmt: skip
    render.add_argument("--width", type=int, default=256, help="default: %(default)s")
    render.add_argument("--height", type=int, default=192, help="default: %(default)s")
    render.add_argument(
        "--spp", type=int, default=96,
        help="samples (camera paths) per pixel; symmetric samplers form whole orbits for multiples of 24 "
        "(48 with translucent materials) (default: %(default)s)",
    )  # fmt: skip
    render.add_argument(
        "--sampler", choices=_render_samplers(), default="symmetric_sobol",
        help="direction sampling at diffuse vertices: the paper's scheme inside a pixel (symmetric, with "
        "random or Owen-scrambled Sobol' base points), i.i.d. orbit samplers per map, or the classic uniform "
        "and cosine references (default: %(default)s)",
    )  # fmt: skip
    render.add_argument(
        "--integrator", choices=("path", "bsdf"), default="path",
        help="path: next-event estimation and BSDF sampling combined by multiple importance sampling; "
        "bsdf: BSDF sampling only, smallpt's estimator (default: %(default)s)",
    )  # fmt: skip
    render.add_argument(
        "--method", choices=METHODS, default=None,
        help="map onto the triangle for the symmetric samplers (default: equal_area)",
    )  # fmt: skip
    render.add_argument("--filter", choices=("box", "tent"), default="box", help="pixel filter (default: %(default)s)")
    render.add_argument("--seed", type=int, default=None, help="non-negative integer; default: fresh entropy")
    render.add_argument(
        "--exposure", type=float, default=None,
        help="PNG only: scale before tone mapping (default: 1; furnace: 0.5 / exact radiance, a mid-grey)",
    )  # fmt: skip
    render.add_argument("--threads", type=int, default=None, help="numba threads (default: all cores)")
    render.add_argument("--out", default="render.png", metavar="FILE.png", help="default: %(default)s")
    render.add_argument("--no-progress", action="store_true", help="do not show a progress bar")
    _add_allow_long(render)
    _add_cluster_options(render)
    render.set_defaults(handler=_run_render)

    add_study_parser(verbs)
    return parser


def _render_samplers() -> tuple[str, ...]:
    # Function-level: symsphere.render takes ~0.3 s to import; the renderer module alone gives the tuple
    # without loading the kernels.
    from ..render.renderer import SAMPLERS

    return SAMPLERS + ("bsdf",)  # bsdf: Mitsuba's own sampling, for Mitsuba scene files (apps.mitsuba_render)


def _add_cluster_options(verb: argparse.ArgumentParser) -> None:
    cluster = verb.add_mutually_exclusive_group()
    cluster.add_argument(
        "--workers", type=int, default=None, metavar="N",
        help=f"run on a local Dask cluster of N worker processes (needs {_DISTRIBUTED_EXTRA})",
    )  # fmt: skip
    cluster.add_argument(
        "--scheduler", default=None, metavar="ADDRESS",
        help=f"run on the Dask cluster at ADDRESS (tcp://host:8786; needs {_DISTRIBUTED_EXTRA})",
    )  # fmt: skip
    verb.add_argument(
        "--timeout", type=float, default=10.0, help="seconds to wait for the scheduler (default: %(default)s)"
    )


def _cluster_client(args: argparse.Namespace) -> Any:  # a dask.distributed Client, or None
    """A Dask client for --workers / --scheduler, or None to run in this process."""
    if args.workers is None and args.scheduler is None:
        return None
    if not (math.isfinite(args.timeout) and args.timeout > 0):
        raise _UsageError(f"--timeout must be a positive number of seconds, got {args.timeout}")
    option = "--workers" if args.scheduler is None else "--scheduler"
    try:  # the optional extra: say so, not with a traceback from deep inside symsphere.distributed
        import importlib

        for name in ("dask", "distributed"):
            importlib.import_module(name)  # function-level: dask is slow to import and optional
    except ModuleNotFoundError:
        raise _UsageError(
            f"{option} needs Dask, which is not installed; install it with: pip install '{_DISTRIBUTED_EXTRA}'"
        ) from None
    distributed = _distributed()
    if args.scheduler is not None:
        return distributed.connect(args.scheduler, timeout=args.timeout)
    if args.workers < 1:
        raise _UsageError(f"--workers must be a positive integer, got {args.workers}")
    return distributed.local_client(args.workers)


def _close_client(client: Any) -> None:
    if client is not None:
        _distributed().close_client(client)


def _distributed() -> Any:  # Any while symsphere.distributed is not annotated (its mypy override)
    from .. import distributed  # function-level: dask is slow to import and optional

    return distributed


def main(argv: Sequence[str] | None = None) -> int:
    """Run the ``symsphere`` command with *argv* (default ``sys.argv[1:]``); return the exit status.

    Parameters
    ----------
    argv : sequence of str, optional
        The arguments after the program name (see the module docstring and ``symsphere --help``).

    Returns
    -------
    int
        0 on success, 2 for invalid arguments (the message on stderr names the argument), 1 when
        the output cannot be written, 130 on Ctrl-C, 143 on SIGTERM (129 on SIGHUP), in each case
        with one line on stderr and no output file.  Errors are reported, not raised.

    Examples
    --------
    >>> import os, tempfile
    >>> import numpy as np
    >>> from symsphere.apps.cli import main
    >>> path = os.path.join(tempfile.mkdtemp(), "directions.npy")
    >>> main(["sample", "--n", "48", "--seed", "1", "--out", path])
    wrote 48 directions (sphere, equal_area, random, seed 1, float64) to ... in ... s
    0
    >>> np.load(path).shape
    (48, 3)
    >>> main(["sample", "--n", "50", "--out", path])        # not a multiple of 48: exit status 2
    2
    """
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # --help, --version and usage errors: hand back argparse's status
        return exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 2)
    if args.verb is None:
        parser.print_help(sys.stderr)
        return 2
    prog = f"symsphere {args.verb}"
    args.outputs = _Outputs()
    args.pending = []
    try:
        with _signals_as_interrupts(args.pending), compile_notice(prog):
            status = _with_notes(args.handler, args, prog)
            if not args.outputs.complete():  # an interrupt lost inside a C callback: not a success
                _check_pending(args)
        if argv is None and status == 0 and args.outputs.paths:  # the program is about to exit: a signal
            _ignore_signals()  # now must not turn a written output into a death by signal
        return status
    except KeyboardInterrupt as exc:
        name = signal.Signals(getattr(exc, "signum", signal.SIGINT)).name
        if argv is None:  # the program is about to exit: no second signal may turn this into a death by signal
            _ignore_signals()
        if args.outputs.complete():  # the renames had begun: the output is whole, and it stays
            shown = ", ".join(str(p) for p in args.outputs.paths)
            print(f"{prog}: {name} arrived after the output was complete; kept {shown}", file=sys.stderr)
            return 0
        if isinstance(exc, _Terminated):
            print(f"{prog}: terminated ({name}); nothing was written", file=sys.stderr)
            return _exit_now(128 + exc.signum, argv)
        print(f"{prog}: interrupted; nothing was written", file=sys.stderr)
        return _exit_now(130, argv)
    except (_UsageError, ValueError, TypeError) as exc:
        # The library's validators name the argument; a traceback would add nothing.
        print(f"{prog}: error: {_one_line(exc)}", file=sys.stderr)
        return 2
    except OSError as exc:
        print(f"{prog}: error: {_one_line(_describe_os_error(exc))}", file=sys.stderr)
        return 1
    except MemoryError as exc:
        print(f"{prog}: error: out of memory{': ' + _one_line(exc) if str(exc) else ''}", file=sys.stderr)
        return 1
    except Exception as exc:  # a bug, or a library below failing in a new way: still one line
        if os.environ.get("SYMSPHERE_TRACEBACK"):
            raise
        print(
            f"{prog}: internal error: {type(exc).__name__}: {_one_line(exc)} "
            "(set SYMSPHERE_TRACEBACK=1 for the traceback)",
            file=sys.stderr,
        )
        return 1


def _exit_now(status: int, argv: Sequence[str] | None) -> int:
    """Run as the program (no *argv*) after an interrupt: exit with *status* now.  The interpreter's own
    exit could still die by the signal (the audit once saw exit -2 after this line was printed, an
    interrupt having been dropped inside a numba callback); everything of ours is already cleaned up."""
    if argv is None:
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(status)
    return status


def _ignore_signals() -> None:
    for signum in (signal.SIGINT, *_CLEAN_EXIT_SIGNALS):
        signal.signal(signum, signal.SIG_IGN)


def _one_line(exc: object) -> str:
    text = " ".join(str(exc).split())
    return text if len(text) <= 500 else text[:480] + " ..."


def _with_notes(handler: Callable[[argparse.Namespace], int], args: argparse.Namespace, prog: str) -> int:
    """Run a verb; a library warning (scipy's Sobol' balance note) becomes one line on stderr."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", UserWarning)
        status = handler(args)
    for message in dict.fromkeys(str(w.message) for w in caught):
        hint = _NOTE_HINTS.get(message.split(" require")[0], "")
        print(f"{prog}: note: {message}{hint}", file=sys.stderr)
    return status


_NOTE_HINTS = {
    "The balance properties of Sobol' points": " (here n is the number of base points: N/48, hemisphere N/24, "
    "and per replicate for integrate); for Sobol's best error choose N so that it is, e.g. --n 49152 = 48 * 1024",
}


def _run_sample(args: argparse.Namespace) -> int:
    from tqdm.auto import tqdm  # function-level: ~60 ms, only for the verbs that show progress

    if args.normal is not None and args.domain != "hemisphere":
        raise _UsageError("--normal is only valid with --domain hemisphere; add --domain hemisphere or drop --normal")
    check_suffix(args.out, "--out")  # before sampling, so that a typo costs nothing
    check_output_path(args.out, "--out")  # a device, a FIFO, a missing directory: refused now (OSError)
    seed = args.seed
    if seed is None:
        seed = np.random.SeedSequence().entropy  # printed below, so the run can be repeated
    start = time.perf_counter()
    seed = check_seed(seed, "--seed")
    options = dict(method=args.method, points=args.points, rng=seed, dtype=np.dtype(args.dtype))
    count = 48 if args.domain == "sphere" else 24
    check_count(args.n, "n", multiple=count)  # named as the library's sample functions name it, not n_total
    _check_duration(args.n / _FASTEST_DIRECTIONS_PER_SECOND, f"--n {args.n}", args)
    chunk = args.chunk if args.chunk is not None else count * 2**16

    def iterate(out: FloatArray | None) -> Iterator[FloatArray]:
        if args.domain == "sphere":
            return iter_sphere(args.n, chunk=chunk, out=out, **options)
        return iter_hemisphere(args.n, chunk=chunk, normal=args.normal, out=out, **options)

    iterate(None)  # validate every argument before the output file is created
    client = _cluster_client(args)
    try:
        blocks = iterate if client is None else _cluster_blocks(client, args, options, chunk)
        with tqdm(total=args.n, unit="dir", unit_scale=True, disable=None, desc="sampling", leave=False) as bar:
            args.outputs.watch([args.out])

            def progress(count: int) -> None:
                _check_pending(args)  # an interrupt lost while a kernel compiled: roll back now
                bar.update(count)

            try:
                stream_directions(args.out, args.n, args.dtype, blocks, name="--out", progress=progress)
            except OSError as exc:  # name the user's file, not the temporary next to it
                raise OSError(exc.errno, exc.strerror, args.out) from exc
            args.outputs.done = True
    finally:
        _close_client(client)
    elapsed = time.perf_counter() - start
    print(
        f"wrote {args.n} directions ({args.domain}, {args.method}, {args.points}, "
        f"seed {seed}, {args.dtype}) to {args.out} in {elapsed:.3f} s"
    )
    return 0


def _cluster_blocks(client: Any, args: argparse.Namespace, options: dict[str, Any], chunk: int) -> _Blocks:
    """blocks(out) for stream_directions: chunks computed on the cluster, in order, a few in flight."""
    distributed = _distributed()
    count = 48 if args.domain == "sphere" else 24
    chunk = max(count * BLOCK, chunk - chunk % (count * BLOCK))  # cluster chunks are whole blocks
    if args.domain == "sphere":
        array = distributed.sample_sphere(args.n, chunks=chunk, **options)
    else:
        array = distributed.sample_hemisphere(args.n, chunks=chunk, normal=args.normal, **options)
    pieces = array.to_delayed().ravel().tolist()
    in_flight = 2 * max(1, len(client.scheduler_info()["workers"]))

    def blocks(out: FloatArray | None) -> Iterator[FloatArray]:
        futures = [client.compute(piece) for piece in pieces[:in_flight]]
        for index in range(len(pieces)):
            block = futures[index].result()
            futures[index] = None  # release the finished chunk
            if index + in_flight < len(pieces):
                futures.append(client.compute(pieces[index + in_flight]))
            yield block

    return blocks


def _run_integrate(args: argparse.Namespace) -> int:
    if args.integrand not in INTEGRANDS:
        raise _UsageError(f"--integrand {args.integrand!r} is not known; use one of {sorted(INTEGRANDS)}")
    integrand = INTEGRANDS[args.integrand]
    seed = check_seed(args.seed, "--seed") if args.seed is not None else np.random.SeedSequence().entropy
    kwargs = dict(
        domain=integrand.domain, n=args.n, method=args.method, points=args.points, replicates=args.replicates, rng=seed
    )
    to_tolerance = args.rtol is not None or args.atol is not None
    if to_tolerance:
        check_rtol(0.0 if args.rtol is None else args.rtol, "--rtol")  # before the time estimate's pilot
        check_nonnegative(0.0 if args.atol is None else args.atol, "--atol")
        kwargs.update(rtol=args.rtol, atol=args.atol, n_max=args.n_max)
    elif args.n is None:
        raise _UsageError("--n is required unless --rtol or --atol is given")
    elif args.n_max is not None:
        raise _UsageError("--n-max is only valid with --rtol or --atol")
    start = time.perf_counter()
    client = _cluster_client(args)
    try:
        with warnings.catch_warnings():  # n_max reached: the tolerance line below says so
            warnings.filterwarnings("ignore", message="integrate: the tolerance")
            if client is None:
                _print_estimate(integrand, kwargs, args)  # the integrand's compiled kernel: the fused path
                result = integrate(integrand, **kwargs)
            else:
                result = _distributed().integrate(integrand, client=client, progress=True, **kwargs)
    finally:
        _close_client(client)
    elapsed = time.perf_counter() - start
    error = result.integral - integrand.exact
    low, high = result.confidence_interval
    print(f"{integrand.name} over the {integrand.domain}: {integrand.description}")
    if math.isnan(result.standard_error):
        print(f"  estimate  {result.integral:.12g}  (no error bar: {_no_error_bar(result)})")
    else:
        print(
            f"  estimate  {result.integral:.12g} ± {result.standard_error:.3g} "
            f"(standard error, {result.n_units} {result.unit}s)"
        )
        print(f"  {result.confidence_level:.0%} interval [{low:.12g}, {high:.12g}]")
    print(f"  exact     {integrand.exact:.12g}  (error {error:.3g})")
    print(f"  {result.n_evaluations} evaluations ({result.method}, {result.points}, seed {seed}) in {elapsed:.3f} s")
    if to_tolerance:
        state = "reached" if result.converged else "NOT reached (n_max)"
        print(
            f"  tolerance {result.tolerance:.3g} {state}: half-width {(high - low) / 2:.3g} after {result.n_stages} stages"
        )
    return 0


def _no_error_bar(result: IntegrationResult) -> str:
    """Why a result has no standard error, and what to pass for one."""
    if result.unit == "replicate":
        return "one replicate of the point set has no spread to measure; use --replicates 2 or more (default 8)"
    return f"one {result.unit} has no spread to measure; use a larger --n"


_ESTIMATE_ABOVE = 48 * 2**22  # evaluations (~2 s): longer in-process runs first say how long they will take


def _print_estimate(f: Integrand, kwargs: dict[str, Any], args: argparse.Namespace) -> None:
    """For a long in-process integration: time a pilot of 48 * 2**14 evaluations, print the estimate."""
    n = kwargs["n"]
    if kwargs.get("n_max") is not None or "rtol" in kwargs:  # to a tolerance: up to n_max (default 48 * 2**24)
        n = max(n or 0, kwargs.get("n_max") or 48 * 2**24)
    if not isinstance(n, int) or n <= _ESTIMATE_ABOVE:
        return
    _check_duration(n / _FASTEST_EVALUATIONS_PER_SECOND, f"{n} evaluations", args)  # before the pilot
    pilot = {k: v for k, v in kwargs.items() if k not in ("rtol", "atol", "n_max")}
    pilot.update(n=48 * 2**14, method="equal_area", points="random", replicates=None, rng=0)
    start = time.perf_counter()
    integrate(f, **pilot)  # the arguments are checked at the real call: errors appear there, at once
    rate = pilot["n"] / max(time.perf_counter() - start, 1e-9)
    _check_duration(n / rate, f"{n} evaluations at {rate:.3g} evaluations/s", args)
    print(
        f"symsphere integrate: {n} evaluations, estimated {_duration(n / rate)} at {rate:.3g} evaluations/s; "
        "Ctrl-C stops",
        file=sys.stderr,
    )


def _duration(seconds: float) -> str:
    for unit, size in (("days", 86400.0), ("hours", 3600.0), ("minutes", 60.0)):
        if seconds >= 2 * size:
            return f"{seconds / size:.3g} {unit}"
    return f"{seconds:.3g} s"


def _run_demo(args: argparse.Namespace) -> int:
    start = time.perf_counter()
    args.outputs.watch([args.out])
    report = run_demo(out_dir=args.out, n=args.n, seed=args.seed, progress=not args.no_progress)
    print(
        f"report: {report}  (figures: {report.with_name('figure.png')}, {report.with_name('render.png')}; "
        f"{time.perf_counter() - start:.1f} s)"
    )
    return 0


def _run_render(args: argparse.Namespace) -> int:
    from ..render import render, write_outputs  # function-level: ~0.3 s, only for this verb

    out = Path(args.out)
    if out.suffix.lower() not in (".png", ".pfm", ".npy"):
        raise _UsageError(f"--out must end in .png, .pfm or .npy, got {args.out!r}")
    outputs = [out.with_suffix(s) for s in (".png", ".pfm", ".npy")]  # what write_outputs writes
    for path in outputs:  # before the render, not after minutes of work; errors name the path (OSError)
        check_output_path(path, "--out")
    if args.seed is not None:
        check_seed(args.seed, "--seed")
    furnace_exact = _furnace_radiance() if args.scene == "furnace" else None
    if args.exposure is None:  # the furnace's uniform radiance 2 would clip to pure white
        args.exposure = 1.0 if furnace_exact is None else 0.5 / furnace_exact
    if not (math.isfinite(args.exposure) and args.exposure > 0):  # checked by save_png too, but after the render
        raise _UsageError(f"--exposure must be a positive finite number, got {args.exposure}")
    scene_file = Path(args.scene)
    if scene_file.suffix.lower() == ".xml":  # a Mitsuba 3 scene file: rendered with symsphere_path
        return _run_mitsuba_render(args, out)
    if scene_file.suffix.lower() in (".toml", ".json"):
        if not scene_file.exists():
            raise _UsageError(f"--scene: file {args.scene!r} does not exist")
        if not scene_file.is_file():  # a FIFO would block the reader, /dev/zero never ends
            raise _UsageError(
                f"--scene: {args.scene!r} is {file_kind(os.stat(scene_file).st_mode)}, not a regular file"
            )
    for name in ("width", "height", "spp", "threads"):  # render() checks them too, naming 'spp' not '--spp'
        if getattr(args, name) is not None:
            check_count(getattr(args, name), f"--{name}")
    pixels = args.width * args.height  # before any allocation; render() checks the same, without the '--'
    check_size(pixels, "--width * --height", MAX_PIXELS, f"({args.width} x {args.height} pixels)")
    check_size(args.spp, "--spp", MAX_PATHS // pixels, f"for {args.width} x {args.height} pixels (int64 path indices)")
    if args.scheduler is None:  # on a remote cluster the number of threads is not known here
        threads = (args.threads or os.cpu_count() or 1) * (args.workers or 1)
        _check_duration(
            pixels * args.spp / (_FASTEST_PATHS_PER_THREAD * threads),
            f"{pixels * args.spp} paths (--width x --height x --spp on {threads} threads)",
            args,
        )
    options = dict(
        width=args.width,
        height=args.height,
        spp=args.spp,
        sampler=args.sampler,
        integrator=args.integrator,
        method=args.method,
        pixel_filter=args.filter,
        seed=args.seed,
        progress=not args.no_progress,
    )
    client = _cluster_client(args)
    try:
        if client is None:
            result = render(args.scene, threads=args.threads, **options)
        else:
            result = _distributed().render(args.scene, client=client, **options)
    finally:
        _close_client(client)
    _check_pending(args)  # an interrupt lost while the kernels compiled: nothing is written
    args.outputs.watch(outputs)
    paths = write_outputs(result, out, exposure=args.exposure)  # all three files or none; errors name the file
    args.outputs.done = True
    method = f" ({result.method})" if result.method else ""
    if client is None:
        where = f"on {result.threads} threads (+{result.startup_seconds:.2f} s compile/load)"
    else:
        where = f"in all, on a Dask cluster of {result.threads} workers (wall time, compilation included)"
    print(
        f"rendered {result.scene} {result.width}x{result.height} at {result.spp} spp, {result.integrator} integrator, "
        f"{result.sampler} sampler{method}, "
        f"seed {result.seed}: {result.paths} paths in {result.seconds:.2f} s = "
        f"{result.paths_per_second / 1e6:.2f} Mpaths/s {where}; wrote {', '.join(str(p) for p in paths)}"
    )
    if furnace_exact is not None:
        mean = float(result.image.mean())
        spread = float(result.image.mean(axis=2).std(ddof=1) / math.sqrt(result.width * result.height))
        print(
            f"furnace: mean radiance {mean:.6g} ± {spread:.2g} (standard error over pixels), exact {furnace_exact:g} "
            f"= emission / (1 - albedo); relative error {mean / furnace_exact - 1:+.2e}; PNG at exposure "
            f"{args.exposure:g} (exact = mid-grey)"
        )
    return 0


def _run_mitsuba_render(args: argparse.Namespace, out: Path) -> int:
    from ..render import save_image_set
    from .mitsuba_render import render_scene_file  # function-level: imports Mitsuba

    for name in ("width", "height", "spp"):
        check_count(getattr(args, name), f"--{name}")
    if args.integrator != "path":
        raise _UsageError("--integrator: Mitsuba scene files are rendered with NEE and MIS (path) only")
    seed = args.seed if args.seed is not None else int(cast(int, np.random.SeedSequence().entropy) % 2**32)
    r = render_scene_file(args.scene, width=args.width, height=args.height, spp=args.spp, sampler=args.sampler,
                          method=args.method, seed=seed)  # fmt: skip
    paths = save_image_set([out.with_suffix(s) for s in (".png", ".pfm", ".npy")], r["image"], args.exposure)
    print(
        f"rendered {args.scene} {r['width']}x{r['height']} at {r['spp']} spp with Mitsuba 3 ({r['variant']}), "
        f"symsphere_path strategy {r['strategy']}, points {r['points']}, seed {seed}: {r['paths']} paths in "
        f"{r['seconds']:.2f} s = {r['paths'] / r['seconds'] / 1e6:.2f} Mpaths/s (JIT compile included); "
        f"wrote {', '.join(str(p) for p in paths)}"
    )
    return 0


def _furnace_radiance() -> float:
    """The exact radiance of the built-in furnace scene: emission / (1 - albedo), from its defaults."""
    import inspect

    from ..render import furnace

    defaults = inspect.signature(furnace).parameters
    return float(defaults["emission"].default) / (1 - float(defaults["albedo"].default))


def _describe_os_error(exc: OSError) -> str:
    if exc.filename is not None and exc.strerror:
        return f"cannot write {exc.filename!s}: {exc.strerror}"
    return str(exc)


if __name__ == "__main__":
    sys.exit(main())
