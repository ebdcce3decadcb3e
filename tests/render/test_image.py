"""symsphere.render.image: PFM, .npy and tone-mapped PNG output."""

import numpy as np
import pytest

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
