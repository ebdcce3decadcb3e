"""The package's random streams, each defined once and shared by the kernels, the renderer and the
Mitsuba plugin through the public names of these private modules.

- :mod:`~symsphere._random.pcg64`: numpy's PCG64 in numba (the sampling and integration kernels draw
  their base points with it, bit for bit numpy's ``Generator.random()``);
- :mod:`~symsphere._random.seed_sequence`: numpy's ``SeedSequence`` hash in Python's integers (a
  call's seed words without numpy calls);
- :mod:`~symsphere._random.splitmix`: SplitMix64's constants and finaliser (the block keys of
  :mod:`symsphere._blocks`, the renderer's streams);
- :mod:`~symsphere._random.hashes`: the renderer's counter-based streams (per pixel, per sample);
- :mod:`~symsphere._random.owen_sobol`: Owen-scrambled (and interlaced) Sobol' points.

The Dr.Jit forms (:mod:`symsphere.mitsuba._random`) import their constants from here.
"""
