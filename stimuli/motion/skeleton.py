"""The skeleton: joint names, parents, rest offsets and the channel layout as read.

Conventions (stated once, as scipy's ``Rotation`` does):

* joints are stored in topological order: ``parents[j] < j`` for every joint but
  the root, whose parent is ``-1``;
* ``offsets[j]`` is the rest translation of joint ``j`` in its parent's frame, in
  metres (the readers convert units at the edge);
* ``euler_orders[j]`` is the order of the joint's rotation channels as listed in
  the file, upper case, e.g. ``"ZYX"``; BVH Euler angles are *intrinsic*, so the
  local rotation is ``Rotation.from_euler(order, angles)`` with that upper-case
  (intrinsic) order;
* ``end_sites`` are kept as ``(parent joint, offset)`` pairs so a writer can put
  them back and a body model can use them as segment tips.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

ROTATION_CHANNELS = ("Xrotation", "Yrotation", "Zrotation")
POSITION_CHANNELS = ("Xposition", "Yposition", "Zposition")


@dataclass(frozen=True, eq=False)
class Skeleton:
    """A joint hierarchy.

    Parameters
    ----------
    joint_names : list of str
        Unique joint names, parents before children.
    parents : array_like of int, shape (J,)
        Parent index of each joint (-1 for the root).
    offsets : array_like, shape (J, 3)
        Rest offset of each joint from its parent, metres.
    channels : list of tuple of str, optional
        Each joint's BVH channels as read (default: root position and rotation,
        rotations elsewhere).
    end_sites : list of (int, ndarray)
        BVH end sites: the joint and the offset of its end.

    Examples
    --------
    >>> sk = Skeleton(["Hips", "Spine"], [-1, 0], [[0, 0, 0], [0, 0.1, 0]])
    >>> sk.num_joints, sk.index("Spine")
    (2, 1)
    """

    joint_names: list[str]
    parents: np.ndarray
    offsets: np.ndarray
    channels: list[tuple[str, ...]] = field(default=None)  # type: ignore[assignment]
    end_sites: list[tuple[int, np.ndarray]] = field(default_factory=list)

    def __post_init__(self):
        names = list(self.joint_names)
        parents = np.asarray(self.parents, dtype=np.int64).reshape(-1)
        offsets = np.asarray(self.offsets, dtype=np.float64).reshape(-1, 3)
        J = len(names)
        if parents.shape[0] != J or offsets.shape[0] != J:
            raise ValueError(
                f"Skeleton: {J} joint names but {parents.shape[0]} parents and "
                f"{offsets.shape[0]} offsets")
        if J == 0:
            raise ValueError("Skeleton: no joints")
        if parents[0] != -1 or np.any(parents[1:] < 0) or np.any(parents[1:] >= np.arange(1, J)):
            raise ValueError("Skeleton: joints must be in topological order with the root first "
                             "(parents[0] == -1 and 0 <= parents[j] < j)")
        if len(set(names)) != J:
            dup = sorted({n for n in names if names.count(n) > 1})
            raise ValueError(f"Skeleton: duplicate joint names {dup}")
        channels = self.channels
        if channels is None:
            channels = [POSITION_CHANNELS + ("Zrotation", "Yrotation", "Xrotation")] + \
                [("Zrotation", "Yrotation", "Xrotation")] * (J - 1)
        channels = [tuple(c) for c in channels]
        if len(channels) != J:
            raise ValueError(f"Skeleton: {len(channels)} channel lists for {J} joints")
        for name, ch in zip(names, channels):
            rot = [c for c in ch if c in ROTATION_CHANNELS]
            if len(rot) not in (0, 3) or len(set(rot)) != len(rot):
                raise ValueError(f"Skeleton: joint {name!r} needs 0 or 3 distinct rotation "
                                 f"channels, has {list(ch)}")
        ends = [(int(p), np.asarray(o, dtype=np.float64).reshape(3)) for p, o in self.end_sites]
        object.__setattr__(self, "joint_names", names)
        object.__setattr__(self, "parents", parents)
        object.__setattr__(self, "offsets", offsets)
        object.__setattr__(self, "channels", channels)
        object.__setattr__(self, "end_sites", ends)
        parents.setflags(write=False)
        offsets.setflags(write=False)
        object.__setattr__(self, "_index", {n: i for i, n in enumerate(names)})

    # ------------------------------------------------------------------ basics
    @property
    def num_joints(self) -> int:
        return len(self.joint_names)

    def index(self, name: str) -> int:
        """Index of a joint by name (``KeyError`` naming the joint if absent)."""
        try:
            return self._index[name]
        except KeyError:
            raise KeyError(f"no joint named {name!r} in skeleton") from None

    def __contains__(self, name: str) -> bool:
        return name in self._index

    @property
    def euler_orders(self) -> list[str]:
        """Rotation-channel order per joint as read, e.g. ``"ZYX"`` ('' if none)."""
        return ["".join(c[0] for c in ch if c in ROTATION_CHANNELS) for ch in self.channels]

    @property
    def has_position(self) -> np.ndarray:
        """(J,) bool: joints that carry position channels."""
        return np.array([any(c in POSITION_CHANNELS for c in ch) for ch in self.channels])

    @property
    def num_channels(self) -> int:
        return sum(len(c) for c in self.channels)

    def children(self, j: int) -> np.ndarray:
        return np.nonzero(self.parents == j)[0]

    def depth(self) -> np.ndarray:
        """(J,) depth of each joint (root 0)."""
        d = np.zeros(self.num_joints, dtype=np.int64)
        for j in range(1, self.num_joints):
            d[j] = d[self.parents[j]] + 1
        return d

    def levels(self) -> list[np.ndarray]:
        """Joint indices grouped by depth: FK processes one level at a time."""
        d = self.depth()
        return [np.nonzero(d == k)[0] for k in range(int(d.max()) + 1)]

    def path_to_root(self, j: int) -> list[int]:
        out = [j]
        while self.parents[out[-1]] >= 0:
            out.append(int(self.parents[out[-1]]))
        return out

    def common_ancestor(self, a: int, b: int) -> int:
        """Lowest common ancestor of joints ``a`` and ``b``."""
        pb = set(self.path_to_root(b))
        return next(j for j in self.path_to_root(a) if j in pb)

    def end_sites_of(self, j: int) -> list[np.ndarray]:
        return [o for p, o in self.end_sites if p == j]

    def scaled(self, s: float) -> "Skeleton":
        """The same skeleton with every length multiplied by ``s``."""
        return Skeleton(self.joint_names, self.parents, self.offsets * s, self.channels,
                        [(p, o * s) for p, o in self.end_sites])

    def rest_positions(self) -> np.ndarray:
        """(J,3) joint positions of the rest pose (all rotations identity)."""
        P = np.zeros((self.num_joints, 3))
        P[0] = self.offsets[0]
        for j in range(1, self.num_joints):
            P[j] = P[self.parents[j]] + self.offsets[j]
        return P

    def rest_height(self) -> float:
        """Vertical extent of the rest pose, end sites included (file units)."""
        P = self.rest_positions()
        ys = [P[:, 1]]
        if self.end_sites:
            ys.append(np.array([P[p, 1] + o[1] for p, o in self.end_sites]))
        y = np.concatenate(ys)
        return float(y.max() - y.min())

    def __repr__(self) -> str:
        return f"Skeleton({self.num_joints} joints, root={self.joint_names[0]!r})"
