# SPDX-License-Identifier: GPL-3.0-or-later
"""Proxy bodies (``api.add_bodies``, the Add Body button, ``--bodies``): a capsule round
every bone that follows the evaluated pose, meshes shared by a crowd of one rig, made
again without duplicates, refused for what is no armature, of human size on a centimetre
rig under a 0.01 scale, and never an obstacle for anyone's plan.

Every vertex of a capsule lies at its radius from its bone's segment (head to tail), so the
evaluated vertices measured against the evaluated bones say at once whether the body
follows the pose and how thick it is."""

import json
import sys

import bpy
import numpy as np
import pytest

from scene_helpers import empty, prop_box, walker_from

CMU_SCALE = 0.056444


@pytest.fixture
def walker(addon_module, mocap_dir, clean_scene):
    """CMU 16_15 (a straight walk, 4.3 m) playing on the armature 'Walker'."""
    clean_scene.render.fps = 30
    arm, _ = addon_module.api.import_mocap([mocap_dir / "cmu" / "16_15.bvh"], name="Walker")
    return arm


def bodies_io(addon_module):
    return sys.modules[addon_module.__name__ + ".adapter.bodies"]


def segment_distances(points, head, tail):
    """Distance of each point from the segment head-tail."""
    d = tail - head
    t = np.clip((points - head) @ d / max(float(d @ d), 1e-12), 0.0, 1.0)
    return np.linalg.norm(points - (head + t[:, None] * d), axis=1)


def measured(addon_module, character):
    """{bone: (min, max) distance of its capsule's evaluated world vertices from the
    evaluated bone's world segment}, at the current frame."""
    dg = bpy.context.evaluated_depsgraph_get()
    ev = character.evaluated_get(dg)
    mw = np.array(ev.matrix_world)
    out = {}
    for part in bodies_io(addon_module).parts(character):
        pb = ev.pose.bones[part.parent_bone]
        head, tail = ((mw @ np.append(np.array(v), 1.0))[:3] for v in (pb.head, pb.tail))
        pe = part.evaluated_get(dg)
        mesh = pe.to_mesh()
        co = np.empty(len(mesh.vertices) * 3)
        mesh.vertices.foreach_get("co", co)
        pe.to_mesh_clear()
        m = np.array(pe.matrix_world)
        world = co.reshape(-1, 3) @ m[:3, :3].T + m[:3, 3]
        dist = segment_distances(world, head, tail)
        out[part.parent_bone] = (float(dist.min()), float(dist.max()))
    return out


def test_the_body_follows_the_evaluated_pose(addon_module, walker):
    res = addon_module.api.add_bodies([walker])
    assert res.characters == ["Walker"] and res.parts == len(walker.data.bones) == 31
    scene = bpy.context.scene
    hips = []
    for frame in (1, 60, 120):  # the walk goes 4.3 m in 117 frames at 30 fps
        scene.frame_set(frame)
        dist = measured(addon_module, walker)
        assert set(dist) == {b.name for b in walker.data.bones}
        for bone, (lo, hi) in dist.items():
            assert hi - lo < 1e-4, f"frame {frame}: '{bone}' is off its bone"
            assert 0.015 < hi < 0.12, f"frame {frame}: '{bone}' is {hi * 100:.1f} cm thick"
        ev = walker.evaluated_get(bpy.context.evaluated_depsgraph_get())
        hips.append(np.array(ev.matrix_world @ ev.pose.bones["Hips"].head))
    assert np.linalg.norm(hips[2] - hips[0]) > 3.0  # the pose did change: it walked
    assert dist["Head"][1] == pytest.approx(0.09, abs=1e-4)  # the head and torso sizes
    assert dist["Spine"][1] == pytest.approx(0.11, abs=1e-4)


def test_a_crowd_of_one_rig_shares_the_meshes_each_in_its_colour(addon_module, walker):
    crowd = [walker] + [walker_from(walker, f"Walker{k}", (2.0 * k, 0, 0)) for k in (1, 2, 3)]
    res = addon_module.api.add_bodies(crowd)
    assert res.parts == 4 * 31 and res.meshes == 31
    io = bodies_io(addon_module)
    by_bone = {}
    for ob in crowd:
        for part in io.parts(ob):
            by_bone.setdefault(part.parent_bone, set()).add(part.data.as_pointer())
    assert all(len(meshes) == 1 for meshes in by_bone.values())  # one datablock per bone
    assert sum(1 for m in bpy.data.meshes if io.SHAPE_KEY in m.keys()) == 31
    colours = set()
    for ob in crowd:
        (mat,) = {s.material for p in io.parts(ob) for s in p.material_slots}
        assert all(s.link == "OBJECT" for p in io.parts(ob) for s in p.material_slots)
        colours.add(tuple(round(c, 3) for c in mat.diffuse_color))
    assert len(colours) == 4


def test_a_body_made_again_replaces_the_old_one(addon_module, walker):
    api = addon_module.api
    # The user's own mesh on the rig's head: never the add-on's to remove.
    hat = prop_box("Hat", 0.0, 0.0, size=(0.2, 0.2, 0.1))
    hat.parent, hat.parent_type, hat.parent_bone = walker, "BONE", "Head"
    api.add_bodies([walker])
    names = sorted(o.name for o in bpy.data.objects)
    counts = (len(bpy.data.objects), len(bpy.data.meshes), len(bpy.data.materials))
    api.add_bodies([walker], colour=(0.1, 0.5, 0.2))
    assert sorted(o.name for o in bpy.data.objects) == names  # no "Walker body Head.001"
    assert (len(bpy.data.objects), len(bpy.data.meshes), len(bpy.data.materials)) == counts
    (mat,) = {s.material for p in bodies_io(addon_module).parts(walker) for s in p.material_slots}
    assert tuple(mat.diffuse_color)[:3] == pytest.approx((0.1, 0.5, 0.2))
    assert api.remove_bodies([walker]) == 31
    assert not api.has_body(walker) and list(walker.children) == [hat]
    assert [m.name for m in bpy.data.meshes] == [hat.data.name]
    assert not len(bpy.data.materials)


def test_what_is_no_armature_is_refused_by_name_and_nothing_is_made(addon_module, walker):
    api = addon_module.api
    crate = prop_box("Crate", 2.0, 0.0)
    before = len(bpy.data.objects)
    with pytest.raises(api.MotionPatchesError, match="'Crate' is a mesh, not an armature"):
        api.add_bodies([walker, crate])
    bare = bpy.data.objects.new("Bare", bpy.data.armatures.new("Bare"))
    bpy.context.scene.collection.objects.link(bare)
    with pytest.raises(api.MotionPatchesError, match="armature 'Bare' has no bones"):
        api.add_bodies([bare])
    with pytest.raises(api.MotionPatchesError, match="three numbers from 0 to 1"):
        api.add_bodies([walker], colour=(2.0, 0.0, 0.0))
    assert len(bpy.data.objects) == before + 1 and not api.has_body(walker)  # only Bare


def centimetre_rig(mocap_dir, name):
    """Subject 16 as an FBX import leaves a character: centimetre bones, Y-up data under a
    90 degree X rotation, the object scaled 0.01, playing 16_15."""
    before = set(bpy.data.objects)
    bpy.ops.import_anim.bvh(
        filepath=str(mocap_dir / "cmu" / "16_15.bvh"),
        global_scale=CMU_SCALE * 100.0,
        update_scene_fps=False,
    )
    (ob,) = [o for o in bpy.data.objects if o not in before]
    ob.name = name
    bpy.context.view_layer.objects.active = ob
    ob.rotation_euler = (-np.pi / 2, 0.0, 0.0)
    bpy.ops.object.transform_apply(location=False, rotation=True, scale=False)
    ob.rotation_euler = (np.pi / 2, 0.0, 0.0)
    ob.scale = (0.01, 0.01, 0.01)
    return ob


def test_a_centimetre_rig_under_a_hundredth_scale_gets_a_body_of_human_size(
    addon_module, walker, mocap_dir
):
    rig = centimetre_rig(mocap_dir, "Scaled")
    addon_module.api.add_bodies([walker, rig])
    bpy.context.scene.frame_set(40)
    metre, scaled = measured(addon_module, walker), measured(addon_module, rig)
    for bone, (lo, hi) in metre.items():
        assert scaled[bone][1] - scaled[bone][0] < 1e-4  # on its bone
        assert scaled[bone][1] == pytest.approx(hi, abs=1e-4), bone  # as thick, in metres


def test_bodies_are_no_obstacles(addon_module, walker):
    """Another character's body must not block a plan (nor its own): the obstacles the
    planner reads leave every body part out."""
    other = walker_from(walker, "Other", (1.0, 0.0, 0.0))
    addon_module.api.add_bodies([walker, other])
    prop_box("Crate", 3.0, 0.0)
    dg = bpy.context.evaluated_depsgraph_get()
    names = [o.name for o in addon_module.api.scene_io.obstacles(bpy.context.scene, dg)]
    assert names == ["Crate"]


def test_the_buttons_add_and_remove_the_selected_characters_bodies(addon_module, walker):
    other = walker_from(walker, "Other", (1.0, 0.0, 0.0))
    ops = bpy.ops.motion_patches
    for ob in bpy.context.scene.objects:
        ob.select_set(False)
    bpy.context.view_layer.objects.active = None
    assert not ops.add_body.poll() and not ops.remove_body.poll()
    walker.select_set(True)
    other.select_set(True)
    assert "UNDO" in addon_module.operators.bodies.MOTION_PATCHES_OT_add_body.bl_options
    bpy.ops.ed.undo_push(message="Before bodies")
    assert ops.add_body("EXEC_DEFAULT", True) == {"FINISHED"}  # its own undo step
    api = addon_module.api
    assert api.has_body(walker) and api.has_body(other)
    assert bpy.ops.ed.undo() == {"FINISHED"}
    walker, other = bpy.data.objects["Walker"], bpy.data.objects["Other"]
    assert not any(bodies_io(addon_module).is_part(o) for o in bpy.data.objects)
    assert bpy.ops.ed.redo() == {"FINISHED"}
    walker, other = bpy.data.objects["Walker"], bpy.data.objects["Other"]
    assert api.has_body(walker) and api.has_body(other)
    assert ops.remove_body() == {"FINISHED"}
    assert not api.has_body(walker) and not api.has_body(other)
    assert ops.remove_body() == {"FINISHED"}  # nothing left: "0 capsules removed"


def test_a_duplicated_crowd_of_a_character_with_a_body_has_bodies(addon_module, walk_blend):
    bpy.ops.wm.open_mainfile(filepath=str(walk_blend))
    api, scene = addon_module.api, bpy.context.scene
    walker = walker_from(bpy.data.objects["Source"], "Walker", (0.0, 0.0, 0.0))
    api.add_bodies([walker])
    pairs = api.duplicate_crowd(scene, walker, 3, ((-6, 3), (-2, 8)), ((4, 3), (8, 8)))
    io = bodies_io(addon_module)
    meshes = {p.data.as_pointer() for p in io.parts(walker)}
    for ob, _ in pairs:
        assert {p.data.as_pointer() for p in io.parts(ob)} == meshes
    api.remove_crowd(pairs)
    assert sum(1 for o in bpy.data.objects if io.is_part(o)) == 31  # the walker's own


def test_plan_with_bodies_saves_characters_whose_bodies_walk_the_plan(
    addon_module, walk_blend, tmp_path
):
    """``plan --bodies``: the body is saved with the plan, and at a frame of the planned
    motion (NLA strips) it sits on the evaluated bones."""
    bpy.ops.wm.open_mainfile(filepath=str(walk_blend))
    walker_from(bpy.data.objects["Source"], "Walker", (0.0, 0.0, 0.0))
    out = tmp_path / "planned.blend"
    cli = addon_module.cli
    argv = ["plan", "--character", "Walker", "--goal-xyh", "5", "1", "0", "--bodies"]
    assert cli.main(argv + ["--save", str(out)]) == cli.OK
    bpy.ops.wm.open_mainfile(filepath=str(out))
    walker = bpy.data.objects["Walker"]
    assert addon_module.api.has_body(walker)
    meta, _ = addon_module.api.load_plan_record(walker)
    bpy.context.scene.frame_set((meta["frame_start"] + meta["frame_end"]) // 2)
    dist = measured(addon_module, walker)
    assert len(dist) == 31 and all(hi - lo < 1e-4 for lo, hi in dist.values())
    ev = walker.evaluated_get(bpy.context.evaluated_depsgraph_get())
    hips = ev.matrix_world @ ev.pose.bones["Hips"].head
    assert hips.xy.length > 1.0  # on its way to the goal 5 m off: the strips play


def test_crowd_with_bodies_gives_every_character_a_body(addon_module, walk_blend, capsys):
    bpy.ops.wm.open_mainfile(filepath=str(walk_blend))
    src = bpy.data.objects["Source"]
    for name, y in (("A", 0.0), ("B", -3.0)):
        walker_from(src, name, (0.0, y, 0.0))
        empty(f"Goal {name}", 6.0, y, 0.0)
    cli = addon_module.cli
    capsys.readouterr()
    argv = ["crowd", "--pair", "A", "Goal A", "--pair", "B", "Goal B", "--bodies", "--json"]
    assert cli.main(argv) == cli.OK
    doc = json.loads(capsys.readouterr().out)
    assert doc["bodies"] == {"characters": ["A", "B"], "parts": 62, "meshes": 31}
    api = addon_module.api
    assert api.has_body(bpy.data.objects["A"]) and api.has_body(bpy.data.objects["B"])
    assert not api.has_body(src)
