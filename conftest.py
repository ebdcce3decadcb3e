"""Collection: without Mitsuba 3 (the optional extra ``mitsuba``), symsphere.mitsuba's doctests are not
collected (importing it says what to install); tests/mitsuba skip with the reason (tests/mitsuba/conftest.py)."""

import importlib.util

collect_ignore_glob = [] if importlib.util.find_spec("mitsuba") else ["src/symsphere/mitsuba/*.py"]
