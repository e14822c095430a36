"""BVH writing: a clip as BVH text (:func:`bvh_text`) and as a file written
atomically (:func:`save_bvh`), in the layout the reader reads back exactly."""
from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from .._io import atomic_write_text
from .clip import Clip
from .skeleton import POSITION_CHANNELS


def _fmt(x: float) -> str:
    s = f"{x:.9f}".rstrip("0").rstrip(".")
    return "0" if s in ("-0", "") else s


def bvh_text(clip: Clip, scale: float = 1.0) -> str:
    """The BVH text of a clip; lengths are written as metres / ``scale``.

    Parameters
    ----------
    clip : Clip
    scale : float
        Metres per file unit (0.01: centimetres).

    Returns
    -------
    str

    Examples
    --------
    >>> from flipstudy import builtin
    >>> bvh_text(builtin("jump")).splitlines()[:2]
    ['HIERARCHY', 'ROOT Hips']
    """
    sk = clip.skeleton
    J = sk.num_joints
    inv = 1.0 / scale
    jp = clip.joint_pos
    if jp is None:
        # joints other than the root may declare position channels yet hold their OFFSET
        jp = np.broadcast_to(sk.offsets[None], (clip.num_frames, J, 3))
    offsets = sk.offsets * inv
    # joints with position channels: write OFFSET = frame 1 and absolute channels,
    # which the reader's rule reads back unambiguously
    has = sk.has_position.copy()
    has[0] = False
    offsets[has] = jp[0, has] * inv
    # the root: a clip's root_pos is its world position (the skeleton's root offset plays
    # no part in forward kinematics), so write OFFSET 0 + absolute channels; a root without
    # position channels can only carry a fixed position, in its OFFSET
    if sk.has_position[0]:
        offsets[0] = 0.0
    else:
        if not np.allclose(clip.root_pos, clip.root_pos[:1], rtol=0, atol=1e-9):
            raise ValueError("bvh_text: the root moves but has no position channels; give it "
                             "Xposition Yposition Zposition channels before writing")
        offsets[0] = clip.root_pos[0] * inv
    children: list[list[int]] = [[] for _ in range(J)]
    for j in range(1, J):
        children[sk.parents[j]].append(j)
    # the writer walks depth-first, which must reproduce the stored topological order
    dfs: list[int] = []
    todo = [0]
    while todo:
        j = todo.pop()
        dfs.append(j)
        todo.extend(reversed(children[j]))
    if dfs != list(range(J)):
        raise ValueError("bvh_text: skeleton joints are not in depth-first order; "
                         "reorder the skeleton before writing")
    ends: list[list[np.ndarray]] = [[] for _ in range(J)]
    for p, o in sk.end_sites:
        ends[p].append(o * inv)
    out = ["HIERARCHY"]

    def emit(j: int, depth: int):
        ind = "\t" * depth
        out.append(f"{ind}{'ROOT' if j == 0 else 'JOINT'} {sk.joint_names[j]}")
        out.append(f"{ind}{{")
        out.append(f"{ind}\tOFFSET {' '.join(_fmt(v) for v in offsets[j])}")
        if sk.channels[j]:
            out.append(f"{ind}\tCHANNELS {len(sk.channels[j])} {' '.join(sk.channels[j])}")
        for c in children[j]:
            emit(c, depth + 1)
        for o in ends[j]:
            out.append(f"{ind}\tEnd Site")
            out.append(f"{ind}\t{{")
            out.append(f"{ind}\t\tOFFSET {' '.join(_fmt(v) for v in o)}")
            out.append(f"{ind}\t}}")
        out.append(f"{ind}}}")

    emit(0, 0)
    F = clip.num_frames
    body = _motion_rows(clip, jp, inv)
    out.append("MOTION")
    out.append(f"Frames: {F}")
    out.append(f"Frame Time: {1.0 / clip.fps:.10f}")
    return "\n".join(out) + "\n" + body + "\n"


def _motion_rows(clip: Clip, jp: np.ndarray, inv: float) -> str:
    """The MOTION section's rows: per frame every channel, positions in file units
    (``inv`` file units per metre), Euler angles in degrees unwrapped over frames."""
    sk = clip.skeleton
    J = sk.num_joints
    F = clip.num_frames
    cols = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # gimbal-lock warnings: the angles stay valid
        rots = {}
        for order in set(sk.euler_orders):
            if order:
                js = [j for j in range(J) if sk.euler_orders[j] == order]
                e = Rotation.from_quat(clip.rotations[:, js].reshape(-1, 4)).as_euler(order.upper(), degrees=True)
                e = np.unwrap(e.reshape(F, len(js), 3), period=360.0, axis=0)
                for k, j in enumerate(js):
                    rots[j] = e[:, k]
    for j in range(J):
        order = sk.euler_orders[j]
        for ch in sk.channels[j]:
            axis = "XYZ".index(ch[0])
            if ch in POSITION_CHANNELS:
                src = clip.root_pos if j == 0 else jp[:, j]
                cols.append(src[:, axis] * inv)
            else:
                cols.append(rots[j][:, order.index(ch[0])])
    data = np.stack(cols, axis=1) if cols else np.zeros((F, 0))
    data[np.abs(data) < 5e-10] = 0.0
    fmt = " ".join("%.9f" if ch in POSITION_CHANNELS else "%.7f"
                   for ch in (c for chs in sk.channels for c in chs))
    body = "\n".join(fmt % tuple(row) for row in data)
    return body


def save_bvh(clip: Clip, path, scale: float = 1.0) -> Path:
    """Write a clip as BVH (atomically).  Lengths are written in units of ``scale``
    metres (1.0: metres, 0.01: centimetres).  Euler orders and channel layout are
    the skeleton's; the root OFFSET is zero and its channels absolute (a root without
    position channels must stand still: its position is written as its OFFSET).

    Parameters
    ----------
    clip : Clip
        The motion to write.
    path : str or pathlib.Path
        The file to write (replaced atomically: never left half-written).
    scale : float, default 1.0
        Metres per file unit.

    Returns
    -------
    pathlib.Path
        The path written.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> from flipstudy import builtin, save_bvh
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     path = save_bvh(builtin("backflip"), pathlib.Path(tmp) / "backflip.bvh", scale=0.01)
    ...     text = path.read_text()
    >>> text.splitlines()[:2]
    ['HIERARCHY', 'ROOT Hips']
    >>> "Frames: 397" in text
    True
    """
    atomic_write_text(path, bvh_text(clip, scale))
    return Path(path)
