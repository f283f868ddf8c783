# SPDX-License-Identifier: GPL-3.0-or-later
"""What the GUI suite (./dev gui, a real Blender with its window) found, pinned down where
bpy-as-a-module can check it: labels that wrap instead of being cut, headed preference
sections, the overlay's blocked area (each prop grown by the radius, not whole cells) and
the scene's frame range following the plan."""

from types import SimpleNamespace

import bpy
import numpy as np
import pytest

from conftest import REPO_ROOT

SAMPLE = REPO_ROOT / "sample_blends" / "demo_walk.blend"


# --- labels --------------------------------------------------------------------------------


def fake_context(width):
    return SimpleNamespace(region=SimpleNamespace(width=width), preferences=bpy.context.preferences)


@pytest.mark.parametrize("width", [292, 400, 180])
def test_long_labels_wrap_to_the_sidebar_width(addon_module, width):
    sidebar = addon_module.panels.sidebar
    ctx = fake_context(width)
    for text in (
        "Select a planned character and analyse it",
        "Red fill: where the root cannot go (each prop grown by the radius); red "
        "squares: cells the planner marks occluded",
        "no locomotion patch is baked in this scene; bake one first",
    ):
        for icon in (False, True):
            lines = sidebar.wrap_text(text, ctx, icon)
            assert " ".join(lines) == text
            room = width - (sidebar.LABEL_INSET + (sidebar.ICON_WIDTH if icon else 0))
            words = [ln for ln in lines if " " in ln]  # a single word longer than room stays
            assert all(sidebar.text_width(ln, ctx) <= room for ln in words), (lines, room)
    # Drawn with no region (off screen): one line, as before.
    assert sidebar.wrap_text(
        "a b c", SimpleNamespace(region=None, preferences=bpy.context.preferences)
    ) == ["a b c"]


# --- preferences ---------------------------------------------------------------------------


class Recorder:
    """Records labels and properties; ``panel`` behaves like Blender's layout panels."""

    def __init__(self, log):
        self.log = log
        self.use_property_split = self.use_property_decorate = False

    def column(self, heading="", **kw):
        assert not heading, "a column heading labels only its first checkbox"
        return Recorder(self.log)

    row = box = column

    def panel(self, idname, default_closed=False):
        return Recorder(self.log), Recorder(self.log)

    def label(self, text="", **kw):
        self.log.append(("label", text))

    def prop(self, data, name, **kw):
        assert name in data.bl_rna.properties
        self.log.append(("prop", name))


def test_preferences_are_drawn_in_headed_sections(addon_module_name, addon_module):
    prefs = bpy.context.preferences.addons[addon_module_name].preferences
    log = []
    type(prefs).draw(SimpleNamespace(layout=Recorder(log), bl_rna=prefs.bl_rna), bpy.context)
    labels = [t for k, t in log if k == "label"]
    assert labels[:1] == ["Planning Defaults"] and "Bake Defaults" in labels
    props = [t for k, t in log if k == "prop"]
    planning = list(addon_module.props.PLANNING)
    bake = list(addon_module.props.BAKE)
    assert props == planning + bake
    i = log.index(("label", "Bake Defaults"))
    assert all(("prop", n) in log[:i] for n in planning) and all(
        ("prop", n) in log[i:] for n in bake
    )


def test_copy_step_says_its_unit(addon_module):
    name = (
        bpy.types.Object.bl_rna.properties["motion_patch"]
        .fixed_type.properties["clips"]
        .fixed_type.properties["copy_step"]
        .name
    )
    assert "°" in name


# --- overlay -------------------------------------------------------------------------------


def test_blocked_area_is_the_footprint_grown_by_the_radius(addon_module):
    overlay = addon_module.panels.overlay
    from_env = addon_module.motion_patches.props.environment
    chair = np.array([[-0.2, -0.22], [0.2, -0.22], [0.2, 0.22], [-0.2, 0.22]])
    for poly in (chair, chair[::-1]):
        outline = overlay.grown(poly, 0.25)
        assert len(outline) % 2 == 0
        d = from_env.distance_to_polygon(outline, chair)
        assert np.allclose(d, 0.25, atol=1e-9)  # every outline point at the radius
        # About 0.9 m x 0.94 m, not the 1.3 m square of whole 0.33 m cells.
        assert np.allclose(np.ptp(outline, axis=0), (0.9, 0.94), atol=1e-9)
        tris = np.array(overlay._fan_quads(outline, 0.01))
        assert len(tris) % 6 == 0
        # The fill covers the grown footprint's area (a polygon inscribed in it).
        a, b, c = tris[0::3, :2], tris[1::3, :2], tris[2::3, :2]
        u, v = b - a, c - a
        area = 0.5 * np.abs(u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0]).sum()
        exact = 0.4 * 0.44 + 2 * 0.25 * (0.4 + 0.44) + np.pi * 0.25**2
        assert exact * 0.98 < area <= exact + 1e-9


# --- frame range ---------------------------------------------------------------------------


def test_fitted_frame_range_rule(addon_module):
    fit = addon_module.api.fitted_frame_range
    assert fit((1, 250), [(1, 239)]) == (1, 239)  # Blender's default follows
    assert fit((1, 250), [(1, 380)]) == (1, 380)
    assert fit((1, 239), [(1, 120)], ours=(1, 239)) == (1, 120)  # ours follows a re-plan
    assert fit((1, 1000), [(1, 239)]) == (1, 1000)  # the user's longer range stays
    assert fit((20, 100), [(1, 239)]) == (1, 239)  # ... and is extended when short
    assert fit((1, 250), [(1, 120), (30, 400)]) == (1, 400)  # every planned character


def test_planning_sets_the_scene_frame_range(addon_module):
    if not SAMPLE.is_file():
        pytest.fail(f"{SAMPLE} is missing: ./dev test generates it before the Blender suites")
    bpy.ops.wm.open_mainfile(filepath=str(SAMPLE))
    api = addon_module.api
    scene = bpy.context.scene
    walker, goal = bpy.data.objects["Walker"], bpy.data.objects["Goal"]

    def span():
        metas = [api.load_plan_record(ob)[0] for ob in scene.objects if api.PLAN_KEY in ob]
        return (min(m["frame_start"] for m in metas), max(m["frame_end"] for m in metas))

    scene.frame_start, scene.frame_end = 1, 250
    scene.pop(api.FRAME_RANGE_KEY, None)
    api.plan_path(scene, walker, goal, frame_start=1)
    assert (scene.frame_start, scene.frame_end) == span()
    scene.frame_start, scene.frame_end = 1, 5000  # the user's own, longer
    api.plan_path(scene, walker, goal, frame_start=1)
    assert (scene.frame_start, scene.frame_end) == (1, 5000)
    scene.motion_patches.fit_frame_range = False  # off: untouched
    scene.frame_start, scene.frame_end = 1, 10
    api.plan_path(scene, walker, goal, frame_start=1)
    assert (scene.frame_start, scene.frame_end) == (1, 10)


# --- Blender's conventions (what a newcomer meets in the window) ---------------------------

# The sidebar at the default 1920x1200 layout (the GUI suite's screenshots): a panel's fields
# span 236 px. With use_property_split the label takes 40 % of that, right-aligned with a
# margin each side (0.4 of a 20 px widget unit): longer labels are cut to "Layer...".
FIELDS_WIDTH = 236
LABEL_COLUMN = 0.4 * FIELDS_WIDTH - 2 * 8
CHECKBOX = 24  # a checkbox's box and gap before its label


def label_width(text):
    """Width of ``text`` at the UI's 11 points (the interface scale is 0 without a window,
    so this measures with the font directly)."""
    import blf

    blf.size(0, 11)
    return blf.dimensions(0, text)[0]


class SplitRecorder:
    """A layout that passes its property split on to the layouts made in it, as Blender's
    does, and records each property with its label and whether it is split."""

    def __init__(self, log, split=False):
        self.log, self.use_property_split, self.use_property_decorate = log, split, True

    def row(self, *args, **kw):
        return SplitRecorder(self.log, self.use_property_split)

    column = box = split = row

    def label(self, *args, **kw):
        pass

    operator = label

    def prop(self, data, name, text=None, **kw):
        rna = data.bl_rna.properties[name]
        label = rna.name if text is None else text
        self.log.append((name, label, self.use_property_split, rna.type == "BOOLEAN"))

    prop_search = prop

    def template_list(self, listtype, list_id, data, items, active_data, active_prop, **kw):
        cls = getattr(bpy.types, listtype)
        for i, item in enumerate(getattr(data, items)):
            lay = SplitRecorder(self.log, self.use_property_split)
            cls.draw_item(None, bpy.context, lay, data, item, 0, active_data, active_prop, i)


@pytest.fixture
def every_panel_drawn(addon_module, walk_blend):
    """{panel: [(property, label, split, boolean)]} of every sidebar panel, drawn with a
    character active, and again with a tagged prop active (its clip a traversal)."""
    from scene_helpers import prop_box, walker_from

    bpy.ops.wm.open_mainfile(filepath=str(walk_blend))
    walker = walker_from(bpy.data.objects["Source"], "Walker")
    chair = prop_box("Chair", 3.0, 0.0)
    clip = chair.motion_patch.clips.add()
    clip.action, clip.kind = bpy.data.actions["16_15"], "TRAVERSAL"
    drawn = {}
    for active in (walker, chair):
        bpy.context.view_layer.objects.active = active
        for cls in addon_module.panels.classes:
            if not issubclass(cls, bpy.types.Panel) or (
                hasattr(cls, "poll") and not cls.poll(bpy.context)
            ):
                continue
            log = []
            cls.draw(SimpleNamespace(layout=SplitRecorder(log)), bpy.context)
            drawn.setdefault(cls.bl_label, log)
    return drawn


def test_sidebar_labels_fit_beside_their_fields(every_panel_drawn):
    assert label_width("Source Armature") > 60  # the font measures (not a headless stub)
    split = {p for panel, log in every_panel_drawn.items() for p in log if p[2]}
    # Blender's convention: label | field in the panels with fields.
    for panel in ("Locomotion Patches", "Object Patch", "Planning"):
        assert any(p[2] for p in every_panel_drawn[panel]), f"{panel}: no property split"
    for name, label, _, boolean in split:
        assert label, f"'{name}' is split with no label: its label column is empty"
        assert not boolean, f"checkbox '{label}' in the label column (cut when long)"
        assert label_width(label) <= LABEL_COLUMN, f"'{label}' is cut beside its field"
    for panel, log in every_panel_drawn.items():
        for name, label, is_split, boolean in log:
            if not is_split and boolean:
                assert label_width(label) <= FIELDS_WIDTH - CHECKBOX, f"'{label}' is cut"
    names = {p[0] for log in every_panel_drawn.values() for p in log}
    assert {"layer_in", "layer_out", "copy_step", "radius", "source_armature"} <= names


def test_goal_pickers_offer_places_not_cameras_lights_or_bodies(addon_module, walk_blend):
    bpy.ops.wm.open_mainfile(filepath=str(walk_blend))
    scene = bpy.context.scene
    api = addon_module.api
    cam = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    lamp = bpy.data.objects.new("Light", bpy.data.lights.new("Light", "POINT"))
    goal = bpy.data.objects.new("Goal", None)
    for ob in (cam, lamp, goal):
        scene.collection.objects.link(ob)
    api.add_bodies([bpy.data.objects["Source"]])
    body = next(o for o in scene.objects if o.parent == bpy.data.objects["Source"])
    for owner, name in ((scene.motion_patches, "goal"), (bpy.data.objects["Source"], None)):
        group = type(owner) if name else type(owner.motion_patches_character)
        poll = group.__annotations__["goal"].keywords["poll"]  # what the picker lists
        assert [poll(None, ob) for ob in (cam, lamp, body, goal)] == [False, False, False, True]
    start = type(bpy.data.objects["Source"].motion_patches_character).__annotations__
    assert not start["start_prop"].keywords["poll"](None, body)


def test_the_bvh_scale_shows_every_digit_of_cmus():
    scale = bpy.ops.motion_patches.import_mocap.get_rna_type().properties["scale"]
    assert scale.default == pytest.approx(0.056444) and scale.precision == 6


def test_an_imported_armature_is_named_after_its_subject(addon_module):
    name = addon_module.api.baking.subject_name
    assert name(["cmu/16_06.bvh", "cmu/16_15.bvh", "cmu/16_18.bvh"]) == "Subject 16"
    assert name(["actor-walk.bvh", "actor-turn.bvh"]) == "actor"
    assert name(["walk.bvh"]) == "walk"
    assert name(["02_01.bvh", "16_15.bvh"]) == "Mocap"  # two subjects


def test_a_plan_of_one_piece_says_1_piece(addon_module):
    res = SimpleNamespace(
        character="Walker",
        pieces=["walk"],
        frame_start=1,
        frame_end=31,
        length_m=1.0,
        cost=1.0,
        seconds=0.01,
    )
    line = addon_module.cli.plan.plan_line(res, 30.0)
    assert "1 piece," in line and "pieces" not in line
    res.pieces = ["walk", "turn"]
    assert "2 pieces," in addon_module.cli.plan.plan_line(res, 30.0)
