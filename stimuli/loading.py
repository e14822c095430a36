"""Loading a CLIP the same way everywhere: a built-in name, a BVH path, joint
positions (``.npy``/``.npz`` with a layout) or an AMASS/SMPL ``.npz`` (with the
user's body model)."""
from __future__ import annotations

from pathlib import Path

from flipstudy.errors import FlipstudyFileNotFoundError

#: file suffixes read as joint positions or SMPL parameters (every other file is read as BVH)
POSITION_SUFFIXES = (".npy", ".npz")


def load_clip(spec: str, scale: float | None = None, fps: float | None = None,
              accept_unphysical: bool = False, check: bool = True, *,
              layout=None, up: str | None = None, body_model=None, gate: bool = True):
    """A clip by name: a built-in name (backflip, frontflip, jump), a BVH path, a
    joint-position ``.npy``/``.npz`` (F, J, 3) or an AMASS/SMPL ``.npz``.
    The same loading rules for every command: ``scale`` (metres per file unit;
    default guessed) and ``fps`` (default: the file's) override the file; ``layout``
    (a name such as ``humanml3d-22`` or a layout file), ``up`` (``"y"``/``"z"``) and
    ``body_model`` (the user's SMPL-family ``.npz``) are for the position and SMPL
    readers (see :func:`flipstudy.stimuli.motion.positions.load_positions`).

    Every clip then passes the one physics gate: its apparent gravity and body height
    must agree with physics, else an error names the fix (``--fps``, ``--scale``,
    ``--up``) and ``accept_unphysical`` (``--accept-unphysical``), the way past it.
    A BVH clip is judged by :func:`checked_clip`
    (:class:`~flipstudy.errors.UnphysicalClipError`), a position or SMPL clip by
    :func:`check_up_axis` and :func:`physics_gate`
    (:class:`~flipstudy.errors.MotionFileError`).  ``check=False`` (or ``gate=False``)
    skips the gate: ``inspect``, which reports the same findings as warnings, and a
    design's clips, which the design's own gate judges.  A name that is nothing of
    the above raises :class:`~flipstudy.errors.FlipstudyFileNotFoundError`.

    Parameters
    ----------
    spec : str
        A built-in name, or the path of a BVH, joint-position or AMASS/SMPL file.
    scale : float, optional
        Metres per file unit; default: guessed from the flight (BVH) or 1.0.
    fps : float, optional
        Frames per second, overriding the file's.
    accept_unphysical : bool, default False
        Use a clip the physics gate would refuse as it is (``--accept-unphysical``).
    check : bool, default True
        Run the physics gate; False reports nothing and refuses nothing.
    layout : str, optional
        A position array's joints: a layout name (``humanml3d-22``) or a layout file.
    up : {"y", "z"}, optional
        The up axis of a position or AMASS file.
    body_model : str or pathlib.Path, optional
        The user's SMPL-family body model (``.npz``), needed for an AMASS file.
    gate : bool, default True
        The same as ``check`` (both must be true for the gate to run).

    Returns
    -------
    Clip

    Raises
    ------
    FlipstudyFileNotFoundError
        When ``spec`` is neither a built-in name nor an existing file.
    BVHError
        For a malformed BVH file (naming its line).
    MotionFileError
        For a position or AMASS file that is not what its reader expects, or that
        physics contradicts (naming the fix).
    UnphysicalClipError
        For a BVH or built-in clip that physics contradicts (naming the fix).

    Examples
    --------
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
            return checked_clip(clip, spec, accept_unphysical) if check else clip
        return clip                         # physically exact at any fps
    p = Path(spec)
    if not p.exists():
        from ._io import missing_file_hint
        raise FlipstudyFileNotFoundError(f"{spec}: neither a built-in clip ({', '.join(BUILTIN_NAMES)}) "
                                         f"nor an existing BVH, joint-position (.npy/.npz) or AMASS "
                                         f"(.npz) file ({missing_file_hint(p, spec, also=BUILTIN_NAMES)})")
    check = check and gate
    if p.suffix.lower() in POSITION_SUFFIXES:
        from .motion.positions import load_positions
        clip = load_positions(p, scale=scale, fps=fps, layout=layout, up=up, body_model=body_model)
        if check:
            check_up_axis(clip)                      # a body lying down: the wrong --up
            if not accept_unphysical:
                physics_gate(clip)
        return clip
    clip = load_bvh(p, scale=scale, fps=fps)
    return checked_clip(clip, spec, accept_unphysical) if check else clip


def physics_gate(clip) -> None:
    """The gate of a position or SMPL clip: refuse one that physics contradicts, naming
    the fix as options: a body lying along a horizontal axis (the up axis is wrong:
    ``--up``), a body height outside an adult's, or an apparent gravity in flight that
    is not 9.81 m/s² (``--scale``, ``--fps``; see
    :func:`flipstudy.stimuli.analyse.physics_advice`), or ``--accept-unphysical``."""
    from flipstudy.errors import MotionFileError
    from .analyse import analyse, physics_advice
    check_up_axis(clip)
    a = analyse(clip, estimate=False)
    adv = physics_advice(a.apparent_gravity, clip)
    if adv is not None:
        fix = adv.options()
        where = clip.meta.get("path", clip.meta.get("name", "clip"))
        raise MotionFileError(f"{where}: {adv.problem}" + (f" Rerun with {fix}" if fix else "")
                              + ("; or" if fix else "") + " pass --accept-unphysical to use it as it is.")


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


def checked_clip(clip, spec: str, accept_unphysical: bool = False):
    """The physics gate every command that takes a CLIP runs: ``clip`` itself, unless
    physics contradicts it (the apparent gravity of its flight, or the body's height
    from its skeleton; see :func:`flipstudy.stimuli.analyse.physics_advice`); then
    :class:`~flipstudy.errors.UnphysicalClipError` names the options that fix it
    (``--fps``/``--scale``) and ``--accept-unphysical``.

    >>> from flipstudy.stimuli import builtin
    >>> checked_clip(builtin("backflip"), "backflip").fps
    120.0
    """
    if accept_unphysical:
        return clip
    from flipstudy.errors import UnphysicalClipError
    from .analyse import analyse, gravity_warning
    a = analyse(clip, estimate=False)
    msg = gravity_warning(a.apparent_gravity, clip)
    if msg is None:
        return clip
    raise UnphysicalClipError(f"{spec}: {msg.rstrip('.')}; or pass --accept-unphysical to use it as it is.")
