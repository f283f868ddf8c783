# SPDX-License-Identifier: GPL-3.0-or-later
"""Render the demo scene (sample_blends/demo_walk.blend) to a PNG for the README.

Run with Blender as a Python module, e.g.::

    .venv/blender-4.5/bin/python tools/render_demo.py                 # docs/demo_render.png
    .venv/blender-4.5/bin/python tools/render_demo.py --view chairs   # docs/demo_render_chairs.png

What is drawn is the saved demo itself: its ground, pillars and chairs as they are, and the
planned characters evaluated through the depsgraph at a handful of frames. The BVH rigs have
no mesh, so each character is given the extension's **proxy body** (``api.add_bodies``: a
capsule round each bone, parented to it) and the body is copied as the depsgraph evaluates it
(``--figures bones``: the armature bones instead, a cylinder per bone, a ball per joint and
one larger ball on the Head bone). Copies at several frames
along the plan ("onion skin", lighter = earlier; a traversal adds its take-off, top and
landing) share the character's colour with its planned ground path (``arrays["ground"]`` of
the plan record on the armature), drawn as a thin tube; small white discs mark the joins
between the plan's pieces (its NLA strip boundaries) and a flat arrow the goal. The only
additions to the scene are those drawings, the characters' names (chairs view), a camera, a
sun, a sky colour, a 1 m checker on the floor (extended under the whole layout) and
materials; the .blend is never saved.

Cycles on the CPU (no GPU or display needed), denoised with OpenImageDenoise when the bpy
build has it.
"""

import argparse
import contextlib
import math
import os
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import blender_session  # noqa: E402

REPO = blender_session.REPO_ROOT

# Character colours (linear RGB).
COLOURS = {
    "Walker": (0.02, 0.16, 0.75),
    "Hurried": (0.85, 0.18, 0.02),
    "Calm": (0.02, 0.42, 0.20),
    "Crowd.0": (0.75, 0.10, 0.10),
    "Crowd.1": (0.85, 0.45, 0.02),
    "Crowd.2": (0.55, 0.55, 0.02),
    "Crowd.3": (0.05, 0.50, 0.15),
    "Crowd.4": (0.02, 0.25, 0.80),
    "Crowd.5": (0.45, 0.08, 0.65),
}
FINGER_BONES = ("FingerBase", "HandIndex", "Thumb")

# Per view: the characters drawn; whether their names are written over their starts; the
# props kept whole in frame (name contains ``props``, within ``near`` m of a path; the frame
# always holds the paths and the drawn poses); the camera: azimuth of the view direction in
# degrees (0 = looking along +Y, positive turns towards +X), pitch below the horizon in
# degrees, focal length in mm; the default image size and output.
VIEWS = {
    "pillars": dict(
        characters=("Walker",),
        labels=False,
        props=None,
        near=0.0,
        azimuth=-20.0,
        pitch=60.0,
        lens=40.0,
        size=(960, 540),
        out="docs/demo_render.png",
    ),
    "chairs": dict(
        characters=("Hurried", "Calm"),
        labels=True,
        props="hurdle",
        near=6.0,
        azimuth=-8.0,
        pitch=36.0,
        lens=60.0,
        size=(960, 720),
        out="docs/demo_render_chairs.png",
    ),
    "gaits": dict(
        characters=("Walker",),
        labels=False,
        props="Chair",
        near=6.0,
        azimuth=-15.0,
        pitch=40.0,
        lens=50.0,
        copies=12,
        size=(960, 540),
        out="docs/gaits_render.png",
    ),
    "crowd": dict(
        characters=tuple(f"Crowd.{n}" for n in range(6)),
        labels=False,
        props=None,
        near=0.0,
        azimuth=-90.0,
        pitch=62.0,
        lens=35.0,
        copies=4,
        size=(960, 600),
        out="docs/demo_render_crowd.png",
    ),
}


def parse_args(argv):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument(
        "--blend",
        default=str(REPO / "sample_blends" / "demo_walk.blend"),
        help="the demo scene written by ./dev demo (default: %(default)s)",
    )
    p.add_argument(
        "--view",
        choices=sorted(VIEWS),
        default="pillars",
        help="pillars: the Walker through the pillar field; chairs: the hurried "
        "and the calm walker at the two chair lines; crowd: the six walkers; gaits: the "
        "walker of tools/gaits_demo.py (--blend sample_blends/gaits_demo.blend) walking, "
        "running over the chair line and walking on (default: %(default)s)",
    )
    p.add_argument(
        "--out",
        help="PNG to write (default: docs/demo_render.png for the pillars "
        "view, docs/demo_render_chairs.png for the chairs view)",
    )
    p.add_argument("--samples", type=int, default=32, help="Cycles samples (default: %(default)s)")
    p.add_argument(
        "--size",
        type=int,
        nargs=2,
        metavar=("W", "H"),
        help="image size (default: 960 540 for pillars, 960 720 for chairs, 960 600 for crowd)",
    )
    p.add_argument(
        "--copies",
        type=int,
        help="poses drawn per character, evenly spaced in time (default: 8, 4 for "
        "the crowd; a traversal adds its take-off, top and landing)",
    )
    p.add_argument(
        "--figures",
        choices=("bodies", "bones"),
        default="bodies",
        help="draw each pose as the character's proxy body (api.add_bodies) or as its "
        "armature bones (default: %(default)s)",
    )
    p.add_argument("--verbose", action="store_true", help="show Blender's render progress")
    return p.parse_args(argv)


# --- drawing helpers -------------------------------------------------------------------------


def material(bpy, name, colour, roughness=0.6, emission=0.0):
    mat = bpy.data.materials.new(name)
    if mat.node_tree is None:  # Blender 4.x; 5.x materials always have nodes
        mat.use_nodes = True
    bsdf = mat.node_tree.nodes.get("Principled BSDF")
    bsdf.inputs["Base Color"].default_value = (*colour, 1.0)
    bsdf.inputs["Roughness"].default_value = roughness
    if emission:
        bsdf.inputs["Emission Color"].default_value = (*colour, 1.0)
        bsdf.inputs["Emission Strength"].default_value = emission
    mat.diffuse_color = (*colour, 1.0)
    return mat


def checker_material(bpy, name, a, b):
    """A 1 m checker in world X/Y (so the ground and its extension line up)."""
    mat = bpy.data.materials.new(name)
    if mat.node_tree is None:  # Blender 4.x; 5.x materials always have nodes
        mat.use_nodes = True
    nt = mat.node_tree
    bsdf = nt.nodes.get("Principled BSDF")
    bsdf.inputs["Roughness"].default_value = 0.9
    geo = nt.nodes.new("ShaderNodeNewGeometry")
    sep = nt.nodes.new("ShaderNodeSeparateXYZ")
    comb = nt.nodes.new("ShaderNodeCombineXYZ")
    comb.inputs["Z"].default_value = 0.5  # off the cell boundary: no flicker at z = 0
    chk = nt.nodes.new("ShaderNodeTexChecker")
    chk.inputs["Scale"].default_value = 1.0
    chk.inputs["Color1"].default_value = (*a, 1.0)
    chk.inputs["Color2"].default_value = (*b, 1.0)
    nt.links.new(geo.outputs["Position"], sep.inputs[0])
    nt.links.new(sep.outputs["X"], comb.inputs["X"])
    nt.links.new(sep.outputs["Y"], comb.inputs["Y"])
    nt.links.new(comb.outputs[0], chk.inputs["Vector"])
    nt.links.new(chk.outputs["Color"], bsdf.inputs["Base Color"])
    return mat


def mesh_object(bpy, bm, name, mat, collection):
    me = bpy.data.meshes.new(name)
    bm.to_mesh(me)
    bm.free()
    me.materials.append(mat)
    ob = bpy.data.objects.new(name, me)
    collection.objects.link(ob)
    return ob


def stick_figure(bpy, bmesh, Matrix, ob_eval, name, mat, collection):
    """The evaluated armature's bones in world space: a cylinder per bone, a ball per joint."""
    bm = bmesh.new()
    mw = ob_eval.matrix_world
    for pb in ob_eval.pose.bones:
        head, tail = mw @ pb.head, mw @ pb.tail
        r = 0.014 if any(k in pb.name for k in FINGER_BONES) else 0.036
        axis = tail - head
        length = axis.length
        if length > 1e-3:
            rot = axis.to_track_quat("Z", "Y").to_matrix().to_4x4()
            bmesh.ops.create_cone(
                bm,
                cap_ends=True,
                segments=10,
                radius1=r,
                radius2=r * 0.8,
                depth=length,
                matrix=Matrix.Translation((head + tail) / 2) @ rot,
            )
        bmesh.ops.create_uvsphere(
            bm, u_segments=10, v_segments=6, radius=r * 1.25, matrix=Matrix.Translation(head)
        )
        if pb.name == "Head":
            bmesh.ops.create_uvsphere(
                bm,
                u_segments=16,
                v_segments=10,
                radius=max(0.09, length * 0.6),
                matrix=Matrix.Translation(head + axis * 0.55),
            )
    for f in bm.faces:
        f.smooth = True
    return mesh_object(bpy, bm, name, mat, collection)


def body_figure(bpy, bmesh, parts, depsgraph, name, mat, collection):
    """The character's proxy body (``parts``: its capsule objects) as the depsgraph
    evaluates it now, copied into one static mesh in world space."""
    bm = bmesh.new()
    for part in parts:
        ev = part.evaluated_get(depsgraph)
        me = ev.to_mesh()
        me.transform(ev.matrix_world)
        bm.from_mesh(me)
        ev.to_mesh_clear()
    for f in bm.faces:
        f.smooth = True
    return mesh_object(bpy, bm, name, mat, collection)


def path_tube(bpy, name, xy, z, radius, mat, collection):
    cu = bpy.data.curves.new(name, "CURVE")
    cu.dimensions = "3D"
    cu.bevel_depth = radius
    cu.bevel_resolution = 2
    sp = cu.splines.new("POLY")
    sp.points.add(len(xy) - 1)
    for p, (x, y) in zip(sp.points, xy):
        p.co = (float(x), float(y), z, 1.0)
    cu.materials.append(mat)
    ob = bpy.data.objects.new(name, cu)
    collection.objects.link(ob)
    return ob


def disc(bpy, bmesh, Matrix, name, xy, radius, height, mat, collection):
    bm = bmesh.new()
    for x, y in xy:
        bmesh.ops.create_cone(
            bm,
            cap_ends=True,
            segments=16,
            radius1=radius,
            radius2=radius,
            depth=height,
            matrix=Matrix.Translation((x, y, height / 2)),
        )
    return mesh_object(bpy, bm, name, mat, collection)


def arrow(bpy, bmesh, Matrix, name, x, y, heading, mat, collection):
    """A flat arrow on the floor at (x, y) pointing along ``heading`` (0 = +X, CCW)."""
    bm = bmesh.new()
    shaft = [
        (-0.45, -0.06),
        (0.1, -0.06),
        (0.1, -0.16),
        (0.45, 0.0),
        (0.1, 0.16),
        (0.1, 0.06),
        (-0.45, 0.06),
    ]
    c, s = math.cos(heading), math.sin(heading)
    verts = [bm.verts.new((x + c * u - s * v, y + s * u + c * v, 0.012)) for u, v in shaft]
    bm.faces.new(verts)
    return mesh_object(bpy, bm, name, mat, collection)


def label(bpy, text, x, y, z, mat, collection):
    """The character's object name over its start (turned to face the camera later)."""
    cu = bpy.data.curves.new(f"rd label {text}", "FONT")
    cu.body = text
    cu.size = 0.45
    cu.align_x = "CENTER"
    cu.extrude = 0.01
    cu.materials.append(mat)
    ob = bpy.data.objects.new(f"rd label {text}", cu)
    ob.location = (x, y, z)
    collection.objects.link(ob)
    return ob


def tint(colour, t):
    """``colour`` mixed with white: t = 0 light (early), t = 1 the full colour (late)."""
    w = 0.5 * (1.0 - t)
    return tuple(c * (1 - w) + 0.85 * w for c in colour)


# --- scene -----------------------------------------------------------------------------------


def pick_frames(meta, arrays, copies):
    """Evenly spaced frames over the plan, plus take-off / top / landing of each traversal."""
    import numpy as np

    f0, f1 = int(meta["frame_start"]), int(meta["frame_end"])
    frames = set(int(round(f)) for f in np.linspace(f0, f1, copies))
    keys = set()
    root = arrays["root"]
    for a, b in meta.get("traversals", []):
        seg = root[a - f0 : b - f0 + 1, 2]
        top = a + int(np.argmax(seg))
        keys.update(k for k in (top - 12, top, top + 12) if f0 <= k <= f1)
    if keys:
        frames = {f for f in frames if min(abs(f - k) for k in keys) > 20} | keys
    return sorted(frames)


def build(bpy, addon, view, copies, figures="bodies"):
    import bmesh
    import numpy as np
    from mathutils import Matrix, Vector

    api = addon.api
    scene = bpy.context.scene
    coll = bpy.data.collections.new("render_demo (not saved)")
    scene.collection.children.link(coll)

    # Props as they are, with materials; the floor extended under the whole layout.
    floor = checker_material(bpy, "rd floor", (0.30, 0.30, 0.29), (0.24, 0.24, 0.23))
    stone = material(bpy, "rd pillar", (0.62, 0.55, 0.45), 0.7)
    wood = material(bpy, "rd chair", (0.33, 0.15, 0.05), 0.55)
    for ob in scene.objects:
        if ob.type != "MESH":
            continue
        m = floor if ob.name == "Ground" else stone if ob.name.startswith("Pillar") else wood
        ob.data.materials.clear()
        ob.data.materials.append(m)
    bm = bmesh.new()
    bmesh.ops.create_grid(
        bm, x_segments=1, y_segments=1, size=60.0, matrix=Matrix.Translation((5.0, 10.0, -0.002))
    )
    mesh_object(bpy, bm, "rd floor extension", floor, coll)

    fit_points = []
    report = []
    paths = []
    labels = []
    white = material(bpy, "rd joins", (0.9, 0.9, 0.9), 0.4)
    for name in VIEWS[view]["characters"]:
        ob = bpy.data.objects.get(name)
        if ob is None:
            raise SystemExit(f"render_demo: no object '{name}' in the scene (re-run ./dev demo)")
        try:
            meta, arrays = api.load_plan_record(ob)
        except api.MotionPatchesError as exc:
            raise SystemExit(f"render_demo: {exc} (re-run ./dev demo)") from None
        colour = COLOURS[name]
        f0 = int(meta["frame_start"])
        ground = arrays["ground"]
        path_tube(
            bpy,
            f"rd {name} path",
            ground[:, :2],
            0.015,
            0.03,
            material(bpy, f"rd {name} path", colour, 0.5),
            coll,
        )
        joins = [
            ground[b - f0, :2] for b in meta.get("boundaries", []) if 0 <= b - f0 < len(ground)
        ]
        disc(bpy, bmesh, Matrix, f"rd {name} joins", joins, 0.07, 0.03, white, coll)
        gx, gy, gh = meta["goal"]
        arrow(
            bpy,
            bmesh,
            Matrix,
            f"rd {name} goal",
            gx,
            gy,
            gh,
            material(bpy, f"rd {name} goal", colour, 0.5),
            coll,
        )
        if VIEWS[view]["labels"]:
            labels.append(
                label(
                    bpy,
                    name,
                    ground[0, 0],
                    ground[0, 1],
                    2.1,
                    material(bpy, f"rd {name} label", (0.95, 0.95, 0.95), 0.5, 0.6),
                    coll,
                )
            )
            fit_points.extend(
                Vector((ground[0, 0] + dx, ground[0, 1] + dy, 2.6))
                for dx, dy in ((-1, -1), (1, 1), (-1, 1), (1, -1))
            )
        frames = pick_frames(meta, arrays, copies)
        worst = 0.0
        if figures == "bodies":
            api.add_bodies([ob])
            parts = addon.adapter.bodies.parts(ob)
        for i, f in enumerate(frames):
            scene.frame_set(f)
            dg = bpy.context.evaluated_depsgraph_get()
            ev = ob.evaluated_get(dg)
            t = i / max(1, len(frames) - 1)
            mat = material(bpy, f"rd {name} f{f}", tint(colour, t), 0.45)
            if figures == "bodies":
                fig = body_figure(bpy, bmesh, parts, dg, f"rd {name} f{f}", mat, coll)
            else:
                fig = stick_figure(bpy, bmesh, Matrix, ev, f"rd {name} f{f}", mat, coll)
            fit_points.extend(fig.matrix_world @ Vector(c) for c in fig.bound_box)
            hips = ev.matrix_world @ ev.pose.bones[meta["root_name"]].head
            worst = max(worst, (hips - Vector(arrays["root"][f - f0])).length)
        if figures == "bodies":  # only the copies are drawn, not the live body
            api.remove_bodies([ob])
        fit_points.extend(Vector((x, y, 0.0)) for x, y in ground[::10, :2])
        paths.append(ground[:, :2])
        report.append((name, frames, worst))
    # Keep in frame, whole, the props the paths pass near.
    path_xy = np.concatenate(paths)
    for ob in scene.objects:
        if ob.type == "MESH" and VIEWS[view]["props"] and VIEWS[view]["props"] in ob.name:
            x, y = ob.matrix_world.translation.xy
            if np.hypot(path_xy[:, 0] - x, path_xy[:, 1] - y).min() < VIEWS[view]["near"]:
                fit_points.extend(ob.matrix_world @ Vector(c) for c in ob.bound_box)
    return labels, fit_points, report


def frame_points(bpy, scene, cam, points, margin):
    """Move ``cam`` (rotation fixed) so ``points`` fill the frame, centred, with a margin."""
    from bpy_extras.object_utils import world_to_camera_view
    from mathutils import Vector

    rot = cam.rotation_euler.to_matrix()
    right, up, fwd = rot @ Vector((1, 0, 0)), rot @ Vector((0, 1, 0)), rot @ Vector((0, 0, -1))
    centre = sum(points, Vector()) / len(points)
    cam.location = centre - fwd * 30.0
    w, h = scene.render.resolution_x, scene.render.resolution_y
    half_w = cam.data.sensor_width / (2 * cam.data.lens)  # tan(horizontal fov / 2)
    for _ in range(30):
        bpy.context.view_layer.update()
        proj = [world_to_camera_view(scene, cam, p) for p in points]
        xs, ys = [p.x for p in proj], [p.y for p in proj]
        depth = sum(p.z for p in proj) / len(proj)
        span_w = 2 * depth * half_w
        span_h = span_w * h / w
        cam.location += right * ((min(xs) + max(xs)) / 2 - 0.5) * span_w
        cam.location += up * ((min(ys) + max(ys)) / 2 - 0.5) * span_h
        fill = max((max(xs) - min(xs)), (max(ys) - min(ys))) / (1 - 2 * margin)
        cam.location += fwd * depth * (1 - fill) * 0.7
    bpy.context.view_layer.update()


def camera_and_light(bpy, view, fit_points, size):
    from mathutils import Euler

    scene = bpy.context.scene
    spec = VIEWS[view]
    cam = bpy.data.objects.new("rd camera", bpy.data.cameras.new("rd camera"))
    scene.collection.objects.link(cam)
    cam.data.lens = spec["lens"]
    cam.data.sensor_fit = "HORIZONTAL"
    az, pitch = math.radians(spec["azimuth"]), math.radians(spec["pitch"])
    # Blender camera looks down -Z; X rotation 90 - pitch tilts it up from straight down.
    cam.rotation_euler = Euler((math.pi / 2 - pitch, 0.0, -az), "XYZ")
    scene.camera = cam
    scene.render.resolution_x, scene.render.resolution_y = size
    frame_points(bpy, scene, cam, fit_points, margin=0.04)

    sun = bpy.data.objects.new("rd sun", bpy.data.lights.new("rd sun", "SUN"))
    scene.collection.objects.link(sun)
    sun.data.energy = 3.5
    sun.data.angle = math.radians(4.0)
    sun.rotation_euler = Euler((math.radians(40), 0.0, -az + math.radians(35)), "XYZ")

    world = bpy.data.worlds.new("rd sky")
    if world.node_tree is None:
        world.use_nodes = True
    bg = world.node_tree.nodes.get("Background")
    bg.inputs["Color"].default_value = (0.55, 0.65, 0.80, 1.0)
    bg.inputs["Strength"].default_value = 0.9
    scene.world = world
    return cam


def render_settings(scene, samples, out):
    import _cycles

    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = samples
    scene.cycles.use_adaptive_sampling = True
    scene.cycles.max_bounces = 4
    denoiser = None
    if getattr(_cycles, "with_openimagedenoise", False):
        scene.cycles.use_denoising = True
        scene.cycles.denoiser = "OPENIMAGEDENOISE"
        denoiser = "OpenImageDenoise"
    else:
        scene.cycles.use_denoising = False
    scene.render.resolution_percentage = 100
    scene.render.film_transparent = False
    scene.render.image_settings.file_format = "PNG"
    scene.render.image_settings.color_mode = "RGB"
    scene.render.image_settings.color_depth = "8"
    scene.render.image_settings.compression = 100
    scene.render.filepath = str(out)
    scene.view_settings.view_transform = "AgX"
    try:
        scene.view_settings.look = "AgX - Medium High Contrast"
    except TypeError:
        pass
    return denoiser


@contextlib.contextmanager
def quiet(enabled):
    """Drop Blender's per-tile progress lines (written to fd 1 by C code) while rendering."""
    if not enabled:
        yield
        return
    sys.stdout.flush()
    saved = os.dup(1)
    with open(os.devnull, "w") as null:
        os.dup2(null.fileno(), 1)
        try:
            yield
        finally:
            sys.stdout.flush()
            os.dup2(saved, 1)
            os.close(saved)


def main(argv):
    args = parse_args(argv)
    blend = Path(args.blend).resolve()
    if not blend.is_file():
        print(
            f"render_demo: sample scene not found: {blend}\n"
            f"  generate it with ./dev demo (tools/demo.py), or pass --blend FILE",
            file=sys.stderr,
        )
        return 2
    out = Path(args.out or REPO / VIEWS[args.view]["out"]).resolve()
    t_start = time.perf_counter()
    bpy, addon = blender_session.start()
    bpy.ops.wm.open_mainfile(filepath=str(blend), load_ui=False)
    scene = bpy.context.scene
    saved_frame = scene.frame_current

    copies = args.copies or VIEWS[args.view].get("copies", 8)
    labels, fit_points, report = build(bpy, addon, args.view, copies, args.figures)
    scene.frame_set(saved_frame)
    size = tuple(args.size or VIEWS[args.view]["size"])
    cam = camera_and_light(bpy, args.view, fit_points, size)
    for lab in labels:
        lab.rotation_euler = cam.rotation_euler
    denoiser = render_settings(scene, args.samples, out)
    out.parent.mkdir(parents=True, exist_ok=True)

    t_render = time.perf_counter()
    with quiet(not args.verbose):
        bpy.ops.render.render(write_still=True)
    render_s = time.perf_counter() - t_render
    if not out.is_file():
        print(f"render_demo: the render did not write {out}", file=sys.stderr)
        return 1
    # Nothing is saved: the loaded copy is dropped when the process ends.

    print()
    print(
        "render_demo: %s view of %s (Blender %s)" % (args.view, blend.name, bpy.app.version_string)
    )
    for name, frames, worst in report:
        print(
            "  %-8s %s at frames %s "
            "(evaluated hips within %.2f cm of the plan's root)"
            % (
                name,
                "proxy body" if args.figures == "bodies" else "armature bones",
                ", ".join(map(str, frames)),
                worst * 100,
            )
        )
    print(
        "  Cycles CPU, %d samples, %dx%d, denoiser: %s"
        % (args.samples, size[0], size[1], denoiser or "none (not in this build)")
    )
    print("  render %.1f s, total %.1f s" % (render_s, time.perf_counter() - t_start))
    print("  wrote %s" % out)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
