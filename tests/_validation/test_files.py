"""symsphere._validation.files: what checking an output path leaves behind."""

import os

import pytest
from references import inject_sigint

from symsphere._testing import validation


@pytest.mark.usefixtures("python_sigint_handler")  # Python's own handler, whatever the worker's
def test_a_ctrl_c_while_probing_the_folder_leaves_no_probe(tmp_path, monkeypatch):
    # The SIGINT arrives right after the probe is created (its os.open), before it is removed: it is
    # deferred until the probe is gone (found by test_late_sigint_at_many_times, whose signal at the
    # start of `symsphere sample` left `.d.npy.<hex>.probe` behind).
    inject_sigint(monkeypatch, os, "open", 1)
    with pytest.raises(KeyboardInterrupt):
        validation.check_output_path(tmp_path / "d.npy", "--out")
    monkeypatch.undo()
    assert os.listdir(tmp_path) == []
