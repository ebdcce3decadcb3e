"""``symsphere study``: the verb's parser and handler, wired into the ``symsphere`` command."""

from __future__ import annotations

import argparse
import errno
import sys
import time
from pathlib import Path

from ..._validation import check_seed, short_repr
from .config import CONFIGS, MAX_REPETITIONS, StudyConfig
from .run import run_study

__all__ = ["add_study_parser", "run_study_command"]


def add_study_parser(subparsers: argparse._SubParsersAction[argparse.ArgumentParser]) -> argparse.ArgumentParser:
    """Add the ``study`` verb to the ``symsphere`` command's sub-parsers.

    Parameters
    ----------
    subparsers : argparse._SubParsersAction
        What ``ArgumentParser.add_subparsers()`` returned.

    Returns
    -------
    argparse.ArgumentParser
        The ``study`` parser; its default ``handler`` is :func:`run_study_command`.

    Examples
    --------
    >>> import argparse
    >>> from symsphere.apps.study import add_study_parser
    >>> parser = argparse.ArgumentParser(prog="symsphere")
    >>> _ = add_study_parser(parser.add_subparsers(dest="verb"))
    >>> parser.parse_args(["study", "--config", "small"]).config
    'small'
    """
    study = subparsers.add_parser(
        "study",
        help="convergence study of every strategy (the scheme, the peers), points and integrand, written up as a report",
        description=(
            "Measure, for every strategy x points x method (the scheme with each map, and the peers) x integrand, the RMSE over independent repetitions "
            "for n = 48*2^k, the convergence slope and the efficiency 1/(MSE x seconds); the spherical-cap "
            "L2 discrepancy of every point set (exact, by Stolarsky's invariance principle); chi-square "
            "p-values of the random samplers; and write report.md, report.html, CSV tables and PNG figures "
            "into DIR.  --config full (the default) takes about 13 minutes on 2 cores; --config small, "
            "well under a minute; --config qmc (higher-order QMC base points against Lebedev and rotated "
            "Fibonacci, sphere only) about 15 minutes.  An existing DIR is replaced only if it holds nothing but an earlier "
            "study's output."
        ),
    )
    study.add_argument("--out", default="study-report", metavar="DIR", help="output directory (default: %(default)s)")
    study.add_argument("--config", choices=tuple(CONFIGS), default="full", help="default: %(default)s")
    study.add_argument("--seed", type=int, default=0, help="non-negative integer (default: %(default)s)")
    study.add_argument(
        "--repetitions",
        type=int,
        default=None,
        help="independent repetitions per cell, >= 2 (default: 32 for full and qmc, 4 for small)",
    )
    study.add_argument(
        "--k-max",
        type=int,
        default=None,
        dest="k_max",
        metavar="K",
        help="largest size n = 48*2^K (default: 14 for full and qmc, 6 for small)",
    )
    study.add_argument("--no-progress", action="store_true", help="do not show a progress bar")
    study.add_argument(
        "--allow-long", action="store_true",
        help="run even if the work is estimated to take more than a day (refused otherwise, before any work)",
    )  # fmt: skip
    study.set_defaults(handler=run_study_command)
    return study


_LONG_SECONDS = 86400.0
# What each configuration took on 2 cores (docs/study.md: full about 13 minutes, qmc about 15, small well
# under one), divided by 4 for a faster machine: a lower bound for the estimate, which scales it by the
# repetitions and the largest size asked for.
_FASTEST_SECONDS = {"full": 13 * 60 / 4, "qmc": 15 * 60 / 4, "small": 60 / 4}


def _estimated_seconds(name: str, config: StudyConfig) -> float:
    base = CONFIGS[name]
    scale = config.repetitions / base.repetitions * 2.0 ** (config.k_max - base.k_max)
    return _FASTEST_SECONDS.get(name, 60.0) * max(1.0, scale)


def run_study_command(args: argparse.Namespace) -> int:
    """Handler of ``symsphere study``: run :func:`run_study` with the parsed *args*; return 0.

    Invalid values raise ValueError naming the option (the ``symsphere`` command turns it into exit
    status 2); an unwritable output raises OSError (exit status 1).

    Parameters
    ----------
    args : argparse.Namespace
        Parsed by the parser of :func:`add_study_parser`: ``out``, ``config`` (a name in
        :data:`CONFIGS`), ``seed``, ``repetitions``, ``k_max`` and ``no_progress``.

    Returns
    -------
    int
        0, once the report folder is written (its path is printed).

    Examples
    --------
    The study takes a while, even small (about a minute on 2 cores), so the run is not executed
    here; the arguments are checked before any work is done:

    >>> import argparse, os, tempfile
    >>> from symsphere.apps.study import add_study_parser, run_study_command
    >>> parser = argparse.ArgumentParser(prog="symsphere")
    >>> _ = add_study_parser(parser.add_subparsers(dest="verb"))
    >>> out = os.path.join(tempfile.mkdtemp(), "study-report")
    >>> args = parser.parse_args(["study", "--config", "small", "--k-max", "4", "--repetitions", "2",
    ...                           "--out", out])
    >>> args.handler is run_study_command
    True
    >>> run_study_command(args)  # doctest: +SKIP
    report: .../study-report/report.md  (and report.html, CSV tables and figures in ...; ... s)
    0
    >>> run_study_command(parser.parse_args(["study", "--repetitions", "1", "--out", out]))
    Traceback (most recent call last):
        ...
    ValueError: --repetitions must be >= 2, got 1
    """
    check_seed(args.seed, "--seed")
    config = CONFIGS[args.config]
    changes = {}
    if args.repetitions is not None:
        if args.repetitions < 2:
            raise ValueError(f"--repetitions must be >= 2, got {args.repetitions}")
        if args.repetitions > MAX_REPETITIONS:
            raise ValueError(f"--repetitions must be at most {MAX_REPETITIONS}, got {short_repr(args.repetitions)}")
        changes["repetitions"] = args.repetitions
    if args.k_max is not None:
        if args.k_max < config.k_min + 2 or args.k_max > 20:
            raise ValueError(f"--k-max must be in [{config.k_min + 2}, 20], got {args.k_max}")
        changes["k_max"] = args.k_max
    if changes:
        config = config.replace(
            name=f"{config.name} (" + ", ".join(f"{k}={v}" for k, v in changes.items()) + ")", **changes
        )
    seconds = _estimated_seconds(args.config, config)
    if seconds > _LONG_SECONDS and not getattr(args, "allow_long", False):
        raise ValueError(
            f"--repetitions {config.repetitions} with --k-max {config.k_max} is estimated to take at least "
            f"{seconds / 86400:.3g} days; add --allow-long to run it anyway"
        )
    if seconds > 600:
        print(f"symsphere study: estimated at least {seconds / 3600:.3g} hours; Ctrl-C stops", file=sys.stderr)
    parent = Path(args.out).absolute().parent
    if not parent.is_dir():  # name the user's path, not the temporary folder next to it
        raise OSError(errno.ENOENT, "no such directory", str(parent))
    start = time.perf_counter()
    report = run_study(args.out, config=config, seed=args.seed, progress=not args.no_progress)
    print(
        f"report: {report}  (and report.html, CSV tables and figures in {report.parent}; "
        f"{time.perf_counter() - start:.1f} s)"
    )
    return 0
