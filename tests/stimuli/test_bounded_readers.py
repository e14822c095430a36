"""Issue 45, items 12 and 15 and the position readers' tracebacks: every ``.npy``,
``.npz``, layout, AMASS and body-model file is bounded (frames, bytes) and checked
(real, finite, in range) before it is used, and each bad one gives one
:class:`~flipstudy.errors.MotionFileError`-family line naming the file and the field."""
from __future__ import annotations

import io
import json

import numpy as np
import pytest
from numpy.lib import format as npformat

from _bad_files import POSITIONS, bad_crc, deep_json, npy_bytes, npy_header_only, zip_of
from _positions import synthetic_body_model
from flipstudy.errors import FlipstudyError
from flipstudy.stimuli import load_clip


def _layout(tmp, text: str | bytes, name: str = "l.json"):
    p = tmp / name
    p.write_bytes(text if isinstance(text, bytes) else text.encode())
    np.save(tmp / "m.npy", np.zeros((30, 2, 3)))
    return tmp / "m.npy", {"layout": str(p)}, name


def _amass(tmp, **over):
    model, _ = synthetic_body_model()
    np.savez(tmp / "model.npz", **model)
    d = {"poses": np.zeros((30, 156)), "trans": np.zeros((30, 3)), "betas": np.zeros(10),
         "mocap_framerate": np.float64(60.0), **over}
    np.savez(tmp / "a.npz", **d)
    return tmp / "a.npz", {"body_model": str(tmp / "model.npz")}, "a.npz"


def _header_bytes(shape) -> bytes:
    b = io.BytesIO()
    npformat.write_array_header_1_0(b, {"descr": "<f8", "fortran_order": False, "shape": shape})
    return b.getvalue() + bytes(64)


def _file(tmp, name, write):
    p = tmp / name
    write(p)
    return p, {}, name


CASES = {
    # item 12: sizes refused from the header, before anything is allocated
    "header claims 10^12 frames": (lambda t: _file(t, "big.npy", lambda p: npy_header_only(p, (10**12, 22, 3))),
                                   r"big\.npy: .*1,000,000,000,000 frames, more than the 100,000"),
    "header of 10^6 frames": (lambda t: _file(t, "m6.npy", lambda p: npy_header_only(p, (10**6, 22, 3), "<f4")),
                              r"m6\.npy: .*1,000,000 frames"),
    "header of 100,000 frames of 30 joints": (
        lambda t: _file(t, "wide.npy", lambda p: npy_header_only(p, (100_000, 30, 3))),
        r"wide\.npy: .*100,000 frames × 30 joints = 3,000,000 joint-frames, more than the 2,500,000"),
    "npz whose array header claims more than the bytes limit": (
        lambda t: _file(t, "bomb.npz", lambda p: zip_of(p, {"joints.npy": _header_bytes((2_000, 1_000, 20))})),
        r"bomb\.npz: the file's array 'joints': an array of shape \(2000, 1000, 20\) \(305 MiB\), more than "
        r"the 256 MiB"),
    # tracebacks on main
    "npz with an object array under joints": (
        lambda t: _file(t, "o.npz", lambda p: zip_of(p, {"joints.npy": np.array([{"a": 1}], dtype=object)})),
        r"o\.npz: cannot read the file's array 'joints' without unpickling"),
    "npz with an object array under fps": (
        lambda t: _file(t, "of.npz", lambda p: zip_of(p, {"joints.npy": POSITIONS,
                                                         "fps.npy": np.array([None], dtype=object)})),
        r"of\.npz: cannot read the file's array 'fps' without unpickling"),
    "truncated npz": (lambda t: _file(t, "tr.npz", lambda p: (zip_of(p, {"joints.npy": POSITIONS}),
                                                            p.write_bytes(p.read_bytes()[:len(p.read_bytes()) // 2]))),
                      r"tr\.npz: not a readable \.npz file"),
    "npz with a bad CRC": (lambda t: _file(t, "crc.npz", lambda p: bad_crc(p, POSITIONS)),
                           r"crc\.npz: the file's array 'joints' is damaged"),
    "npz without any npy": (lambda t: _file(t, "none.npz", lambda p: zip_of(p, {"readme.txt": b"hello"})),
                            r"none\.npz: an \.npz file without any \.npy array"),
    "garbage npy header": (lambda t: _file(t, "g.npy", lambda p: p.write_bytes(b"\x93NUMPY\x01\x00\x10\x00{'descr': ]]]]}\n")),
                           r"g\.npy: the \.npy header is not readable"),
    "fps a string": (lambda t: _file(t, "s.npz", lambda p: zip_of(p, {"joints.npy": POSITIONS,
                                                                    "fps.npy": np.array("fast")})),
                     r"s\.npz: fps: holds <U4; expected numbers"),
    "fps complex": (lambda t: _file(t, "c.npz", lambda p: zip_of(p, {"joints.npy": POSITIONS,
                                                                   "fps.npy": np.array(30 + 1j)})),
                    r"c\.npz: fps: holds complex numbers"),
    "fps a vector": (lambda t: _file(t, "v.npz", lambda p: zip_of(p, {"joints.npy": POSITIONS,
                                                                    "fps.npy": np.array([30.0, 60.0])})),
                     r"v\.npz: fps: an array of shape \(2,\); expected one number"),
    "AMASS mocap_framerate a vector": (lambda t: _amass(t, mocap_framerate=np.array([60.0, 120.0])),
                                       r"a\.npz: mocap_framerate: an array of shape \(2,\)"),
    "layout landmark a list": (lambda t: _layout(t, json.dumps({"joints": ["a", "b"], "parents": [-1, 0],
                                                                "fps": 30, "landmarks": {"neck": ["b"]}})),
                               r"l\.json: landmarks\.neck = \['b'\]: not one of the layout's joints"),
    "layout deep JSON": (lambda t: _layout(t, deep_json()), r"l\.json: not a readable layout file"),
    "layout not UTF-8": (lambda t: _layout(t, b'{"joints": ["\xff\xfe"], "parents": [-1]}'),
                         r"l\.json: not UTF-8 text"),
    "layout fps Infinity": (lambda t: _layout(t, '{"joints": ["a", "b"], "parents": [-1, 0], "fps": Infinity}'),
                            r"l\.json: fps = inf: expected a number between 1 and 10000"),
    # item 15: range checks
    "layout fps 1e9": (lambda t: _layout(t, '{"joints": ["a", "b"], "parents": [-1, 0], "fps": 1e9}'),
                       r"l\.json: fps = 1000000000\.0: expected a number between 1 and 10000"),
    "complex positions": (lambda t: _file(t, "cx.npy", lambda p: np.save(p, POSITIONS + 1j)),
                          r"cx\.npy: complex positions"),
    "positions far beyond any body": (lambda t: _file(t, "far.npy", lambda p: np.save(p, POSITIONS + 1e200)),
                                      r"far\.npy: positions reach .* m from the origin"),
    # misleading messages on main
    "truncated npy": (lambda t: _file(t, "t.npy", lambda p: p.write_bytes(
        npy_bytes(POSITIONS)[:500])),
        r"t\.npy: the file ends after \d+ of the 15,840 bytes its header promises \(a truncated file\)"),
    "text file named npy": (lambda t: _file(t, "txt.npy", lambda p: p.write_text("1 2 3\n4 5 6\n")),
                            r"txt\.npy: not a readable \.npy/\.npz file: it does not start with numpy's"),
    "BVH named npy": (lambda t: _file(t, "b.npy", lambda p: p.write_text("HIERARCHY\nROOT Hips\n{\n")),
                      r"b\.npy: not a readable \.npy/\.npz file: it reads as a BVH file"),
    "text file as body model": (lambda t: (lambda r: (r[0], {"body_model": str(t / "model.txt")}, "model.txt"))(
        (_amass(t), (t / "model.txt").write_text("not a model"))[0]),
        r"model\.txt: not a readable \.npz body model"),
}


@pytest.mark.parametrize("case", list(CASES))
def test_a_bad_motion_file_is_one_line_naming_the_file_and_field(case, tmp_path):
    build, expect = CASES[case]
    path, kwargs, name = build(tmp_path)
    with pytest.raises(FlipstudyError, match=expect) as e:
        load_clip(str(path), **kwargs)
    msg = str(e.value)
    assert "\n" not in msg and name in msg
    assert "unpickling" not in msg or "object" in msg


def test_the_limits_leave_room_for_a_long_real_capture():
    """A 10-minute 120 fps capture (72,000 frames) of 22 joints fits the limits."""
    from flipstudy.stimuli.motion._npyio import MAX_ARRAY_BYTES, MAX_JOINT_FRAMES, MAX_POSITION_FRAMES
    assert MAX_POSITION_FRAMES >= 72_000 and 72_000 * 22 <= MAX_JOINT_FRAMES
    assert 72_000 * 22 * 3 * 8 <= MAX_ARRAY_BYTES


def test_an_npz_within_the_limits_still_loads(tmp_path):
    """The bounded reader reads what numpy.savez writes (C and Fortran order, float32)."""
    from flipstudy.stimuli.motion._npyio import load_npy, load_npz
    a = np.arange(2 * 22 * 3, dtype=np.float32).reshape(2, 22, 3)
    np.savez_compressed(tmp_path / "a.npz", joints=a, fps=np.float64(30))
    d = load_npz(tmp_path / "a.npz", ["joints", "fps"])
    assert np.array_equal(d["joints"], a) and float(d["fps"]) == 30.0
    np.save(tmp_path / "f.npy", np.asfortranarray(a))
    assert np.array_equal(load_npy(tmp_path / "f.npy"), a)
