"""Stimulus videos against the limits of this machine, for every character style.

For each style (ellipsoids, capsules, stick, point-light, mannequin) the script
measures, in one run, on the built-in backflip at 640x480 / 60 fps in the
default look (FXAA, depth peeling, the style's ground and lights):

* **ours, frames**: ``render.video.iter_frames`` — what ``render_video`` and
  ``render_study``'s workers run per frame (pose the character, render it
  without the ground, read back its pixels and depth, put it on the ground's
  plate rendered once per video, redo the FXAA around it), without encoding;
  since it skips the ground's fill, ours can run faster than the bare-VTK
  "ceiling", which renders the whole scene every frame;
* **ceiling**: bare VTK calls on the very scene our renderer builds (the same
  merged character mesh, ground, lights and anti-aliasing): only ``Render()``
  and the read-back of the pixels (``GetPixelData`` into a reused array, viewed
  as numpy; then, for the default ``fxaa``, the FXAA of ``render.antialias`` on
  it, as ours runs) — no geometry update, as little Python as there can be;
* **ceiling + upload**: the same, but a pose computed in advance is first
  copied into the point and normal arrays and marked modified (VTK then
  uploads the mesh again, as any animation must): the limit of a renderer that
  poses the character;
* **encoder**: the H.264 writer of ``render.video.h264_writer`` (libx264, the
  same settings) fed the frames of that video, rendered beforehand;
* **ours, video**: ``render.video.render_video`` — frames encoded as they are
  rendered (ffmpeg runs in its own process beside the renderer).

The first three run in turn frame by frame in one scene (one ours, one
ceiling, one ceiling + upload, then the next display frame), so a load change
on a shared machine hits them alike.  Figures are frames per wall-clock second
(best of ``--repeat`` runs) and frames per CPU-second (``/cpu``: the process's
CPU time with llvmpipe's raster threads, plus its ffmpeg child's for the
encoded ones) — the rate one core would give, and the steadier figure when
other jobs share the machine.  Ratios: ours/ceiling for the frames (wall and per CPU-second); for
the videos, wall: video/min(ceiling, encoder) (renderer and encoder run side
by side), per CPU-second: video against 1/(1/ceiling + 1/encoder) (one core
does both).

With ``--aa`` it also measures the ceiling and ours (ellipsoids, the first
``--aa-frames`` frames) for each anti-aliasing a style offers (``none``,
``fxaa``, ``ssaa``), as a frame's cost relative to ``none``.

Then (unless ``--no-minimal``; needs moderngl, ``pip install '.[bench]'``) a
**minimal-OpenGL ceiling** below VTK: the same posed mesh, ground, two camera
lights and size drawn by :class:`MinimalGL` (moderngl on its own EGL context,
one Lambert shader, the pose uploaded every frame, read back to numpy), without
and with a simple FXAA post pass (the classic compact FXAA, 9 bilinear taps a
pixel), interleaved frame by frame with ours and bare VTK, for the style
without anti-aliasing and with the default one.  Frames per CPU-second there
are ``time.process_time`` spans: the CPU time of every thread of this process,
Mesa llvmpipe's raster threads included (both GL contexts live in it).

With ``--hashes`` it prints, per style, the SHA-256 of all frames of
``iter_frames`` (a speed-up must keep them).

Usage: ``python benchmarks/bench_render_ceiling.py [--size 640x480] [--repeat 3] [--styles ...] [--hashes] [--no-video] [--aa]``.
"""
from __future__ import annotations

import argparse
import hashlib
import os
import resource
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from flipstudy.render._pv import pv  # noqa: E402  (EGL offscreen before anything else)
from flipstudy.render.antialias import fxaa  # noqa: E402
from flipstudy.render.geometry import resample  # noqa: E402
from flipstudy.render.scene import scene_for  # noqa: E402
from flipstudy.render.staging import stage  # noqa: E402
from flipstudy.render.style import Style  # noqa: E402
from flipstudy.render.video import h264_writer, iter_frames, render_video  # noqa: E402
from flipstudy.stimuli import builtin  # noqa: E402
from flipstudy.stimuli.design import CHARACTER_STYLES  # noqa: E402

FPS = 60.0


def _cpu(children: bool = False) -> float:
    """CPU seconds (user + system) of this process (all threads), or of its
    waited-for children."""
    r = resource.getrusage(resource.RUSAGE_CHILDREN if children else resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


class Rate:
    """Frames per wall second and per CPU second of a timed block."""

    def __init__(self, children: bool = False):
        self.children = children

    def __enter__(self):
        self.t, self.c, self.cc = time.perf_counter(), _cpu(), _cpu(True)
        return self

    def stop(self, n: int) -> "Rate":
        wall = time.perf_counter() - self.t
        cpu = _cpu() - self.c + ((_cpu(True) - self.cc) if self.children else 0.0)
        self.fps, self.fps_cpu = n / wall, n / max(cpu, 1e-9)
        return self

    def __exit__(self, *exc):
        return False


class Clock:
    """Wall and CPU seconds summed over many short timed spans."""

    def __init__(self):
        self.wall = self.cpu = 0.0
        self.n = 0

    def __enter__(self):
        self._t, self._c = time.perf_counter(), time.process_time()
        return self

    def __exit__(self, *exc):
        self.wall += time.perf_counter() - self._t
        self.cpu += time.process_time() - self._c
        self.n += 1
        return False

    @property
    def fps(self) -> float:
        return self.n / self.wall

    @property
    def fps_cpu(self) -> float:
        return self.n / self.cpu


# ------------------------------------------------------- the minimal-OpenGL ceiling
_VS = """
#version 330
uniform mat4 mvp; uniform mat3 nrm_mat;
in vec3 pos; in vec3 nrm; in vec3 col;
out vec3 v_n; out vec3 v_c;
void main() { gl_Position = mvp * vec4(pos, 1.0); v_n = nrm_mat * nrm; v_c = col; }
"""
_FS = """
#version 330
uniform vec3 key; uniform vec3 fill; uniform vec2 amb_dif;
in vec3 v_n; in vec3 v_c; out vec4 f;
void main() {
    vec3 n = normalize(v_n);
    float d = 0.85 * abs(dot(n, key)) + 0.35 * abs(dot(n, fill));   // two-sided, as VTK's lights
    f = vec4(v_c * (amb_dif.x + amb_dif.y * d), 1.0);
}
"""
# the classic FXAA of Lottes (the compact "FXAA 3 console" form of the common GLSL ports)
_QUAD_VS = """
#version 330
in vec2 p; out vec2 uv;
void main() { uv = p * 0.5 + 0.5; gl_Position = vec4(p, 0.0, 1.0); }
"""
_FXAA_FS = """
#version 330
uniform sampler2D tex; uniform vec2 px; in vec2 uv; out vec4 f;
void main() {
    const vec3 w = vec3(0.299, 0.587, 0.114);
    float nw = dot(texture(tex, uv + vec2(-1.0, -1.0) * px).rgb, w);
    float ne = dot(texture(tex, uv + vec2( 1.0, -1.0) * px).rgb, w);
    float sw = dot(texture(tex, uv + vec2(-1.0,  1.0) * px).rgb, w);
    float se = dot(texture(tex, uv + vec2( 1.0,  1.0) * px).rgb, w);
    vec3 cm = texture(tex, uv).rgb; float m = dot(cm, w);
    float lo = min(m, min(min(nw, ne), min(sw, se))), hi = max(m, max(max(nw, ne), max(sw, se)));
    vec2 dir = vec2(-((nw + ne) - (sw + se)), (nw + sw) - (ne + se));
    float red = max((nw + ne + sw + se) * (0.25 / 8.0), 1.0 / 128.0);
    dir = clamp(dir / (min(abs(dir.x), abs(dir.y)) + red), -8.0, 8.0) * px;
    vec3 a = 0.5 * (texture(tex, uv + dir * (1.0 / 3.0 - 0.5)).rgb + texture(tex, uv + dir * (2.0 / 3.0 - 0.5)).rgb);
    vec3 b = a * 0.5 + 0.25 * (texture(tex, uv - dir * 0.5).rgb + texture(tex, uv + dir * 0.5).rgb);
    float lb = dot(b, w);
    f = vec4((lb < lo || lb > hi) ? a : b, 1.0);
}
"""


class MinimalGL:
    """The same posed character mesh and ground drawn by as little OpenGL as
    there can be (moderngl on its own EGL context): one Lambert shader with the
    scene's two camera lights, the character's points and normals uploaded
    every frame, the frame read back into a reused numpy array; ``aa`` adds a
    second pass, the classic FXAA over the frame in a texture."""

    def __init__(self, sc, mesh, ground):
        import moderngl
        self.ctx = ctx = moderngl.create_standalone_context(backend="egl")
        w, h = sc.size
        self.size = (w, h)
        prog = ctx.program(vertex_shader=_VS, fragment_shader=_FS)
        cam = sc.plotter.renderer.GetActiveCamera()
        mv = _m4(cam.GetModelViewTransformMatrix())                   # VTK's own camera
        pr = _m4(cam.GetCompositeProjectionTransformMatrix(w / h, -1, 1))
        prog["mvp"].write(pr.T.astype("f4").tobytes())            # projection x view, column-major
        prog["nrm_mat"].write(np.ascontiguousarray(mv[:3, :3]).T.astype("f4").tobytes())
        for name, p in (("key", (-0.6, 1.2, 1.0)), ("fill", (0.8, 0.3, 0.6))):
            prog[name].value = tuple(np.asarray(p) / np.linalg.norm(p))
        self.prog = prog
        # the character: points and normals rewritten each frame, colours and triangles once
        self.n = mesh.n_points
        self.vpos = ctx.buffer(reserve=self.n * 12)
        self.vnrm = ctx.buffer(reserve=self.n * 12)
        vcol = ctx.buffer((np.asarray(mesh.point_data["rgb"], "f4") / 255.0).astype("f4").tobytes())
        ibo = ctx.buffer(np.asarray(mesh.regular_faces, "i4").tobytes())
        self.char = ctx.vertex_array(prog, [(self.vpos, "3f", "pos"), (self.vnrm, "3f", "nrm"),
                                            (vcol, "3f", "col")], index_buffer=ibo)
        # the ground: its triangles unshared, each with its tile's colour
        tri = np.asarray(ground.regular_faces)
        gp = np.asarray(ground.points, "f4")[tri].reshape(-1, 3)
        gc = np.repeat(np.asarray(ground.cell_data["rgb"], "f4") / 255.0, 3, axis=0)
        gn = np.tile(np.array([0, 1, 0], "f4"), (len(gp), 1))
        self.ground = ctx.vertex_array(prog, [(ctx.buffer(gp.tobytes()), "3f", "pos"),
                                              (ctx.buffer(gn.tobytes()), "3f", "nrm"),
                                              (ctx.buffer(gc.astype("f4").tobytes()), "3f", "col")])
        self.bg = tuple(sc.plotter.renderer.GetBackground())
        self.fbo = ctx.framebuffer([ctx.texture((w, h), 4)], ctx.depth_renderbuffer((w, h)))
        self.fbo_aa = ctx.simple_framebuffer((w, h))
        self.fxaa = ctx.program(vertex_shader=_QUAD_VS, fragment_shader=_FXAA_FS)
        self.fxaa["px"].value = (1.0 / w, 1.0 / h)
        quad = ctx.buffer(np.array([-1, -1, 1, -1, -1, 1, 1, 1], "f4").tobytes())
        self.quad = ctx.vertex_array(self.fxaa, [(quad, "2f", "p")])
        self.out = np.empty((h, w, 3), np.uint8)

    def frame(self, pts, nrm, aa: bool = False) -> np.ndarray:
        """Upload a pose, draw, (FXAA,) read back: the (H, W, 3) uint8 frame (bottom row first)."""
        import moderngl
        ctx = self.ctx
        with ctx:                                   # VTK's context is current otherwise
            self.vpos.write(pts.astype("f4"))
            self.vnrm.write(nrm.astype("f4"))
            self.fbo.use()
            ctx.enable(moderngl.DEPTH_TEST)
            self.fbo.clear(*self.bg, 1.0, depth=1.0)
            self.prog["amb_dif"].value = (0.5, 0.5)
            self.ground.render()
            self.prog["amb_dif"].value = (0.3, 0.75)
            self.char.render()
            src = self.fbo
            if aa:
                ctx.disable(moderngl.DEPTH_TEST)
                self.fbo_aa.use()
                self.fbo.color_attachments[0].use(0)
                self.quad.render(moderngl.TRIANGLE_STRIP)
                src = self.fbo_aa
            src.read_into(self.out, components=3)
        return self.out

    def release(self) -> None:
        self.ctx.release()


def _m4(m) -> np.ndarray:
    """A vtkMatrix4x4 as a (4, 4) numpy array."""
    return np.array([[m.GetElement(i, j) for j in range(4)] for i in range(4)])


def interleaved(st, fps=FPS, frames: int | None = None, minimal: bool = False):
    """Ours, the ceiling and the ceiling with upload, frame by frame in turn in
    one scene (so the three see the same machine load): per display frame one
    ``next()`` of ``iter_frames`` (ours: pose, render, read back, flip), then
    a bare ``Render()`` + ``GetPixelData`` of the geometry as it stands
    (ceiling: nothing to upload), then a precomputed pose copied in and marked
    modified before the same bare render (ceiling + upload); with ``minimal``
    then the same pose drawn by :class:`MinimalGL` without and with its FXAA
    pass.  Returns the :class:`Clock` objects ``[ours, ceiling, upload]``
    (``+ [minimal, minimal_aa]``; ``frames``: only the first ones)."""
    from vtkmodules.util.numpy_support import vtk_to_numpy
    from vtkmodules.vtkCommonCore import vtkUnsignedCharArray
    ours, ceil, upl, mgl, mgl_aa = Clock(), Clock(), Clock(), Clock(), Clock()
    gl = None
    with scene_for(st) as sc:
        it = iter_frames(st.clips[0], sc, fps, body=st.bodies[0])
        next(it)                                    # shaders compiled, the character built
        ch = sc.character("main", st.bodies[0])     # the slot iter_frames draws in
        bm, mesh = ch.body_mesh, ch.body_mesh.mesh
        pts, nrm = bm.world_points(), np.asarray(mesh.point_data["Normals"])
        v = resample(st.clips[0], fps)
        R, P = v.joint_rotations(), v.joint_positions()
        poses = []                                  # 16 poses over the clip, computed untimed
        for k in np.linspace(0, len(R) - 1, 16).astype(int):
            bm.pose(R[k], P[k])
            poses.append((pts.copy(), nrm.copy()))
        rw = sc.plotter.render_window
        w, h = rw.GetSize()
        buf = vtkUnsignedCharArray()
        vpts, vnrm = mesh.GetPoints(), mesh.GetPointData().GetNormals()
        post = sc.style.anti_aliasing == "fxaa"     # ours runs FXAA on the read-back frame: so does the ceiling
        if minimal:
            import pyvista as pv_
            gl = MinimalGL(sc, mesh, pv_.wrap(sc.ground_actor.GetMapper().GetInput()))
            gl.frame(*poses[0], aa=True)            # shaders compiled
        for k in range(min(len(R) - 1, frames or len(R))):
            with ours:
                next(it)
            with ceil:
                rw.Render()
                rw.GetPixelData(0, 0, w - 1, h - 1, 1, buf, 0)
                px = vtk_to_numpy(buf)
                if post:
                    fxaa(px.reshape(h, w, 3), px.reshape(h, w, 3))
            with upl:
                a, b = poses[k % len(poses)]
                np.copyto(pts, a)
                np.copyto(nrm, b)
                vpts.Modified()
                vnrm.Modified()
                mesh.Modified()
                rw.Render()
                rw.GetPixelData(0, 0, w - 1, h - 1, 1, buf, 0)
                px = vtk_to_numpy(buf)
                if post:
                    fxaa(px.reshape(h, w, 3), px.reshape(h, w, 3))
            if gl is not None:
                with mgl:
                    gl.frame(*poses[k % len(poses)])
                with mgl_aa:
                    gl.frame(*poses[k % len(poses)], aa=True)
        if gl is not None:
            gl.release()
    return [ours, ceil, upl] + ([mgl, mgl_aa] if gl is not None else [])


def ours_frames(st, fps=FPS, hashes: bool = False):
    """``iter_frames`` over the whole clip (the first frame, which compiles the
    shaders, untimed); with ``hashes`` also the SHA-256 of every frame."""
    with scene_for(st) as sc:
        it = iter_frames(st.clips[0], sc, fps, body=st.bodies[0])
        first = next(it)
        h = hashlib.sha256(first.tobytes()) if hashes else None
        n = 0
        with Rate() as r:
            for f in it:
                n += 1
                if h is not None:
                    h.update(f.tobytes())
            r.stop(n)
    return r, (h.hexdigest() if h is not None else None)


def encoder(frames, size, fps=FPS) -> Rate:
    """The H.264 writer alone, fed pre-rendered frames."""
    with tempfile.TemporaryDirectory() as d:
        with Rate(children=True) as r:
            w = h264_writer(Path(d) / "enc.mp4", size, fps)
            for f in frames:
                w.send(f)
            w.close()
            r.stop(len(frames))
    return r


def ours_video(st, n_frames: int, fps=FPS) -> Rate:
    """``render_video`` (render and encode) of the clip, scene set up untimed."""
    with tempfile.TemporaryDirectory() as d, scene_for(st) as sc:
        next(iter_frames(st.clips[0], sc, fps, body=st.bodies[0]))     # shaders compiled
        with Rate(children=True) as r:
            render_video(st, Path(d) / "v.mp4", fps=fps, scene=sc)
            r.stop(n_frames)
    return r


def _gl_renderer() -> str:
    """The OpenGL renderer string (e.g. llvmpipe)."""
    st = stage([builtin("jump")], size=(16, 16))
    with scene_for(st) as sc:
        sc.grab()
        info = sc.plotter.render_window.ReportCapabilities()
    for line in info.splitlines():
        if "renderer string" in line:
            return line.split(":", 1)[1].strip()
    return "unknown GL renderer"


def best(rates):
    """The best wall and the best per-CPU rate of several runs."""
    return max(r.fps for r in rates), max(r.fps_cpu for r in rates)


def main(argv=None):
    """Print the table (and the anti-aliasing one with ``--aa``); return its rows."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--size", default="640x480", help="frame size WxH (default 640x480)")
    ap.add_argument("--repeat", type=int, default=3, help="runs of each measurement (best kept)")
    ap.add_argument("--styles", nargs="*", default=list(CHARACTER_STYLES), choices=CHARACTER_STYLES)
    ap.add_argument("--hashes", action="store_true", help="print the SHA-256 of every style's frames")
    ap.add_argument("--no-video", action="store_true", help="frames only (no encoder, no video)")
    ap.add_argument("--aa", action="store_true", help="also time each anti-aliasing (ellipsoids)")
    ap.add_argument("--aa-frames", type=int, default=60, help="frames per anti-aliasing (default 60)")
    ap.add_argument("--no-minimal", action="store_true",
                    help="leave out the minimal-OpenGL ceiling (needs moderngl: pip install '.[bench]')")
    args = ap.parse_args(argv)
    size = tuple(int(v) for v in args.size.lower().split("x"))
    clip = builtin("backflip")
    v = resample(clip, FPS)
    n = v.num_frames
    print(f"clip: built-in backflip, {n} frames at {FPS:g} fps, {size[0]}x{size[1]}, FXAA; VTK "
          f"{'.'.join(map(str, pv.vtk_version_info))}, {_gl_renderer()}, {os.cpu_count()} CPU(s), "
          f"LP_NUM_THREADS={os.environ.get('LP_NUM_THREADS', 'unset')}, "
          f"load average {os.getloadavg()[0]:.1f}; best of {args.repeat}")
    print("frames/s (wall) and frames per CPU-second (/cpu):")
    head = (f"{'style':>12} {'points':>7} {'ceiling':>8} {'/cpu':>6} {'+upload':>8} {'/cpu':>6} "
            f"{'ours':>6} {'/cpu':>6} {'ours/ceiling':>12} {'/cpu':>5}")
    if not args.no_video:
        head += (f" {'encoder':>8} {'/cpu':>6} {'video':>6} {'/cpu':>6} {'video/min':>9} "
                 f"{'/cpu':>5}")
    print(head)
    rows = {}
    for name in args.styles:
        st = stage([clip], size=size, style=Style().with_character(name))
        c, cu, o, e, vi, hashes = [], [], [], [], [], set()
        frames = None
        for _ in range(args.repeat):
            oc_, c_, u_ = interleaved(st)[:3]
            o.append(oc_)
            c.append(c_)
            cu.append(u_)
            if args.hashes:
                hashes.add(ours_frames(st, hashes=True)[1])
            if not args.no_video:
                if frames is None:
                    with scene_for(st) as sc:
                        frames = [f.copy() for f in iter_frames(st.clips[0], sc, FPS, body=st.bodies[0])]
                e.append(encoder(frames, size))
                vi.append(ours_video(st, n))
        with scene_for(st) as sc:
            npts = sc.character("main", st.bodies[0]).body_mesh.mesh.n_points
        (cf, cc), (uf, uc), (of, oc) = best(c), best(cu), best(o)
        line = (f"{name:>12} {npts:>7} {cf:8.1f} {cc:6.1f} {uf:8.1f} {uc:6.1f} {of:6.1f} {oc:6.1f} "
                f"{of / cf:12.0%} {oc / cc:5.0%}")
        rows[name] = {"ceiling": (cf, cc), "upload": (uf, uc), "ours": (of, oc)}
        if not args.no_video:
            (ef, ec), (vf, vc) = best(e), best(vi)
            line += (f" {ef:8.1f} {ec:6.1f} {vf:6.1f} {vc:6.1f} {vf / min(cf, ef):9.0%} "
                     f"{vc * (1 / cc + 1 / ec):5.0%}")
            rows[name].update(encoder=(ef, ec), video=(vf, vc))
        print(line, flush=True)
        if args.hashes:
            if len(hashes) != 1:
                print(f"  {name}: frames differ between runs!")
            print(f"  sha256 of {name}'s {n} frames: {hashes.pop()}")
    if args.aa:
        from flipstudy.render.style import ANTI_ALIASING
        print(f"anti-aliasing (ellipsoids, {args.aa_frames} frames; cost of a frame relative to none, "
              f"per CPU-second):")
        print(f"{'AA':>6} {'ceiling':>8} {'/cpu':>6} {'ours':>6} {'/cpu':>6} {'cost':>5}")
        base = None
        for aa in ("none",) + tuple(a for a in ANTI_ALIASING if a != "none"):
            st = stage([clip], size=size, style=Style(anti_aliasing=aa))
            runs = [interleaved(st, frames=args.aa_frames) for _ in range(args.repeat)]
            (cf, cc), (of, oc) = best([r[1] for r in runs]), best([r[0] for r in runs])
            base = base or oc
            print(f"{aa:>6} {cf:8.1f} {cc:6.1f} {of:6.1f} {oc:6.1f} {base / oc:4.1f}×", flush=True)
            rows[f"aa-{aa}"] = {"ceiling": (cf, cc), "ours": (of, oc)}
    if not args.no_minimal:
        rows.update(minimal_table(clip, size, args.repeat, args.aa_frames))
    return rows


def minimal_table(clip, size, repeat: int, frames: int) -> dict:
    """Ours, bare VTK and the minimal-OpenGL ceiling without and with its FXAA
    pass, interleaved frame by frame in one run, for the style without
    anti-aliasing and with the default one (ellipsoids); frames per CPU-second."""
    try:
        import moderngl  # noqa: F401
    except ImportError:
        print("minimal-OpenGL ceiling: skipped, moderngl is not installed (pip install '.[bench]')")
        return {}
    print(f"minimal-OpenGL ceiling (moderngl on EGL, Lambert, the pose uploaded each frame, read back;"
          f" ellipsoids, {frames} frames), frames per CPU-second (time.process_time: every thread of "
          f"this process, llvmpipe's raster threads included):")
    print(f"{'style AA':>9} {'ours':>6} {'bare VTK':>8} {'minimal':>8} {'min+FXAA':>9} "
          f"{'ours/min':>8} {'ours/min+FXAA':>13}")
    rows = {}
    for aa in ("none", "fxaa"):
        st = stage([clip], size=size, style=Style(anti_aliasing=aa))
        runs = [interleaved(st, frames=frames, minimal=True) for _ in range(repeat)]
        o, c, m, ma = (best([r[i] for r in runs])[1] for i in (0, 1, 3, 4))
        print(f"{aa:>9} {o:6.1f} {c:8.1f} {m:8.1f} {ma:9.1f} {o / m:8.0%} {o / ma:13.0%}", flush=True)
        rows[f"minimal-{aa}"] = {"ours": o, "vtk": c, "minimal": m, "minimal_aa": ma}
    return rows


if __name__ == "__main__":
    main()
