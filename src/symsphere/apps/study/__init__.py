"""The convergence study: every sampler, point set and integrand, written up as a report.

``run_study`` measures, for every sampler x point set x integrand of a
:class:`StudyConfig`:

- the root-mean-square error of the estimate over independent repetitions
  for n = 48 * 2**k evaluations, k = ``k_min ... k_max``;
- the convergence slope, by least squares of log RMSE against log n, with
  its standard error;
- the efficiency 1 / (MSE * seconds) at the largest n, seconds being the
  median wall time of one estimate (sampling and evaluation);

and, for the point sets and samplers themselves,

- the spherical-cap L2 discrepancy of every point set on the sphere, exact,
  through Stolarsky's invariance principle
  (:func:`symsphere.quality.cap_discrepancy`), both with equal weights and
  with the estimator's weights 1 / (N 4 pi pdf);
- chi-square p-values of every random sampler against the uniform density
  and against its own density (:func:`symsphere.stats.chi2_test`, one
  direction per orbit for the orbit samplers);
- density maps (Mollweide) and warp pictures of the maps.

The results go to a folder: ``report.md`` (and ``report.html``), the CSV
tables ``convergence.csv``, ``summary.csv``, ``discrepancy.csv``,
``chi2.csv`` and PNG figures.  The folder appears only when complete
(:func:`symsphere.io.atomic_directory`).

Modules: :mod:`.config` (what is measured), :mod:`.samplers` (the scheme and
the peers behind one interface), :mod:`.run` (the stages, seeds, CSV),
:mod:`.figures`, :mod:`.report`, :mod:`.command` (the ``study`` verb).  The
statistics (RMSE, slope fit, cap discrepancy) are library code in
:mod:`symsphere.quality`.

Estimators
----------
The symmetric scheme (sampler ``symsphere_<method>``) is estimated by
:func:`symsphere.integrate`, its own estimator (the mean of f over each orbit,
weighted by 1 / pdf of the scheme), with ``replicates=1``: one repetition is
one call with a fresh seed (fresh random points, jitter or scrambling).  A
peer sampler gives ``mean(f / pdf)`` over its n directions.

Sizes
-----
n = 48 * 2**k for every sampler, except the scheme with stratified points,
which needs a square number of base points (n/48 on the sphere, n/24 on the
hemisphere): there n is the nearest such size, ``48 * round(sqrt(2**k))**2``
(for odd k; even k are exact), and the tables give the n actually used.
For Sobol' points of the peers, n = 3 * 2**(k + 4) is not a power of 2: the
first n points of the sequence are the union of two scrambled (0, m, 2)-nets
(of 2**(k+5) and 2**(k+4) points), so the balance holds piecewise and the
warning scipy gives is silenced.

Command line: ``symsphere study --out study-report`` (the full study) or
``symsphere study --config small`` (the one CI runs); see
:func:`add_study_parser`.
"""

from .command import add_study_parser, run_study_command
from .config import CONFIGS, StudyConfig
from .run import run_study, study_files

__all__ = ["StudyConfig", "CONFIGS", "run_study", "study_files", "add_study_parser", "run_study_command"]
