import bpy
from bpy.props import IntProperty, StringProperty

from .. import api


class MOTION_PATCHES_OT_bake_locomotion_patch(bpy.types.Operator):
    """Bake a tilable locomotion patch from a straight clip and turn clips"""
    bl_idname = "motion_patches.bake_locomotion_patch"
    bl_label = "Bake Locomotion Patch"
    bl_options = {'REGISTER', 'UNDO'}

    layer: StringProperty(name="Layer", default="walk", description="Gait name of the patch")
    straight: StringProperty(name="Straight Action",
                             description="Straight clip (default: the scene's bake setting)")
    turns: StringProperty(name="Turn Actions",
                          description="Comma-separated turn clips (default: the scene's list)")
    cells: IntProperty(name="Cells", default=8, min=2, max=8)
    nodes: IntProperty(name="Nodes per Edge", default=8, min=2, max=8)

    def execute(self, context):
        settings = context.scene.motion_patches
        try:
            straight = _action(self.straight) if self.straight else settings.straight_action
            turns = ([_action(n.strip()) for n in self.turns.split(",") if n.strip()]
                     if self.turns else [r.action for r in settings.turn_actions if r.action])
            arm = settings.source_armature or context.active_object
            wm = context.window_manager
            wm.progress_begin(0, 100)
            try:
                res = api.bake_locomotion_patch(
                    context.scene, arm, straight, turns, layer=self.layer, cells=self.cells,
                    nodes=self.nodes, progress=lambda f: wm.progress_update(int(f * 100)))
            finally:
                wm.progress_end()
        except api.MotionPatchesError as exc:
            self.report({'ERROR'}, str(exc))
            return {'CANCELLED'}
        st = res.stats
        self.report({'INFO'}, f"Baked '{res.name}': {st['kept']} segments kept, {st['culled']} "
                              f"culled ({res.seconds:.1f} s)")
        return {'FINISHED'}


def _action(name):
    act = bpy.data.actions.get(name)
    if act is None:
        raise api.MotionPatchesError(f"no action named '{name}'")
    return act


classes = (MOTION_PATCHES_OT_bake_locomotion_patch,)
