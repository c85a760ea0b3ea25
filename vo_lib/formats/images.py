"""The image files of a sequence: listed in frame order, checked from their headers, decoded.

Frames pair by file name, in numeric order (``2.png`` before ``10.png``); hidden files are ignored.
Every header is checked when a sequence is opened, without decoding: one size, 8 bits per channel,
PNG and JPEG end markers present; damaged compressed data raises when the frame is read. Every
problem raises one :class:`~vo_lib.formats.frame_files.SequenceError` naming the file.
"""

from __future__ import annotations

import os
import re
import struct
import warnings
from pathlib import Path

import cv2
import numpy as np
from PIL import Image

from vo_lib.formats.frame_files import SequenceError

IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".pgm", ".bmp", ".tif", ".tiff")
PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
PNG_END = b"\x00\x00\x00\x00IEND\xaeB`\x82"
JPEG_START, JPEG_END = b"\xff\xd8", b"\xff\xd9"
#: PNG colour types: grey, RGB, palette, grey with alpha, RGBA.
PNG_COLOUR_TYPES = (0, 2, 3, 4, 6)
#: Pillow modes of 8 bits per channel (or fewer, widened to 8 when decoded).
EIGHT_BIT_MODES = {"1", "L", "P", "LA", "La", "PA", "RGB", "RGBA", "RGBa", "RGBX", "CMYK", "YCbCr"}
#: Largest image a header may claim, pixels a side and in all (Pillow's bound against decompression bombs).
MAX_IMAGE_SIDE, MAX_IMAGE_PIXELS = 16384, 89_478_485
NOT_8_BIT = "expected 8-bit grey (convert it, e.g. scale 16-bit values to 0-255)"
TAIL_BYTES = 65536  # searched for an end marker at the end of a file


def _decode(path: Path) -> np.ndarray | None:
    """The image in a file, or None where it cannot be read; colour made grey by OpenCV's weights. Pillow
    decodes (on damaged data it raises, where OpenCV's decoders print to stderr from any thread)."""
    try:
        with Image.open(path) as im:
            im.load()
            if im.mode == "L" or im.mode.startswith(("I", "F")):  # 8-bit grey; deeper ones are refused
                return np.asarray(im)
            return cv2.cvtColor(np.asarray(im.convert("RGBA")), cv2.COLOR_RGBA2GRAY)
    except Exception:  # whatever Pillow raises on a file it cannot decode: our one line says so
        return None


def load_image(path: Path, frame: int) -> np.ndarray:
    """An 8-bit grey image (colour made grey, 16 bits refused); else :class:`SequenceError`."""
    where = f"{path}, frame {frame}"
    img = _decode(path)
    if img is None or img.size == 0:
        raise SequenceError(f"{where}: cannot read the image (empty, truncated, damaged or not an image)")
    if img.dtype != np.uint8:
        raise SequenceError(f"{where}: {img.dtype} image; {NOT_8_BIT}")
    return img


def _png_header(head: bytes, where: str) -> tuple[int, int, int]:
    """``(width, height, bit depth)`` from a PNG's first 33 bytes."""
    if len(head) < 33 or head[12:16] != b"IHDR":
        raise SequenceError(f"{where}: damaged PNG header (no IHDR chunk)")
    width, height = struct.unpack(">II", head[16:24])
    _check_size(where, "PNG", width, height)
    if head[25] not in PNG_COLOUR_TYPES:
        raise SequenceError(f"{where}: damaged PNG header (colour type {head[25]})")
    return width, height, head[24]


def _check_size(where: str, kind: str, width: int, height: int) -> None:
    """One line unless the image is within :data:`MAX_IMAGE_SIDE` a side and :data:`MAX_IMAGE_PIXELS`."""
    if (
        not (0 < width <= MAX_IMAGE_SIDE and 0 < height <= MAX_IMAGE_SIDE)
        or width * height > MAX_IMAGE_PIXELS
    ):
        raise SequenceError(
            f"{where}: the {kind} header claims {width}x{height} pixels; expected each side "
            f"1..{MAX_IMAGE_SIDE} and {MAX_IMAGE_PIXELS / 1e6:.0f} million pixels at most"
        )


def image_header(path: Path, frame: int) -> tuple[int, int, int]:
    """``(width, height, bits per channel)`` of an image file, without decoding where possible."""
    where = f"{path}, frame {frame}"
    try:
        with open(path, "rb") as fh:
            head, size = fh.read(33), fh.seek(0, 2)
            if size == 0:
                raise SequenceError(f"{where}: empty file; expected an image")
            kind, marker = ("PNG", PNG_END) if head.startswith(PNG_SIGNATURE) else ("JPEG", JPEG_END)
            header = _png_header(head, where) if kind == "PNG" else None
            fh.seek(max(0, size - TAIL_BYTES))  # the end marker, trailing bytes allowed after it
            if (kind == "PNG" or head.startswith(JPEG_START)) and marker not in fh.read():
                what = "end chunk" if kind == "PNG" else "end marker"
                raise SequenceError(f"{where}: truncated {kind} (no {what}); expected a complete image")
    except OSError as exc:
        raise SequenceError(f"{where}: cannot open the image ({exc.strerror or exc})") from None
    return header or _header_other(path, where)


def _header_other(path: Path, where: str) -> tuple[int, int, int]:
    """Header of a non-PNG image through Pillow's lazy open (nothing decoded)."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # a damaged file's warnings: the error is one line of ours
            with Image.open(path) as im:
                (width, height), mode = im.size, im.mode
    except Exception:  # whatever Pillow raises on a file it cannot read
        raise SequenceError(f"{where}: cannot read the image (damaged or not an image)") from None
    _check_size(where, im.format or "image", width, height)
    return width, height, 8 if mode in EIGHT_BIT_MODES else 16 if mode.startswith("I;16") else 32  # F, I: 32


def frame_order(name: str) -> tuple:
    """Sort key of an image name: the numbers in it compared as numbers (``2.png`` < ``10.png``)."""
    parts = re.split(r"([0-9]+)", name)  # text, number, text, number, ..., text
    return tuple(int(part) if k % 2 else part for k, part in enumerate(parts))


def _is_image(entry: os.DirEntry) -> bool:
    """Whether a folder entry is an image file; a dangling link of an image's name raises."""
    if entry.name.startswith(".") or os.path.splitext(entry.name)[1].lower() not in IMAGE_SUFFIXES:
        return False
    if not entry.is_file():
        if entry.is_symlink() and not os.path.exists(entry.path):
            target = os.readlink(entry.path)
            raise SequenceError(f"{entry.path}: a symbolic link to {target}, which does not exist")
        what = "a folder" if entry.is_dir() else "a device, pipe or socket"
        raise SequenceError(f"{entry.path}: {what} named like an image; expected an image file")
    if not re.search(r"[0-9]", entry.name):
        raise SequenceError(
            f"{entry.path}: no frame number in the name; name each image by its frame "
            "(000000.png, 000001.png, ...) or move it out of the folder"
        )
    return True


#: The layouts a sequence folder may have, as an error message names them.
LAYOUTS = "expected image_0/ and image_1/ (KITTI), mav0/ (EuRoC/ASL) or image_00/data/ (a KITTI raw drive)"


def _check_image_folder(folder: Path) -> None:
    """One line unless ``folder`` is a folder."""
    if folder.exists() and not folder.is_dir():
        raise SequenceError(f"{folder}: a file where the image folder should be; expected a folder of images")
    if not folder.is_dir():  # image_0/image_0: --sequence named the image folder itself
        hint = f"; give the folder holding {folder.name}" if folder.parent.name == folder.name else ""
        colour = folder.name == "image_0" and (folder.parent / "image_2").is_dir()  # KITTI's colour set
        if not hint and colour:
            hint = "; KITTI's colour pair image_2, image_3 is there: the grey pair image_0, image_1 is read"
        if not hint and not (folder.parent / "image_1").exists():  # no sequence there at all
            hint = f"; {folder.parent} holds no sequence: {LAYOUTS}"
        raise SequenceError(f"{folder}: missing image folder{hint}")


def image_files(folder: Path) -> list[Path]:
    """The images of ``folder`` in frame order; a name without a frame number, a dangling link or
    two names of one frame number raise :class:`SequenceError`."""
    _check_image_folder(folder)
    try:
        with os.scandir(folder) as entries:
            keyed = sorted((frame_order(e.name), e.name) for e in entries if _is_image(e))
    except OSError as exc:
        raise SequenceError(f"{folder}: cannot list the images ({exc.strerror or exc})") from None
    for (key_a, a), (key_b, b) in zip(keyed, keyed[1:], strict=False):
        if key_a == key_b:
            raise SequenceError(f"{folder}: {a} and {b} carry the same frame number; keep one file per frame")
    # one pattern of names, or the order is the names' text (x000003.png would follow 000099.png)
    patterns = [re.sub(r"[0-9]+", "#", name) for _, name in keyed]
    if odd := next((k for k, pattern in enumerate(patterns) if pattern != patterns[0]), None):
        raise SequenceError(
            f"{folder}: {keyed[odd][1]!r} is named unlike {keyed[0][1]!r}; expected every image named "
            "alike but for its frame number, which sets the order"
        )
    return [folder / name for _, name in keyed]


def unpaired(left: list[Path], right: list[Path], sides: tuple[str, str] = ("image_0", "image_1")) -> str:
    """What keeps two image lists (of folders ``sides``) from pairing by name: their counts and the
    lonely names."""
    names_l, names_r = {p.name for p in left}, {p.name for p in right}
    lonely = [f"{sides[0]}/{n}" for n in names_l - names_r] + [f"{sides[1]}/{n}" for n in names_r - names_l]
    lonely.sort(key=lambda s: frame_order(s.rsplit("/", 1)[1]))
    listed = ", ".join(lonely[:4]) + (f" and {len(lonely) - 4} more" if len(lonely) > 4 else "")
    counts = f"{sides[0]} has {len(left)} images but {sides[1]} has {len(right)}; " * (
        len(left) != len(right)
    )
    return f"{counts}{len(lonely)} image(s) without a partner of the same name on the other side: {listed}"


def check_headers(left: list[Path], right: list[Path]) -> tuple[int, int]:
    """Width and height of every image, from the headers; raises on one unreadable, not 8-bit or of
    another size."""
    size = None
    for k, path in enumerate(p for pair in zip(left, right, strict=True) for p in pair):
        width, height, depth = image_header(path, k // 2)
        if depth > 8:
            raise SequenceError(f"{path}, frame {k // 2}: {depth}-bit image; {NOT_8_BIT}")
        size = size or (width, height)
        if (width, height) != size:
            raise SequenceError(
                f"{path}, frame {k // 2}: {width}x{height} image, but {left[0]} is {size[0]}x{size[1]}; "
                "every image of a sequence must have one size"
            )
    return size
