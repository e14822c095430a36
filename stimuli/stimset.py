"""Building a stimulus set from a design: clips, errors, measurement, manifest.

``build_stimuli(design, out)`` writes every stimulus as ``.bvh`` (metres) and
``.npz``, a copy of the design, and ``manifest.csv`` (one row per stimulus: the
nominal error beside the error the analyser measures).  The same design and
seed give a byte-identical manifest (content hashes included).

The folder ``out`` is handled so that a study is never lost:

- A build holds an exclusive lock (``fcntl.flock`` on ``.NAME.lock`` beside
  ``out``) from start to end; a second build into the same ``out`` fails at once
  with :class:`StudyLockedError`.
- The set is built in ``.NAME.tmp-PID-*`` beside ``out`` and swapped into place
  with one atomic ``renameat2(RENAME_EXCHANGE)`` (Linux), so a build killed at
  any moment (even SIGKILL) leaves at ``out`` either the previous complete study
  or the new complete one.  Where the exchange is unavailable the previous study
  is renamed to ``.NAME.old-PID`` first and the next build restores it if
  ``out`` is missing.  Leftovers of killed builds are removed by the next build.
- ``force=True`` replaces only a folder holding nothing but what a build writes
  (``manifest.csv``, ``design.toml`` and the files the manifest lists).  A folder
  holding anything else (``sessions.sqlite``, ``render/``, ``responses.csv``, ...)
  is replaced only if the caller passes ``replace_check``, a function
  ``replace_check(folder, foreign_names)`` that raises to refuse; the
  ``flipstudy stimuli`` command passes one that refuses while the study holds
  any real participant's answer (:func:`flipstudy.study.archive.refuse_real_answers`)
  and returns the files other commands made and recorded that may go with the old
  set.  Every other file, at any depth (the researcher's ``consent.md``,
  ``analysis/``), is kept in the new study (:mod:`.replace`).  The check runs again
  at the moment of the swap, so a study copied to ``out`` while the build runs is
  not deleted either.
"""

from __future__ import annotations

from flipstudy.errors import (DesignError, FlipstudyFileExistsError, FlipstudyFileNotFoundError,
                              StimulusError, StudyFolderError, StudyLockedError)
from flipstudy.results import BuildResult

import ctypes
import errno
import hashlib
import io
import os
import shutil
import sys
import tempfile
import zipfile
from contextlib import contextmanager
from pathlib import Path
from types import SimpleNamespace

import numpy as np

from ._progress import Progress
from .replace import BUILD_FILES, carry, discard_old, kept_files, own_files  # noqa: F401 (BUILD_FILES)
from .analyse import analyse
from .design import GIVEN_KIND, SHARED_ORIGINAL_GROUP, Design, Group, SourceGroup, SourceSpec
from .injection import Injected, check, measure
from .ballistic import check_design_flights
from flipstudy.vocab import kinds
from .ballistic_measure import EXTRA_COLUMNS, measure_ballistic
from .contract import MANIFEST_COLUMNS, StimulusSet  # noqa: F401  (MANIFEST_COLUMNS: re-exported)
from flipstudy.errors import ManifestError
from .motion.bvh import bvh_text, load_bvh
from .motion.clip import Clip



def load_base_clip(spec, design: Design) -> Clip:
    """A design's base clip: a built-in name or a BVH path (relative to the design).

    A BVH clip is read at its entry's ``fps`` (else the header's) and, when the
    design writes ``[study] fps``, resampled to that rate with the project's slerp
    sampler (:func:`flipstudy.stimuli.edit.timing.sample`); ``meta["fps_read"]`` keeps the rate
    it was read at.  With ``flips``, the base clip passes the physics gate
    (:func:`physics_gate`) before it is made an N-flip one."""
    from . import BUILTIN_NAMES, builtin
    where = f"{design.path}: " if design.path is not None else ""
    if spec.source in BUILTIN_NAMES:
        clip = builtin(spec.source, fps=spec.fps or design.fps, total_mass=design.total_mass)
    else:
        p = Path(spec.source)
        if not p.is_absolute() and design.path is not None:
            p = design.path.parent / p
        if not p.exists():
            from ._io import missing_file_hint
            hint = missing_file_hint(p, spec.source, also=BUILTIN_NAMES,
                                     base=design.path.parent if design.path is not None else None)
            raise DesignError(f"{where}clips '{spec.name}': source {spec.source!r} is neither a built-in clip "
                              f"({', '.join(BUILTIN_NAMES)}) nor an existing BVH file ({p}; {hint})")
        from .loading import POSITION_SUFFIXES, check_up_axis, load_clip
        if p.suffix.lower() in POSITION_SUFFIXES:   # joint positions (22: humanml3d-22); the design's gate runs below
            clip = load_clip(str(p), scale=spec.scale, fps=spec.fps, gate=False)
            check_up_axis(clip)
        else:
            clip = load_bvh(p, scale=spec.scale, fps=spec.fps)
        if getattr(design, "fps_given", False) and abs(clip.fps - design.fps) > 1e-9 * design.fps:
            clip = resample(clip, design.fps)
    if getattr(spec, "flips", None):
        from flipstudy.errors import FlipEditError
        from .edit.multiflip import multiflip
        a = analyse(clip, total_mass=design.total_mass)
        physics_gate(spec, a, design)
        try:
            clip = multiflip(a, spec.flips, k_ratio=spec.k_ratio).clip
        except FlipEditError as e:
            raise DesignError(f"{where}clips '{spec.name}': flips = {spec.flips}: {e}") from None
        clip.meta["name"] = spec.name
    return clip


#: a base clip at the design's frame rate: a motion operation, with the others in
#: :mod:`flipstudy.stimuli.edit.reposition`
from .edit.reposition import resample_to as resample  # noqa: E402


def physics_gate(spec, a, design: Design | None = None) -> None:
    """Refuse a base clip that physics contradicts (apparent gravity, or the body's
    height from the skeleton; see :func:`flipstudy.stimuli.analyse.physics_advice`), naming
    the fix as design keys, unless its entry says ``accept_unphysical = true``."""
    from .analyse import physics_advice
    adv = physics_advice(a.apparent_gravity, a.clip)
    if adv is None or getattr(spec, "accept_unphysical", False):
        return
    where = f"{design.path}: " if design is not None and design.path is not None else ""
    fix = adv.keys()
    extra = " or omit scale (it is guessed from the skeleton)" if adv.scale is not None and \
        spec.scale is not None and adv.scale_unit and "1.70 m" not in adv.scale_unit else ""
    raise DesignError(f"{where}clips '{spec.name}' ({spec.source}): {adv.problem} Fix its [[clips]] "
                      f"entry: {fix}{extra}; or set accept_unphysical = true to build it as it is.")


def derived_seed(seed: int, name: str) -> int:
    """A per-stimulus seed derived from the design seed and the stimulus name."""
    return int.from_bytes(hashlib.sha256(f"{seed}:{name}".encode()).digest()[:4], "big")


def npz_bytes(arrays: dict) -> bytes:
    """An ``.npz`` (readable by ``numpy.load``) with fixed zip timestamps, so the
    same arrays always give the same bytes."""
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", compression=zipfile.ZIP_DEFLATED) as z:
        for k in sorted(arrays):
            info = zipfile.ZipInfo(f"{k}.npy", date_time=(1980, 1, 1, 0, 0, 0))
            info.compress_type = zipfile.ZIP_DEFLATED
            b = io.BytesIO()
            np.lib.format.write_array(b, np.asanyarray(arrays[k]), allow_pickle=False)
            z.writestr(info, b.getvalue())
    return buf.getvalue()


def clip_arrays(clip: Clip, takeoff: int, landing: int) -> dict:
    sk = clip.skeleton
    return {"root_pos": clip.root_pos, "rotations": clip.rotations, "fps": np.float64(clip.fps),
            "takeoff": np.int64(takeoff), "landing": np.int64(landing),
            "joint_names": np.array(sk.joint_names), "parents": sk.parents, "offsets": sk.offsets}


#: the pseudo-group of a clip's shared original (level 0 of every sharing group)
SHARED_ORIGINAL = Group(SHARED_ORIGINAL_GROUP, kinds.AM.name, None, 1, [0.0], "shared")


def plan(design: Design) -> list[tuple]:
    """(stimulus name, clip spec, group or None, level) for every stimulus, in
    manifest order: reference clips first, then per clip its shared original
    (group ``original``, when groups share it) and group × level, the sharing
    groups without a level 0 of their own."""
    rows = [(f"{r}_reference", design.clip(r), None, 0.0) for r in design.reference]
    for c in design.clips:
        if design.shares_original:
            rows.append((f"{c.name}_{SHARED_ORIGINAL_GROUP}", c, SHARED_ORIGINAL, 0.0))
        for g in design.groups:
            for lv in g.levels:
                if lv == 0 and g.original == "shared":
                    continue
                rows.append((f"{c.name}_{g.name}_{lv:g}", c, g, lv))
    return rows


def original_of(design: Design, clip_name: str, group) -> str:
    """The stimulus a row's d′ compares with: the clip's shared original, or its
    group's own level 0 ("" for reference rows and groups without one)."""
    if group is None:
        return ""
    if group.original == "shared" and (group is SHARED_ORIGINAL or design.shares_original):
        return f"{clip_name}_{SHARED_ORIGINAL_GROUP}"
    return f"{clip_name}_{group.name}_0" if 0.0 in group.levels else ""


def build_stimuli(design: Design, out, force: bool = False, progress: bool = True,
                  replace_check=None, cluster=None) -> BuildResult:
    """Generate, measure and write the stimulus set of ``design`` into ``out``;
    returns a :class:`~flipstudy.results.BuildResult` (the manifest's rows).

    ``force``: replace an existing ``out`` that holds only a previous build's
    files.  ``replace_check(folder, foreign_names)``: called when ``out`` holds
    anything else; it raises to refuse, returns to allow (see the module
    docstring).  Raises :class:`StudyLockedError` when another build holds ``out``.
    ``cluster``: a :class:`flipstudy.study.cluster.Cluster` that makes the
    stimuli (:func:`make_stimulus`) on its workers, into the same staging folder.
    """
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    with study_lock(out, "build"):
        _recover_and_clean(out)
        if out.exists() or out.is_symlink():
            if not force:
                raise FlipstudyFileExistsError(f"{out} exists; choose another --out or pass --force to replace it")
            _check_replaceable(out, replace_check, out)      # fail before the work, not after
        rows = _build(design, out, force, progress, replace_check, cluster)
    return BuildResult(out=out, rows=tuple(rows), tolerance_pct=design.tolerance_pct)


def _build(design: Design, out: Path, force: bool, progress: bool, replace_check,
           cluster=None) -> list[dict]:
    if design.compares:
        return _build_comparison(design, out, force, progress, replace_check)
    todo = plan(design)
    bar = Progress(len(todo), "stimuli", progress)
    tmp = Path(tempfile.mkdtemp(prefix=f".{out.name}.tmp-{os.getpid()}-", dir=out.parent))
    try:
        base = {}
        for c in design.clips:
            clip = load_base_clip(c, design)
            a = analyse(clip, total_mass=design.total_mass)
            if not c.flips:                      # an N-flip clip's base passed it before the edit
                physics_gate(c, a, design)
            if a.flight is None:
                raise StimulusError(f"clips '{c.name}' ({c.source}): the analyser finds no flight "
                                    f"phase, so it cannot carry the study's errors")
            base[c.name] = a
        check_design_flights(design, base)       # a level that cannot land: refused before any work
        items = [(it, base[it[1].name]) for it in todo]
        if cluster is None:
            rows = []
            for it, a in items:
                rows.append(make_stimulus(design, a, it, tmp))
                bar.step(it[0])
        else:                             # one task per stimulus; rows back in plan order
            rows = cluster.map_stimuli(make_stimulus, design, items, tmp, bar)
        StimulusSet.from_rows(tmp, rows).write()
        if design.path is not None:
            shutil.copyfile(design.path, tmp / "design.toml")
        _install(tmp, out, force, replace_check)
    except BaseException as e:
        if tmp.exists():
            shutil.rmtree(tmp, ignore_errors=True)
        if isinstance(e, StimulusError) and design.path is not None and str(design.path) not in str(e):
            raise StimulusError(f"{design.path}: {e}") from None       # name the design file
        raise
    finally:
        bar.close()
    return rows


def load_source_clip(design: Design, s: SourceSpec, item: str, path: Path):
    """One given clip through the loading rule, resampled to ``[study] fps`` when the
    design writes it, its analysis after the physics gate."""
    from .loading import POSITION_SUFFIXES, check_up_axis, load_clip
    clip = load_clip(str(path), scale=s.scale, fps=s.fps, gate=False)    # the design's gate runs below
    if path.suffix.lower() in POSITION_SUFFIXES:
        check_up_axis(clip)
    if design.fps_given and abs(clip.fps - design.fps) > 1e-9 * design.fps:
        clip = resample(clip, design.fps)
    clip.meta["name"] = item
    a = analyse(clip, total_mass=design.total_mass)
    spec = SimpleNamespace(name=f"{item} of source {s.name}", source=str(path), scale=s.scale,
                           accept_unphysical=s.accept_unphysical)
    try:
        physics_gate(spec, a, design)
    except DesignError as e:
        raise DesignError(str(e).replace("[[clips]] entry", f"[[sources]] entry '{s.name}'")) from None
    return a


def make_given_stimulus(design: Design, a, item: tuple, folder) -> dict:
    """Write one given clip (``item`` of :func:`plan_comparison`) as ``.bvh`` and
    ``.npz`` into ``folder``; its manifest row (measured like a reference motion
    when it has a flight; NaN measures when it has none)."""
    name, it, s, path, orig, group, level = item
    spec = SimpleNamespace(name=it, accept_unphysical=s.accept_unphysical)
    if group is not None and not isinstance(group, SourceGroup):    # an error injected into it
        if a.flight is None:
            raise StimulusError(f"item {it!r} of source '{s.name}' ({path}): the analyser finds no flight "
                                f"phase, so it cannot carry group '{group.name}''s errors")
        row = make_stimulus(design, a, (name, spec, group, level), folder)
        row.update(original=orig, source=s.name)
        return row
    if a.flight is not None:
        row = make_stimulus(design, a, (name, spec, None, 0.0), folder)
    else:
        data = bvh_text(a.clip, 1.0).encode()
        (Path(folder) / f"{name}.bvh").write_bytes(data)
        (Path(folder) / f"{name}.npz").write_bytes(npz_bytes(clip_arrays(a.clip, 0, 0)))
        row = {"stimulus": name, "clip": it, "level": 0.0, "takeoff": 0, "landing": 0,
               "seed": derived_seed(design.seed, name), "sha256": hashlib.sha256(data).hexdigest(),
               "frames": a.clip.num_frames, "fps": a.clip.fps, "bvh": f"{name}.bvh", "npz": f"{name}.npz",
               "accept_unphysical": bool(s.accept_unphysical),
               **({"style": design.style or "ellipsoids"} if design.styled else {})}
        row.update({k: np.nan for k in ("takeoff_angle_deg", "flight_s", "jump_height_m", "jump_length_m",
                                        "takeoff_time", "landing_time")})
    row.update(group=group.name if group is not None else s.name, kind=GIVEN_KIND, profile="",
               original=orig, source=s.name)
    return row


def build_comparison(design: Design, tmp: Path, bar=None) -> list[dict]:
    """The rows of a comparison design's stimuli, written into ``tmp`` (the build's
    staging folder; :func:`flipstudy.stimuli.stimset.build_stimuli` installs it)."""
    rows = []
    for item in plan_comparison(design):
        a = load_source_clip(design, item[2], item[1], item[3])
        rows.append(make_given_stimulus(design, a, item, tmp))
        if bar is not None:
            bar.step(item[0])
    return rows


def _build_comparison(design: Design, out: Path, force: bool, progress: bool, replace_check) -> list[dict]:
    """A comparison design's build (:mod:`flipstudy.stimuli.compare`): staged and
    installed like every build."""
    from .compare import plan_comparison
    todo = plan_comparison(design)            # items matched across the sources, before any work
    bar = Progress(len(todo), "stimuli", progress)
    tmp = Path(tempfile.mkdtemp(prefix=f".{out.name}.tmp-{os.getpid()}-", dir=out.parent))
    try:
        rows, read = [], {}
        for item in todo:
            key = (item[1], item[2].name)       # one reading per item and source
            if key not in read:
                read = {k: v for k, v in read.items() if k[0] == item[1]}
                read[key] = load_source_clip(design, item[2], item[1], item[3])
            rows.append(make_given_stimulus(design, read[key], item, tmp))
            bar.step(item[0])
        StimulusSet.from_rows(tmp, rows).write()
        if design.path is not None:
            shutil.copyfile(design.path, tmp / "design.toml")
        _install(tmp, out, force, replace_check)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    finally:
        bar.close()
    return rows


def uses_ballistic_kinds(design: Design) -> bool:
    """Does a design use a kind of :mod:`flipstudy.stimuli.ballistic`?  Its
    manifest then has the columns of :data:`flipstudy.stimuli.ballistic_measure.EXTRA_COLUMNS`
    (after ``style``), for every row."""
    return any(g.kind in kinds.ballistic_kind_names() for g in design.groups)


def _options(group) -> dict:
    """A group's kind options as an Injected holds them (policy, axis, span)."""
    return {k: getattr(group, k) for k in ("policy", "axis", "span")
            if group is not None and getattr(group, k, None)}


def make_stimulus(design: Design, a, item: tuple, folder) -> dict:
    """Make one stimulus of ``plan(design)`` (``item``: name, clip spec, group,
    level) from its base clip's analysis ``a``: write its ``.bvh`` and ``.npz``
    into ``folder`` and return its manifest row.  It depends on nothing but its
    arguments (its seed is :func:`derived_seed` of the design seed and the name),
    so it gives the same bytes in any process and in any order: what a cluster
    worker runs (:mod:`flipstudy.study.cluster`)."""
    name, spec, group, level = item
    tmp = Path(folder)
    extended = uses_ballistic_kinds(design)
    entry = kinds.find(group.kind) if group is not None else None
    if group is None or level == 0:
        inj = Injected(a.clip, group.kind if group else "reference",
                       group.profile if group else None, 0.0, a.takeoff, a.landing,
                       np.arange(a.clip.num_frames, dtype=float), a.flight_s,
                       a.takeoff_time, a.landing_time, opts=_options(group))
    else:
        try:
            inj = entry.injector()(a, group, level, design)
        except StimulusError as e:
            if entry.family != "ballistic":
                raise
            raise StimulusError(f"{name} (group '{group.name}', level {level:g}): {e}") from None
    ballistic = inj.kind in kinds.ballistic_kind_names()
    if inj.kind == "reference":
        m = measure(a, Injected(a.clip, kinds.TAKEOFF_ANGLE.name, None, 0.0, a.takeoff, a.landing,
                                None, a.flight_s, a.takeoff_time, a.landing_time))
        m["measured_error_pct"] = 0.0
    else:
        m = kinds.get(inj.kind).checker()(a, inj)
        check(m, inj, design.tolerance_pct, name, "[study] tolerance_pct")
    if extended and not ballistic:
        m = {**measure_ballistic(a, inj), **m}
        m["nominal_value"], m["measured_value"] = (group.sign * level if group else 0.0), \
            m["measured_error_pct"]
    text = bvh_text(inj.clip, 1.0)
    data = text.encode()
    npz = npz_bytes(clip_arrays(inj.clip, inj.takeoff, inj.landing))
    (tmp / f"{name}.bvh").write_bytes(data)
    (tmp / f"{name}.npz").write_bytes(npz)
    return {
        "stimulus": name, "clip": spec.name,
        "group": group.name if group else "reference",
        "kind": group.kind if group else "reference",
        "profile": (group.profile or "") if group else "",
        "level": level,
        "nominal_error_pct": 100.0 * inj.error if group and entry is not None and entry.family == "ballistic"
        else (group.sign * level if level else 0.0) if group else 0.0,
        "measured_error_pct": m["measured_error_pct"],
        "takeoff_angle_deg": m["takeoff_angle_deg"],
        "takeoff_angle_change_deg": m["takeoff_angle_change_deg"],
        "takeoff": inj.takeoff, "landing": inj.landing,
        "seed": derived_seed(design.seed, name),
        "sha256": hashlib.sha256(data).hexdigest(),
        "L_ratio_window": m["L_ratio_window"], "L_change_pct": m["L_change_pct"],
        "flight_s": m["flight_s"], "jump_height_m": m["jump_height_m"],
        "jump_length_m": m["jump_length_m"], "dp_takeoff": m["dp_takeoff"],
        "dp_landing": m["dp_landing"], "frames": inj.clip.num_frames, "fps": inj.clip.fps,
        "bvh": f"{name}.bvh", "npz": f"{name}.npz",
        "original": original_of(design, spec.name, group),
        "accept_unphysical": bool(spec.accept_unphysical),
        "takeoff_time": inj.takeoff_time, "landing_time": inj.landing_time,
        **{k: m[k] for k in ("air_acc_dev", "air_acc_dev_original", "dv_takeoff",
                             "dv_landing", "L_error_touchdown_pct", "below_floor_mm")},
        **({"style": design.style_of(group) or "ellipsoids"} if design.styled else {}),
        **({k: m[k] for k in EXTRA_COLUMNS} if extended else {}),
    }


def write_manifest(path: Path, rows: list[dict]) -> None:
    """The manifest of a build's ``rows`` (mappings of column → value) at ``path``
    (see :meth:`flipstudy.stimuli.contract.StimulusSet.write`): a ``style``
    column when the rows have one, then the ballistic kinds' columns when they
    have those."""
    Path(path).write_text(StimulusSet.from_rows(Path(path).parent, rows).manifest_text())


# --- the study folder: lock, atomic swap, recovery ---------------------------------------

AT_FDCWD = -100
RENAME_NOREPLACE, RENAME_EXCHANGE = 1, 2


def lock_path(out) -> Path:
    out = Path(out)
    return out.parent / f".{out.name}.lock"


@contextmanager
def study_lock(out, what: str = "build"):
    """Hold the exclusive lock of the study folder ``out`` (``.NAME.lock`` beside
    it, ``fcntl.flock``); raises :class:`StudyLockedError` at once when another
    process holds it.  The kernel releases the lock when the holder dies (even
    by SIGKILL); the lock file is removed on release."""
    import fcntl
    path = lock_path(out)
    while True:
        fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            try:
                holder = os.read(fd, 200).decode(errors="replace").split()
            except OSError:
                holder = []
            os.close(fd)
            who = f"a {holder[1]} (pid {holder[0]})" if len(holder) >= 2 else "another build"
            raise StudyLockedError(f"{out}: {who} is writing this study folder right now (lock "
                              f"{path}); wait until it has finished, or choose another --out") from None
        try:
            st, cur = os.fstat(fd), os.stat(path)
            same = (st.st_ino, st.st_dev) == (cur.st_ino, cur.st_dev)
        except FileNotFoundError:
            same = False
        if same:
            break
        os.close(fd)                      # the file was removed by its last holder: lock the new one
    try:
        os.ftruncate(fd, 0)
        os.write(fd, f"{os.getpid()} {what}\n".encode())
        yield path
    finally:
        try:
            os.unlink(path)
        except FileNotFoundError:
            pass
        os.close(fd)


def _renameat2(src: Path, dst: Path, flags: int) -> bool:
    """``renameat2(src, dst, flags)``; False when this system or file system lacks it."""
    if not sys.platform.startswith("linux"):
        return False
    try:
        fn = ctypes.CDLL(None, use_errno=True).renameat2
    except (AttributeError, OSError):
        return False
    fn.argtypes = [ctypes.c_int, ctypes.c_char_p, ctypes.c_int, ctypes.c_char_p, ctypes.c_uint]
    if fn(AT_FDCWD, os.fsencode(src), AT_FDCWD, os.fsencode(dst), flags) == 0:
        return True
    e = ctypes.get_errno()
    if e in (errno.EINVAL, errno.ENOSYS, errno.EOPNOTSUPP):
        return False
    raise OSError(e, os.strerror(e), str(src), None, str(dst))


def foreign_files(folder) -> list[str]:
    """Top-level names in ``folder`` that a build does not write (folders end in
    ``/``): everything but ``manifest.csv``, ``design.toml``, the ``.bvh`` / ``.npz``
    files its manifest lists and ``.locks``."""
    folder = Path(folder)
    ours = own_files(folder)
    return sorted(p.name + ("/" if p.is_dir() else "") for p in folder.iterdir() if p.name not in ours)


def _check_replaceable(folder: Path, replace_check, shown: Path) -> set:
    """Refuse (raise) unless ``folder`` may be replaced; returns the names below it
    that ``replace_check`` lets go with it (a set it returned), else none: every
    file not the build's own is then kept (:mod:`.replace`)."""
    if folder.is_symlink() or not folder.is_dir():
        raise StudyFolderError(f"{shown} exists and is not a folder; choose another --out")
    foreign = foreign_files(folder)
    if not foreign:
        return set()
    if replace_check is None:
        listed = ", ".join(foreign[:6]) + (", ..." if len(foreign) > 6 else "")
        raise StudyFolderError(
            f"{shown} holds files a stimuli build did not write ({listed}): participants' answers "
            f"or renders may be among them, so it is not replaced. Move it aside first "
            f"(`flipstudy archive {shown}`) or choose another --out")
    got = replace_check(folder, foreign)
    return set(got) if isinstance(got, (set, frozenset)) else set()


def _install(tmp: Path, out: Path, force: bool, replace_check) -> None:
    """Put the finished build ``tmp`` at ``out`` (under the lock), keeping every file
    of the old ``out`` that neither the old build nor ``replace_check`` made."""
    if not (out.exists() or out.is_symlink()):
        if _renameat2(tmp, out, RENAME_NOREPLACE):
            return
        if not (out.exists() or out.is_symlink()):
            os.rename(tmp, out)
            return
    # out exists now (maybe copied there while this build ran): check it again
    if not force:
        raise FlipstudyFileExistsError(f"{out} appeared while the build ran; it is left as it is "
                              f"(pass --force to replace it)")
    removable = _check_replaceable(out, replace_check, out)
    carry(out, tmp, kept_files(out, removable))           # the researcher's files go along
    old = out.parent / f".{out.name}.old-{os.getpid()}"   # a killed build's: sorted out by the next
    if _renameat2(tmp, out, RENAME_EXCHANGE):             # atomic: out is always a complete study
        os.rename(tmp, old)                              # the old study, never taken for a new build
        try:                                             # what was swapped out, checked once more
            removable = _check_replaceable(old, replace_check, out)
        except BaseException:                          # answers arrived in the last instant
            if _renameat2(old, out, RENAME_EXCHANGE):      # swap back; never delete them
                shutil.rmtree(old, ignore_errors=True)    # the new build (links to kept files)
            else:
                os.rename(old, out.parent / f"{out.name}.previous-{os.getpid()}")
            raise
        discard_old(old, out, removable)
        return
    os.rename(out, old)
    os.rename(tmp, out)
    discard_old(old, out, removable)


def _recover_and_clean(out: Path) -> None:
    """Under the lock: restore ``out`` from a killed build's ``.NAME.old-*`` when
    ``out`` is missing, then remove every leftover ``.NAME.tmp-*`` and ``.NAME.old-*``
    (no live build can own them: it would hold the lock)."""
    parent = out.parent
    olds = sorted(parent.glob(f".{out.name}.old-*"), key=lambda p: p.stat().st_mtime)
    if olds and not (out.exists() or out.is_symlink()):
        os.rename(olds.pop(), out)
    for p in olds:                        # a killed replace: only what it may delete goes
        if out.is_dir():
            discard_old(p, out, ())
        else:
            shutil.rmtree(p, ignore_errors=True)
    for p in parent.glob(f".{out.name}.tmp-*"):   # a new build's files (and links to kept ones)
        shutil.rmtree(p, ignore_errors=True)
