"""Image output: linear HDR (PFM, .npy) and tone-mapped sRGB PNG, every file written atomically.

Images are (height, width, 3) arrays of linear radiance, row 0 at the top.
Several files of one image (:func:`save_image_set`) appear together or not at all
(:func:`symsphere.io.atomic_paths`).

- PFM (Portable Float Map): ``PF``, ``width height``, scale ``-1.0`` (negative:
  little-endian), then float32 RGB rows from the *bottom* row up.
- ``.npy``: the array as is (``numpy.save``), float64 unless given otherwise.
- EXR (OpenEXR, float32 RGB): written with Mitsuba 3's ``Bitmap`` (the extra ``mitsuba``), for
  readers that take HDR images in no other format.
- PNG: ``exposure * radiance`` clamped to [0, 1], then the sRGB transfer
  function (``12.92 c`` below 0.0031308, else ``1.055 c^(1/2.4) - 0.055``),
  rounded to 8 bits; written as 8-bit RGB with Pillow (matplotlib's own PNG writer, without
  matplotlib's ~0.7 s import and set-up on every render).
"""

from __future__ import annotations

import io
import os
from collections.abc import Iterable
from pathlib import Path

import numpy as np
import numpy.typing as npt

from .._typing import Float64Array, FloatArray
from .._validation import (
    check_exposure,
    check_file_suffix,
    check_finite_array,
    check_float32_range,
    check_image,
    check_path,
    check_paths,
    read_regular_file,
)
from ..io import atomic_paths

__all__ = [
    "HDR_SUFFIXES",
    "IMAGE_SUFFIXES",
    "linear_to_srgb",
    "tonemap",
    "save_png",
    "save_pfm",
    "load_pfm",
    "save_npy",
    "save_image",
    "save_image_set",
]

HDR_SUFFIXES = (".pfm", ".npy")
IMAGE_SUFFIXES = (".png", ".pfm", ".npy", ".exr")
"""The suffixes (lower case; matched case-insensitively) :func:`save_image` and :func:`save_image_set` write."""


def _encode(suffix: str, image: FloatArray, exposure: float) -> bytes:
    """The bytes of *image* (checked) in the format of *suffix*: made before any temporary file exists."""
    buffer = io.BytesIO()
    if suffix == ".png":
        from PIL import Image  # function-level: only PNG output needs it

        Image.fromarray(tonemap(image, exposure), mode="RGB").save(buffer, format="png")
    elif suffix == ".pfm":
        height, width = image.shape[:2]
        buffer.write(f"PF\n{width} {height}\n-1.0\n".encode("ascii"))
        buffer.write(np.ascontiguousarray(image[::-1], dtype="<f4").tobytes())
    elif suffix == ".exr":
        return _encode_exr(image)
    else:
        np.save(buffer, image)
    return buffer.getvalue()


def _encode_exr(image: FloatArray) -> bytes:
    """OpenEXR bytes of *image* (float32 RGB), by Mitsuba 3's Bitmap; ValueError if Mitsuba is missing."""
    try:
        import mitsuba as mi  # function-level and optional: only EXR output needs it
    except ImportError as error:
        raise ValueError(f"'.exr' output needs Mitsuba 3: pip install 'symsphere[mitsuba]' ({error})") from None
    from ._exr_threads import exr_threads  # function-level: imports Dr.Jit when called

    bitmap = mi.Bitmap(np.ascontiguousarray(image, dtype=np.float32), mi.Bitmap.PixelFormat.RGB)
    stream = mi.MemoryStream()
    with exr_threads():  # Mitsuba's OpenEXR writer hangs with one thread in Dr.Jit's pool
        bitmap.write(stream, mi.Bitmap.FileFormat.OpenEXR)
    stream.seek(0)
    return bytes(stream.read(stream.size()))


def linear_to_srgb(c: npt.ArrayLike) -> Float64Array:
    """The sRGB transfer function (IEC 61966-2-1) of linear values, elementwise, as float64.

    Parameters
    ----------
    c : array_like of real numbers, any shape
        Linear values; [0, 1] is the displayable range.  Values outside it follow the
        formula (negative values stay linear, values above 1 go above 1): clip first
        for 8-bit output, as :func:`tonemap` does.

    Returns
    -------
    ndarray of float64, the shape of *c*

    Raises
    ------
    ValueError
        If *c* holds NaN or inf (a NaN has no colour: :func:`tonemap` maps NaN to 0
        and inf to 1 itself).
    TypeError
        If *c* is not an array of real numbers.

    Examples
    --------
    >>> from symsphere.render import linear_to_srgb
    >>> linear_to_srgb([0.0, 0.001, 1.0]).round(6)
    array([0.     , 0.01292, 1.     ])
    """
    return _srgb(check_finite_array(c, "c").astype(np.float64))


def _srgb(c: Float64Array) -> Float64Array:
    with np.errstate(over="ignore"):  # finite input: c ** (1/2.4) cannot overflow
        return np.where(c <= 0.0031308, 12.92 * c, 1.055 * np.power(np.maximum(c, 0.0031308), 1 / 2.4) - 0.055)


def tonemap(image: npt.ArrayLike, exposure: float = 1.0) -> npt.NDArray[np.uint8]:
    """8-bit sRGB of a linear HDR image: ``round(255 * srgb(clip(exposure * image, 0, 1)))``.

    NaN (never produced by the renderer) maps to 0.

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere.render import tonemap
    >>> tonemap(np.full((1, 2, 3), 0.5))[0, 0]
    array([188, 188, 188], dtype=uint8)
    """
    image = check_image(image)
    exposure = check_exposure(exposure)
    with np.errstate(over="ignore", invalid="ignore"):  # inf and NaN are handled next
        scaled = np.nan_to_num(image.astype(np.float64) * exposure, nan=0.0, posinf=1.0, neginf=0.0)
    return np.rint(255.0 * _srgb(np.clip(scaled, 0.0, 1.0))).astype(np.uint8)


def save_png(path: str | os.PathLike[str], image: npt.ArrayLike, exposure: float = 1.0) -> Path:
    r"""Write the tone-mapped *image* (see :func:`tonemap`) as a PNG file, atomically.

    *path* must end in ``.png`` (a PNG under another name would mislead every reader).

    Examples
    --------
    >>> import numpy as np, pathlib, tempfile
    >>> from symsphere.render import save_png
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     save_png(pathlib.Path(folder) / "x.png", np.zeros((2, 3, 3))).read_bytes()[:4]
    b'\x89PNG'
    """
    check_file_suffix(path, (".png",))
    return save_image_set([path], image, exposure)[0]


def save_pfm(path: str | os.PathLike[str], image: npt.ArrayLike) -> Path:
    r"""Write *image* as a little-endian RGB PFM (float32, bottom row first), atomically.

    *path* must end in ``.pfm``.

    Examples
    --------
    >>> import numpy as np, pathlib, tempfile
    >>> from symsphere.render import save_pfm
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     save_pfm(pathlib.Path(folder) / "x.pfm", np.zeros((2, 3, 3))).read_bytes()[:12]
    b'PF\n3 2\n-1.0\n'
    """
    check_file_suffix(path, (".pfm",))
    return save_image_set([path], image)[0]


def save_image_set(paths: Iterable[str | os.PathLike[str]], image: npt.ArrayLike, exposure: float = 1.0) -> list[Path]:
    """Write *image* to every file of *paths*, each in the format of its suffix, all or none.

    Parameters
    ----------
    paths : list of str or os.PathLike
        Distinct files ending in ``.png`` (tone-mapped with *exposure*), ``.pfm``, ``.npy`` or ``.exr``
        (needs Mitsuba 3).
    image : array_like, shape (height, width, 3)
        Linear radiance.
    exposure : float
        For the PNG files (see :func:`tonemap`).

    Returns
    -------
    list of pathlib.Path
        *paths*.

    Notes
    -----
    Every argument is checked before any file is created.  The files are written under
    temporary names and renamed together (:func:`symsphere.io.atomic_paths`): after an
    error, a full disk, Ctrl-C or SIGTERM, either every file is new or every file is as
    it was; an ``OSError`` names the file that could not be written.

    Examples
    --------
    >>> import numpy as np, pathlib, tempfile
    >>> from symsphere.render import save_image_set
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     paths = save_image_set([pathlib.Path(folder) / name for name in ("x.png", "x.pfm")], np.zeros((1, 1, 3)))
    ...     sorted(p.name for p in pathlib.Path(folder).iterdir())
    ['x.pfm', 'x.png']
    """
    targets = check_paths(paths)  # a str or a non-iterable: TypeError; an iterator: read once
    suffixes = [check_file_suffix(path, IMAGE_SUFFIXES, "paths") for path in targets]
    image = check_image(image)
    exposure = check_exposure(exposure)
    if ".pfm" in suffixes or ".exr" in suffixes:
        check_float32_range(image)
    # Encoded first (tone mapping, PNG compression): the temporaries exist only while the bytes are written.
    encoded = [_encode(suffix, image, exposure) for suffix in suffixes]
    with atomic_paths(targets) as temporaries:
        for data, temporary, path in zip(encoded, temporaries, targets, strict=False):
            try:
                temporary.write_bytes(data)
            except OSError as exc:  # name the user's file, not the temporary next to it
                raise OSError(exc.errno, exc.strerror or str(exc), str(path)) from exc
    return targets


def load_pfm(path: str | os.PathLike[str]) -> npt.NDArray[np.float32]:
    """Read a PFM file (``PF`` colour or ``Pf`` grey, either endianness) as (height, width, 3 or 1) float32.

    Examples
    --------
    >>> import numpy as np, pathlib, tempfile
    >>> from symsphere.render import load_pfm, save_pfm
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     load_pfm(save_pfm(pathlib.Path(folder) / "x.pfm", np.full((2, 3, 3), 0.25))).shape
    (2, 3, 3)
    """
    raw = read_regular_file(check_path(path, "path"), f"'path' {str(path)!r}")  # never blocks on a FIFO
    tokens: list[str] = []
    position = 0
    while len(tokens) < 4:  # magic, width, height, scale; then exactly one whitespace byte
        while position < len(raw) and raw[position : position + 1].isspace():
            position += 1
        end = position
        while end < len(raw) and not raw[end : end + 1].isspace():
            end += 1
        if end == position:
            raise ValueError(f"{str(path)!r} is not a PFM file (truncated header)")
        tokens.append(raw[position:end].decode("ascii", "replace"))
        position = end
    position += 1
    magic = tokens[0]
    if magic not in ("PF", "Pf"):
        raise ValueError(f"{str(path)!r} is not a PFM file (magic {magic!r})")
    try:
        width, height, scale = int(tokens[1]), int(tokens[2]), float(tokens[3])
    except ValueError:
        raise ValueError(f"{str(path)!r} is not a PFM file (bad size or scale: {tokens[1:]})") from None
    if width < 1 or height < 1 or scale == 0:
        raise ValueError(f"{str(path)!r} is not a PFM file (bad size or scale: {tokens[1:]})")
    channels = 3 if magic == "PF" else 1
    count = width * height * channels
    if len(raw) - position < 4 * count:
        raise ValueError(f"{str(path)!r} is truncated: expected {count} floats")
    data = np.frombuffer(raw, dtype=np.dtype("<f4" if scale < 0 else ">f4"), count=count, offset=position)
    image: npt.NDArray[np.float32] = data.astype(np.float32).reshape(height, width, channels)[::-1].copy()
    return image


def save_npy(path: str | os.PathLike[str], image: npt.ArrayLike) -> Path:
    """Write *image* with ``numpy.save``, atomically; *path* must end in ``.npy``.

    Examples
    --------
    >>> import numpy as np, pathlib, tempfile
    >>> from symsphere.render import save_npy
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     np.load(save_npy(pathlib.Path(folder) / "x.npy", np.ones((1, 1, 3)))).tolist()
    [[[1.0, 1.0, 1.0]]]
    """
    check_file_suffix(path, (".npy",))
    return save_image_set([path], image)[0]


def save_image(path: str | os.PathLike[str], image: npt.ArrayLike, exposure: float = 1.0) -> Path:
    """Write *image* in the format of the suffix of *path*: .png (tone-mapped), .pfm or .npy.

    Examples
    --------
    >>> import numpy as np, pathlib, tempfile
    >>> from symsphere.render import save_image
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     save_image(pathlib.Path(folder) / "x.npy", np.zeros((1, 1, 3))).suffix
    '.npy'
    """
    check_file_suffix(path, IMAGE_SUFFIXES)
    return save_image_set([path], image, exposure)[0]
