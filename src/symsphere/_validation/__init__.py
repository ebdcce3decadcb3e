"""Validators shared by the public functions.

Each raises ``TypeError`` or ``ValueError`` with a message that names the
argument and says what is allowed.  Public functions call these at the
boundary; private helpers trust their inputs.

One namespace, three modules by concept: :mod:`.values` (numbers, names, counts, the size
limits, flags and run objects), :mod:`.arrays` (arrays of points, directions and images,
dtypes, ``out=``) and :mod:`.files` (file names, suffixes, output files).
"""

from __future__ import annotations

from . import arrays, files, values
from .arrays import *  # noqa: F403 - the namespace is its modules' __all__, listed once there
from .files import *  # noqa: F403
from .values import *  # noqa: F403

__all__ = [*values.__all__, *arrays.__all__, *files.__all__]
