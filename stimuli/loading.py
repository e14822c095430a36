"""Loading a CLIP the same way everywhere: a built-in name, a BVH path, joint
positions (``.npy``/``.npz`` with a layout) or an AMASS/SMPL ``.npz`` (with the
user's body model)."""
from __future__ import annotations

from pathlib import Path

from flipstudy.errors import FlipstudyFileNotFoundError

#: file suffixes read as joint positions or SMPL parameters (every other file is read as BVH)
POSITION_SUFFIXES = (".npy", ".npz")


def load_clip(spec: str, scale: float | None = None, fps: float | None = None, *,
              layout=None, up: str | None = None, body_model=None, gate: bool = True):
    """A clip by name: a built-in name (backflip, frontflip, jump), a BVH path, a
    joint-position ``.npy``/``.npz`` (F, J, 3) or an AMASS/SMPL ``.npz``.
    The same loading rules for every command: ``scale`` (metres per file unit;
    default guessed) and ``fps`` (default: the file's) override the file; ``layout``
    (a name such as ``humanml3d-22`` or a layout file), ``up`` (``"y"``/``"z"``) and
    ``body_model`` (the user's SMPL-family ``.npz``) are for the position and SMPL
    readers (see :func:`flipstudy.stimuli.motion.positions.load_positions`).

    A position or SMPL clip passes the physics gate (``gate``; see :func:`physics_gate`):
    its apparent gravity and body height must agree with physics, else a
    :class:`~flipstudy.errors.MotionFileError` names the fix.  A name that is
    nothing of the above raises :class:`~flipstudy.errors.FlipstudyFileNotFoundError`.

    >>> from flipstudy.stimuli import load_clip
    >>> load_clip("backflip", fps=60).fps
    60.0
    """
    from .motion import load_bvh          # the modules, not this package's __init__ (which imports us)
    from .synth import BUILTIN_NAMES, builtin
    if spec in BUILTIN_NAMES:
        clip = builtin(spec, **({"fps": fps} if fps else {}))
        if scale not in (None, 1.0):
            clip = clip.scaled(scale)
        return clip
    p = Path(spec)
    if not p.exists():
        raise FlipstudyFileNotFoundError(f"{spec}: neither a built-in clip ({', '.join(BUILTIN_NAMES)}) "
                                         f"nor an existing BVH, joint-position (.npy/.npz) or AMASS "
                                         f"(.npz) file")
    if p.suffix.lower() in POSITION_SUFFIXES:
        from .motion.positions import load_positions
        clip = load_positions(p, scale=scale, fps=fps, layout=layout, up=up, body_model=body_model)
        if gate:
            physics_gate(clip)
        return clip
    return load_bvh(p, scale=scale, fps=fps)


def physics_gate(clip) -> None:
    """Refuse a position or SMPL clip that physics contradicts, naming the fix as
    options: a body lying along a horizontal axis (the up axis is wrong: ``--up``),
    a body height outside an adult's, or an apparent gravity in flight that is not
    9.81 m/s² (``--scale``, ``--fps``; see :func:`flipstudy.stimuli.analyse.physics_advice`)."""
    from flipstudy.errors import MotionFileError
    from .analyse import analyse, physics_advice
    check_up_axis(clip)
    a = analyse(clip, estimate=False)
    adv = physics_advice(a.apparent_gravity, clip)
    if adv is not None:
        fix = adv.options()
        where = clip.meta.get("path", clip.meta.get("name", "clip"))
        raise MotionFileError(f"{where}: {adv.problem}" + (f" Rerun with {fix}." if fix else ""))


def check_up_axis(clip) -> None:
    """Refuse a clip whose body spreads less vertically than horizontally over the
    clip (on average over frames, by a factor 0.6): it lies down, so a position or
    AMASS file was read with the wrong up axis; the message names ``--up``."""
    from flipstudy.errors import MotionFileError
    where = clip.meta.get("path", clip.meta.get("name", "clip"))
    X = clip.joint_positions()
    extent = (X.max(axis=1) - X.min(axis=1)).mean(axis=0)            # mean (x, y, z) spread
    if extent[1] < 0.6 * max(extent[0], extent[2]):
        other = "z" if clip.meta.get("up", "y") == "y" else "y"
        raise MotionFileError(
            f"{where}: read with up axis {clip.meta.get('up', 'y')!r}, the body spreads "
            f"{extent[1]:.2f} m vertically but {max(extent[0], extent[2]):.2f} m horizontally: it lies "
            f"down, so the up axis is probably wrong; rerun with --up {other} (a design's source: "
            f"`flipstudy convert {where} --up {other} --out FILE.bvh` first)")
