"""How much of the far arm and the far leg a staged clip's picture shows, measured
on rendered pixels.

Each frame is drawn twice under the stage's camera with flat colours (no
lighting, no anti-aliasing, no ground): once whole, the far arm and the far leg
in colours of their own, and once with every other part of the body collapsed
to a point (zero-area triangles draw nothing), the far limbs alone.  The
visible fraction of a limb is its pixels in the first picture over its pixels
in the second: what the near limbs and the trunk hide, whatever the camera
maths of the stage says.  "Far" is per frame the side (left or right, from the
joint names) whose joints lie farther from the camera on average.
"""
from __future__ import annotations

import re

import numpy as np

FAR_ARM, FAR_LEG, REST = (255, 0, 0), (0, 255, 0), (90, 90, 90)
_LEG = re.compile(r"leg|foot|toe|hip|thigh|knee|ankle", re.I)


def _limb_of_points(bm, names) -> tuple[np.ndarray, np.ndarray]:
    """Per mesh point: side (0 trunk, 1 left, 2 right) and whether it is a leg."""
    from flipstudy.render.sides import joint_sides
    joint = np.repeat(bm.joint, bm.points_per_piece)
    leg_joint = np.array([bool(_LEG.search(n)) for n in names])
    return joint_sides(bm.body.skeleton)[joint], leg_joint[joint]


def far_limb_visibility(st, k: int = 0, frames=None) -> dict:
    """Visible fractions of the far arm and the far leg in the frames ``frames``
    (default: the flight, take-off to landing) of clip ``k`` of stage ``st``,
    drawn at the stage's size.  Returns ``{"frames": (n,), "arm": (n,), "leg": (n,), "limbs": (n,),
    "arm_px": (n,), "leg_px": (n,)}`` (fractions — ``limbs`` of the two together — and
    the limbs' pixels alone)."""
    from flipstudy.render.scene import Scene
    from flipstudy.render.sides import LEFT, RIGHT
    from flipstudy.render.style import Style

    clip, body = st.clips[k], st.bodies[k]
    if frames is None:
        frames = np.arange(st.takeoffs[k], st.landings[k] + 1)
    frames = np.asarray(frames, int)
    style = Style.from_dict({"ground": False, "anti_aliasing": "none", "legend": False,
                             "background": "#ffffff"})
    R, P = clip.joint_rotations(), clip.joint_positions()
    back = np.asarray(st.camera.basis()[2])
    names = clip.skeleton.joint_names
    from flipstudy.render.sides import joint_sides
    jside = joint_sides(clip.skeleton)
    out = {key: [] for key in ("arm", "leg", "limbs", "arm_px", "leg_px")}
    with Scene(body, style, size=st.size, camera=st.camera) as sc:
        ch = sc.character(0, body)
        prop = ch.actor.prop
        prop.ambient, prop.diffuse, prop.specular = 1.0, 0.0, 0.0
        ch.look(style.body_color)
        bm = ch.body_mesh
        side, leg = _limb_of_points(bm, names)
        mesh_rgb = ch._rgb
        arr = bm.mesh.GetPointData().GetArray("rgb")
        for f in frames:
            depth = P[f] @ back                        # larger: nearer the camera
            far = LEFT if depth[jside == LEFT].mean() < depth[jside == RIGHT].mean() else RIGHT
            arm_pts, leg_pts = (side == far) & ~leg, (side == far) & leg
            mesh_rgb[:] = REST
            mesh_rgb[arm_pts] = FAR_ARM
            mesh_rgb[leg_pts] = FAR_LEG
            arr.Modified()
            ch.pose(R[f], P[f])
            whole = sc.grab()
            pts = bm.world_points()
            pts[~(arm_pts | leg_pts)] = pts[arm_pts][0]       # everything else: zero area
            bm.mesh.GetPoints().Modified()
            bm.mesh.Modified()
            alone = sc.grab()
            counts = {}
            for key, colour in (("arm", FAR_ARM), ("leg", FAR_LEG)):
                seen = np.all(whole == colour, axis=-1).sum()
                total = np.all(alone == colour, axis=-1).sum()
                counts[key] = (seen, total)
                out[key].append(seen / total if total else np.nan)
                out[key + "_px"].append(total)
            seen, total = np.add(counts["arm"], counts["leg"])
            out["limbs"].append(seen / total if total else np.nan)
    return {"frames": frames, **{key: np.array(v, float) for key, v in out.items()}}
