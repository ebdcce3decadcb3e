"""The applications built on the symsphere library: the ``symsphere`` command, the demo and the study.

- :mod:`symsphere.apps.cli`: the ``symsphere`` command (``python -m symsphere``);
- :mod:`symsphere.apps.demo`: ``symsphere demo``, chi-square tests of the maps written up as a report;
- :mod:`symsphere.apps.study`: ``symsphere study``, the convergence study of every sampler.

They use only the library's public names; nothing in the library imports them.
"""
