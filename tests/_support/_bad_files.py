"""Malformed and oversized motion inputs (``.npy``, ``.npz``, layout, AMASS, body
model), written into a folder, for the bounded readers' tests and fuzzers."""
from __future__ import annotations

import io
import zipfile
from pathlib import Path

import numpy as np
from numpy.lib import format as npformat


def npy_header_only(path: Path, shape, descr: str = "<f8", sparse_data: bool = False) -> Path:
    """An ``.npy`` whose header claims ``shape``; its data is absent (a truncated file),
    or, with ``sparse_data``, a sparse run of zeros of the full size (no disk used)."""
    with open(path, "wb") as f:
        npformat.write_array_header_1_0(f, {"descr": descr, "fortran_order": False, "shape": tuple(shape)})
        if sparse_data:
            f.truncate(f.tell() + int(np.prod(shape)) * np.dtype(descr).itemsize)
    return path


def npy_bytes(a: np.ndarray) -> bytes:
    b = io.BytesIO()
    npformat.write_array(b, np.asanyarray(a), allow_pickle=True)
    return b.getvalue()


def zip_of(path: Path, members: dict, compress: bool = True) -> Path:
    """An ``.npz``-like zip of ``members`` (name → bytes or array)."""
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED if compress else zipfile.ZIP_STORED) as z:
        for k, v in members.items():
            z.writestr(k, v if isinstance(v, bytes) else npy_bytes(v))
    return path


def zip_bomb(path: Path, shape, name: str = "joints.npy") -> Path:
    """An ``.npz`` holding one float64 array of zeros of ``shape``, deflated (tiny on disk)."""
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as z, z.open(name, "w", force_zip64=True) as f:
        npformat.write_array_header_1_0(f, {"descr": "<f8", "fortran_order": False, "shape": tuple(shape)})
        left = int(np.prod(shape)) * 8
        block = bytes(2**22)
        while left > 0:
            f.write(block[:min(left, len(block))])
            left -= len(block)
    return path


def bad_crc(path: Path, a: np.ndarray) -> Path:
    """A stored (uncompressed) ``.npz`` of ``joints`` with one data byte changed (its CRC then fails)."""
    zip_of(path, {"joints.npy": a}, compress=False)
    raw = bytearray(path.read_bytes())
    at = raw.index(b"NUMPY") + 200
    raw[at] ^= 0xFF
    path.write_bytes(bytes(raw))
    return path


def deep_json(depth: int = 100_000) -> str:
    return '{"joints": ["a", "b"], "parents": [-1, 0], "x": ' + "[" * depth + "]" * depth + "}"


POSITIONS = np.zeros((30, 22, 3))
