"""symsphere.render.image: PFM, .npy and tone-mapped PNG output."""

import os

import numpy as np
import pytest
from references import inject_sigint

from symsphere.render import load_pfm, save_npy, save_pfm, save_png, tonemap


def test_pfm_round_trip(tmp_path):
    rng = np.random.default_rng(1)
    image = rng.random((5, 7, 3)) * 10
    path = save_pfm(tmp_path / "x.pfm", image)
    raw = path.read_bytes()
    assert raw.startswith(b"PF\n7 5\n-1.0\n") and len(raw) == len(b"PF\n7 5\n-1.0\n") + 5 * 7 * 3 * 4
    np.testing.assert_array_equal(load_pfm(path), image.astype(np.float32))
    # bottom row first, little-endian
    first = np.frombuffer(raw[len(b"PF\n7 5\n-1.0\n") :][:12], dtype="<f4")
    np.testing.assert_array_equal(first, image[-1, 0].astype(np.float32))
    assert sorted(p.name for p in tmp_path.iterdir()) == ["x.pfm"]  # no temporaries left


def test_pfm_reader_rejects_garbage(tmp_path):
    bad = tmp_path / "bad.pfm"
    bad.write_bytes(b"P6\n1 1\n255\n\x00\x00\x00")
    with pytest.raises(ValueError, match="not a PFM"):
        load_pfm(bad)
    bad.write_bytes(b"PF\n2 2\n-1.0\n" + b"\x00" * 8)
    with pytest.raises(ValueError, match="truncated"):
        load_pfm(bad)


def test_npy_and_png(tmp_path):
    from matplotlib.image import imread

    image = np.zeros((2, 3, 3))
    image[0, 0] = 1.0
    image[0, 1] = 0.5
    image[1, 2] = 7.0  # clamped
    np.testing.assert_array_equal(np.load(save_npy(tmp_path / "x.npy", image)), image)
    pixels = imread(save_png(tmp_path / "x.png", image))
    assert pixels.shape[:2] == (2, 3)
    np.testing.assert_array_equal(np.rint(pixels[..., :3] * 255).astype(int), tonemap(image).astype(int))
    assert tonemap(image)[0, 0].tolist() == [255] * 3 and tonemap(image)[1, 0].tolist() == [0] * 3
    assert tonemap(image)[0, 1, 0] == round(255 * (1.055 * 0.5 ** (1 / 2.4) - 0.055))  # 188
    assert tonemap(image, exposure=0.25)[0, 0, 0] == round(255 * (1.055 * 0.25 ** (1 / 2.4) - 0.055))


# --- writers: suffixes, temporaries only while writing, a signal during the renames --------------------------------


def _listing(directory):
    return sorted(p.name for p in directory.iterdir())


def test_save_png_refuses_another_suffix(tmp_path):
    from symsphere.render import save_npy, save_pfm, save_png

    for save, name in ((save_png, "x.jpg"), (save_pfm, "x.png"), (save_npy, "x.pfm")):
        with pytest.raises(ValueError, match="must end in"):
            save(tmp_path / name, np.zeros((1, 1, 3)))
    assert _listing(tmp_path) == []


def test_image_temporaries_exist_only_while_writing(tmp_path, monkeypatch):
    from symsphere.render import image as image_module

    real_encode = image_module._encode
    seen = []

    def encode(*args):
        seen.append(_listing(tmp_path))
        return real_encode(*args)

    monkeypatch.setattr(image_module, "_encode", encode)
    image_module.save_image_set([tmp_path / "a.png", tmp_path / "a.pfm", tmp_path / "a.npy"], np.zeros((2, 2, 3)))
    assert seen == [[], [], []]


@pytest.mark.usefixtures("python_sigint_handler")
def test_sigint_during_the_renames_of_a_set_is_delivered_after_them(tmp_path, monkeypatch):
    from symsphere.render import save_image_set

    paths = [tmp_path / f"a{s}" for s in (".png", ".pfm", ".npy")]
    save_image_set(paths, np.zeros((2, 2, 3)))
    inject_sigint(monkeypatch, os, "replace", 2)  # between the second and the third rename
    with pytest.raises(KeyboardInterrupt):
        save_image_set(paths, np.ones((2, 2, 3)))
    monkeypatch.undo()
    assert np.load(paths[2]).tolist() == np.ones((2, 2, 3)).tolist()  # all three are the new ones
    assert _listing(tmp_path) == ["a.npy", "a.pfm", "a.png"]
