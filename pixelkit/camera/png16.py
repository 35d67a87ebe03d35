"""A minimal PNG writer for 16-bit (or 8-bit) grayscale images: no imaging library needed.

PNG: signature, IHDR (width, height, bit depth, colour type 0 = grayscale), one
zlib-compressed IDAT of rows each prefixed by filter byte 0, IEND; every chunk
carries a CRC-32. Samples are big-endian.
"""
from __future__ import annotations

import struct
import zlib

import numpy as np


def _chunk(kind: bytes, data: bytes) -> bytes:
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)


def png_bytes(image, bits: int = 16) -> bytes:
    """The PNG file of a 2-D array of non-negative integers below 2**bits (8 or 16)."""
    a = np.asarray(image)
    if a.ndim != 2 or bits not in (8, 16):
        raise ValueError("a 2-D image and a bit depth of 8 or 16")
    if a.size and (a.min() < 0 or a.max() >= 2 ** bits):
        raise ValueError(f"pixel values outside 0 .. {2 ** bits - 1}")
    h, w = a.shape
    rows = a.astype(">u2" if bits == 16 else "u1")
    raw = b"".join(b"\x00" + rows[r].tobytes() for r in range(h))
    return (b"\x89PNG\r\n\x1a\n" + _chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, bits, 0, 0, 0, 0))
            + _chunk(b"IDAT", zlib.compress(raw, 6)) + _chunk(b"IEND", b""))
