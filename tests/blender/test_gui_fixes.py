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
