"""The ``symsphere`` command: sample directions to a file, or run the demo.

Examples
--------
::

    symsphere sample --n 4800 --seed 1 --out directions.npy
    symsphere sample --n 4800 --domain hemisphere --normal 0 1 0 --out hemi.csv
    symsphere demo --out symsphere-demo
    symsphere render --scene cornell --width 256 --height 192 --spp 96 --strategy symmetric --points sobol --out img.png
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
import math
import os
import signal
import sys
import time
import warnings
from collections.abc import Callable, Iterator, Sequence
from typing import Any

import numpy as np

from .. import IntegrationResult, __version__, integrate, iter_hemisphere, iter_sphere
from .._auto import ANSWER_FACTOR
from .._integration import DEFAULT_REPLICATES, check_partials_fit
from .._typing import FloatArray
from .._validation import check_count, check_nonnegative, check_output_path, check_rtol, check_seed
from ..integrands import INTEGRANDS, Integrand
from ..io import DIRECTION_SUFFIXES, check_suffix, stream_directions
from ..points import BLOCK, POINT_SETS
from ..symmetry import orbit_size
from ..warps import METHODS
from ._notices import compile_notice
from ._process import (
    FASTEST_DIRECTIONS_PER_SECOND,
    FASTEST_EVALUATIONS_PER_SECOND,
    Outputs,
    UsageError,
    abandoned_work,
    add_run_options,
    check_duration,
    check_pending,
    close_client,
    cluster_client,
    describe_os_error,
    distributed_module,
    duration,
    exit_now,
    ignore_signals,
    one_line,
    signals_as_interrupts,
)
from .demo import run_demo
from .render_command import add_render_parser, is_mitsuba_scene
from .study import add_study_parser

__all__ = ["main", "build_parser"]

_DOMAINS = ("sphere", "hemisphere")
_DTYPES = ("float64", "float32")
_DEMO_DEFAULT_N = 48 * 2**14
_Blocks = Callable[["FloatArray | None"], Iterator["FloatArray"]]  # stream_directions' blocks(out)


def build_parser(*, mitsuba: bool = False) -> argparse.ArgumentParser:
    """The argument parser of the ``symsphere`` command (one sub-parser per verb).

    With *mitsuba*, the ``render`` verb takes the options of a Mitsuba 3 scene file (``--scene X.xml``),
    and its ``--help`` lists only those.

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
    add_run_options(sample, _run_sample)

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
        help=(
            "independent randomisations of stratified and QMC points; the error bar needs 2 or more (default 8);"
            f" with --method auto|lebedev|fibonacci and a tolerance: the pilot stages' count, the answering stage has {ANSWER_FACTOR}"
            " times as many"
        ),
    )  # fmt: skip
    integrate.add_argument("--seed", type=int, default=None, help="non-negative integer; default: fresh entropy")
    integrate.add_argument("--rtol", type=float, default=None, help="relative tolerance: double n until it is met")
    integrate.add_argument("--atol", type=float, default=None, help="absolute tolerance: double n until it is met")
    integrate.add_argument(
        "--n-max", type=int, default=None, help="with --rtol/--atol: the largest n (default 48 * 2**24)"
    )
    add_run_options(integrate, _run_integrate)

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

    add_render_parser(verbs, mitsuba=mitsuba)

    add_study_parser(verbs)
    return parser


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
    words = sys.argv[1:] if argv is None else list(argv)
    parser = build_parser(mitsuba=is_mitsuba_scene(words))
    try:
        args = parser.parse_args(words)
    except SystemExit as exc:  # --help, --version and usage errors: hand back argparse's status
        return exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 2)
    if args.verb is None:
        parser.print_help(sys.stderr)
        return 2
    status = _run(args, argv)
    if argv is None and abandoned_work():  # a Mitsuba call still running in its thread: the interpreter's
        return exit_now(status, argv)  # finalization would meet it (a fatal "GIL is released" abort)
    return status


def _run(args: argparse.Namespace, argv: Sequence[str] | None) -> int:
    prog = f"symsphere {args.verb}"
    args.outputs = Outputs()
    args.pending = []
    try:
        with signals_as_interrupts(args.pending), compile_notice(prog):
            status = _with_notes(args.handler, args, prog)
            if not args.outputs.complete():  # an interrupt lost inside a C callback: not a success
                check_pending(args)
        if argv is None and status == 0 and args.outputs.paths:  # the program is about to exit: a signal
            ignore_signals()  # now must not turn a written output into a death by signal
        return status
    except KeyboardInterrupt as exc:
        return _interrupted(getattr(exc, "signum", signal.SIGINT), args, prog, argv)
    except Exception as exc:
        if args.pending:  # a signal whose exception a C callback dropped made the work fail: it is the signal
            return _interrupted(args.pending[0], args, prog, argv)
        return _report(exc, prog)


def _report(exc: Exception, prog: str) -> int:
    """One line on stderr for an error, and the exit status: 2 invalid arguments, 1 anything else."""
    if isinstance(exc, (UsageError, ValueError, TypeError)):
        # The library's validators name the argument; a traceback would add nothing.
        print(f"{prog}: error: {one_line(exc)}", file=sys.stderr)
        return 2
    if isinstance(exc, OSError):
        print(f"{prog}: error: {one_line(describe_os_error(exc))}", file=sys.stderr)
        return 1
    if isinstance(exc, MemoryError):
        print(f"{prog}: error: out of memory{': ' + one_line(exc) if str(exc) else ''}", file=sys.stderr)
        return 1
    if os.environ.get("SYMSPHERE_TRACEBACK"):  # a bug, or a library below failing in a new way
        raise exc
    print(
        f"{prog}: internal error: {type(exc).__name__}: {one_line(exc)} (set SYMSPHERE_TRACEBACK=1 for the traceback)",
        file=sys.stderr,
    )
    return 1


def _interrupted(signum: int, args: argparse.Namespace, prog: str, argv: Sequence[str] | None) -> int:
    """The end of a run stopped by *signum*: one line, and 130 (SIGINT) or 128 + the signal; 0 if the
    output was already complete."""
    name = signal.Signals(signum).name
    if argv is None:  # the program is about to exit: no second signal may turn this into a death by signal
        ignore_signals()
    if args.outputs.complete():  # the renames had begun: the output is whole, and it stays
        shown = ", ".join(str(p) for p in args.outputs.paths)
        print(f"{prog}: {name} arrived after the output was complete; kept {shown}", file=sys.stderr)
        return 0
    if signum != signal.SIGINT:
        print(f"{prog}: terminated ({name}); nothing was written", file=sys.stderr)
        return exit_now(128 + signum, argv)
    print(f"{prog}: interrupted; nothing was written", file=sys.stderr)
    return exit_now(130, argv)


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
        raise UsageError("--normal is only valid with --domain hemisphere; add --domain hemisphere or drop --normal")
    check_suffix(args.out, "--out")  # before sampling, so that a typo costs nothing
    check_output_path(args.out, "--out")  # a device, a FIFO, a missing directory: refused now (OSError)
    seed = args.seed
    if seed is None:
        seed = np.random.SeedSequence().entropy  # printed below, so the run can be repeated
    start = time.perf_counter()
    seed = check_seed(seed, "--seed")
    options = dict(method=args.method, points=args.points, rng=seed, dtype=np.dtype(args.dtype))
    count = orbit_size(args.domain)
    check_count(args.n, "n", multiple=count)  # named as the library's sample functions name it, not n_total
    check_duration(args.n / FASTEST_DIRECTIONS_PER_SECOND, f"--n {args.n}", args)
    chunk = args.chunk if args.chunk is not None else count * 2**16

    def iterate(out: FloatArray | None) -> Iterator[FloatArray]:
        if args.domain == "sphere":
            return iter_sphere(args.n, chunk=chunk, out=out, **options)
        return iter_hemisphere(args.n, chunk=chunk, normal=args.normal, out=out, **options)

    iterate(None)  # validate every argument before the output file is created
    client = cluster_client(args)
    try:
        blocks = iterate if client is None else _cluster_blocks(client, args, options, chunk)
        with tqdm(total=args.n, unit="dir", unit_scale=True, disable=None, desc="sampling", leave=False) as bar:
            args.outputs.watch([args.out])

            def progress(count: int) -> None:
                check_pending(args)  # an interrupt lost while a kernel compiled: roll back now
                bar.update(count)

            try:
                stream_directions(args.out, args.n, args.dtype, blocks, name="--out", progress=progress)
            except OSError as exc:  # name the user's file, not the temporary next to it
                raise OSError(exc.errno, exc.strerror, args.out) from exc
            args.outputs.done = True
    finally:
        close_client(client)
    elapsed = time.perf_counter() - start
    print(
        f"wrote {args.n} directions ({args.domain}, {args.method}, {args.points}, "
        f"seed {seed}, {args.dtype}) to {args.out} in {elapsed:.3f} s"
    )
    return 0


def _cluster_blocks(client: Any, args: argparse.Namespace, options: dict[str, Any], chunk: int) -> _Blocks:
    """blocks(out) for stream_directions: chunks computed on the cluster, in order, a few in flight."""
    distributed = distributed_module()
    count = orbit_size(args.domain)
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
        raise UsageError(f"--integrand {args.integrand!r} is not known; use one of {sorted(INTEGRANDS)}")
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
        raise UsageError("--n is required unless --rtol or --atol is given")
    elif args.n_max is not None:
        raise UsageError("--n-max is only valid with --rtol or --atol")
    start = time.perf_counter()
    client = cluster_client(args)
    try:
        with warnings.catch_warnings():  # n_max reached: the tolerance line below says so
            warnings.filterwarnings("ignore", message="integrate: the tolerance")
            if client is None:
                _print_estimate(integrand, kwargs, args)  # the integrand's compiled kernel: the fused path
                result = integrate(integrand, **kwargs)
            else:
                result = distributed_module().integrate(integrand, client=client, progress=True, **kwargs)
    finally:
        close_client(client)
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
    # Before the pilot and its estimate: a run whose partial sums cannot fit in memory is one line.
    replicates = 1 if kwargs["points"] in (None, "random") else kwargs["replicates"] or DEFAULT_REPLICATES
    count = 48 if kwargs["domain"] == "sphere" else 24
    if isinstance(replicates, int) and replicates > 0 and n % (count * replicates) == 0:  # else integrate says
        check_partials_fit(n, count, replicates, "--n" if n == kwargs["n"] else "--n-max", None, "--replicates")
    check_duration(n / FASTEST_EVALUATIONS_PER_SECOND, f"{n} evaluations", args)  # before the pilot
    pilot = {k: v for k, v in kwargs.items() if k not in ("rtol", "atol", "n_max")}
    pilot.update(n=48 * 2**14, method="equal_area", points="random", replicates=None, rng=0)
    start = time.perf_counter()
    integrate(f, **pilot)  # the arguments are checked at the real call: errors appear there, at once
    rate = pilot["n"] / max(time.perf_counter() - start, 1e-9)
    check_duration(n / rate, f"{n} evaluations at {rate:.3g} evaluations/s", args)
    print(
        f"symsphere integrate: {n} evaluations, estimated {duration(n / rate)} at {rate:.3g} evaluations/s; "
        "Ctrl-C stops",
        file=sys.stderr,
    )


def _run_demo(args: argparse.Namespace) -> int:
    start = time.perf_counter()
    args.outputs.watch([args.out])
    report = run_demo(out_dir=args.out, n=args.n, seed=args.seed, progress=not args.no_progress)
    print(
        f"report: {report}  (figures: {report.with_name('figure.png')}, {report.with_name('render.png')}; "
        f"{time.perf_counter() - start:.1f} s)"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
