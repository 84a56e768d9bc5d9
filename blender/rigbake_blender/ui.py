# The rigbake panel (View3D > Sidebar > rigbake) and its operators. Every failure is one Blender
# report line carrying rigbake's code (docs/errors.md).
import os

import bpy
from bpy.props import FloatProperty, StringProperty

from . import cli, jiggle_play, muscle_file


class RigbakePreferences(bpy.types.AddonPreferences):
    bl_idname = __package__
    rigbake_path: StringProperty(name="rigbake executable", subtype='FILE_PATH',
                                 description="The rigbake CLI; empty: $RIGBAKE, then rigbake on PATH")
    runtime_library: StringProperty(name="Runtime library", subtype='FILE_PATH',
                                    description="librigbake_runtime.so, which plays the jiggles; empty: "
                                    "$RIGBAKE_RUNTIME_LIBRARY, then beside the rigbake executable, then the system's")

    def draw(self, context):
        self.layout.prop(self, "rigbake_path")
        self.layout.prop(self, "runtime_library")


def _remove_rig(armature):
    """Removes an imported character (the armature's root hierarchy) and its rig empties."""
    root = armature
    while root.parent is not None:
        root = root.parent
    doomed = [root] + list(root.children_recursive)
    doomed += [o for o in bpy.data.objects if "rigbake_role" in o and o.parent in doomed]
    for collection in list(bpy.data.collections):
        if collection.name.startswith("rigbake muscle rig"):
            doomed += list(collection.objects)
    for obj in set(doomed):
        bpy.data.objects.remove(obj, do_unlink=True)


def import_bake(context, path, muscles_path):
    context.scene.rigbake_import_muscles = muscles_path
    result = bpy.ops.import_scene.gltf(filepath=path)
    return 'FINISHED' in result


class RIGBAKE_OT_place(bpy.types.Operator):
    """Place the muscles on the character with `rigbake place`"""
    bl_idname = "rigbake.place"
    bl_label = "Place muscles"

    def execute(self, context):
        scene = context.scene
        ok, message = cli.run(context, ["place", bpy.path.abspath(scene.rigbake_character), "-o",
                                         bpy.path.abspath(scene.rigbake_muscles)])
        self.report({'INFO'} if ok else {'ERROR'}, message)
        return {'FINISHED'} if ok else {'CANCELLED'}


class RIGBAKE_OT_bake(bpy.types.Operator):
    """Bake the character with the muscle file (`rigbake bake --muscles`) and reload the result"""
    bl_idname = "rigbake.bake"
    bl_label = "Bake and reload"

    def execute(self, context):
        scene = context.scene
        baked = bpy.path.abspath(scene.rigbake_baked)
        muscles = bpy.path.abspath(scene.rigbake_muscles)
        ok, message = cli.run(context, ["bake", bpy.path.abspath(scene.rigbake_character), "--muscles", muscles, "-o", baked])
        if not ok:
            self.report({'ERROR'}, message)
            return {'CANCELLED'}
        armature = muscle_file.rig_armature(context)
        if armature is not None:
            _remove_rig(armature)
        if not import_bake(context, baked, muscles):
            self.report({'ERROR'}, "BLENDER_IMPORT_FAILED %s: the glTF importer refused the bake" % baked)
            return {'CANCELLED'}
        self.report({'INFO'}, message)
        return {'FINISHED'}


class RIGBAKE_OT_validate(bpy.types.Operator):
    """Check the baked character with `rigbake validate`"""
    bl_idname = "rigbake.validate"
    bl_label = "Validate"

    def execute(self, context):
        scene = context.scene
        arguments = ["validate", bpy.path.abspath(scene.rigbake_baked), "--no-pictures",
                     "--report", os.path.join(bpy.app.tempdir, "rigbake-report")]
        # The character Bake and reload baked: validate then measures the bake's own regions and plain
        # skinning, not the weights handed back to the muscles' carriers (docs/validate.md).
        if scene.rigbake_character:
            arguments += ["--input", bpy.path.abspath(scene.rigbake_character)]
        ok, message = cli.run(context, arguments)
        self.report({'INFO'} if ok else {'ERROR'}, message)
        return {'FINISHED'} if ok else {'CANCELLED'}


class RIGBAKE_OT_export_muscles(bpy.types.Operator):
    """Write the muscle JSON (`rigbake place`'s format) with the locators as they are now"""
    bl_idname = "rigbake.export_muscles"
    bl_label = "Export muscle file"
    filepath: StringProperty(subtype='FILE_PATH')

    def execute(self, context):
        armature = muscle_file.rig_armature(context)
        if armature is None:
            self.report({'ERROR'}, "BLENDER_NO_RIG: select the armature of an imported rigbake bake")
            return {'CANCELLED'}
        path = bpy.path.abspath(self.filepath or context.scene.rigbake_muscles)
        try:
            muscle_file.export(armature, path)
        except (muscle_file.MuscleFileError, OSError) as error:
            self.report({'ERROR'}, str(error))
            return {'CANCELLED'}
        self.report({'INFO'}, "wrote " + path)
        return {'FINISHED'}

    def invoke(self, context, event):
        if not self.filepath:
            self.filepath = context.scene.rigbake_muscles
        context.window_manager.fileselect_add(self)
        return {'RUNNING_MODAL'}


class RIGBAKE_OT_mirror(bpy.types.Operator):
    """Mirror every Left locator and factor onto its Right counterpart"""
    bl_idname = "rigbake.mirror"
    bl_label = "Mirror left to right"

    def execute(self, context):
        armature = muscle_file.rig_armature(context)
        if armature is None:
            self.report({'ERROR'}, "BLENDER_NO_RIG: select the armature of an imported rigbake bake")
            return {'CANCELLED'}
        count = muscle_file.mirror_left_to_right(armature)
        self.report({'INFO'}, "mirrored %d parts" % count)
        return {'FINISHED'}


class RIGBAKE_OT_bake_jiggles(bpy.types.Operator):
    """Key the jiggles, played from the first frame, into the armature's action (they then play without the add-on)"""
    bl_idname = "rigbake.bake_jiggles"
    bl_label = "Bake jiggles to action"

    def execute(self, context):
        armature = muscle_file.rig_armature(context)
        if armature is None:
            self.report({'ERROR'}, "BLENDER_NO_RIG: select the armature of an imported rigbake bake")
            return {'CANCELLED'}
        try:
            keys = jiggle_play.bake_jiggles(context, armature)
        except (jiggle_play.RuntimeMissing, RuntimeError) as error:
            self.report({'ERROR'}, str(error))
            return {'CANCELLED'}
        self.report({'INFO'}, "keyed %d jiggle rotations" % keys)
        return {'FINISHED'}


class RIGBAKE_PT_panel(bpy.types.Panel):
    bl_label = "rigbake"
    bl_space_type = 'VIEW_3D'
    bl_region_type = 'UI'
    bl_category = "rigbake"

    def draw(self, context):
        layout = self.layout
        scene = context.scene
        for prop in ("rigbake_character", "rigbake_muscles", "rigbake_baked"):
            layout.prop(scene, prop)
        row = layout.row(align=True)
        row.operator("rigbake.place")
        row.operator("rigbake.bake")
        row.operator("rigbake.validate")
        armature = muscle_file.rig_armature(context)
        if armature is None:
            layout.label(text="Select an imported rigbake bake")
            return
        row = layout.row(align=True)
        row.operator("rigbake.export_muscles")
        row.operator("rigbake.mirror")
        row = layout.row()
        row.label(text=jiggle_play.status(armature))
        if armature.get("rigbake_jiggles", 0):
            row.operator("rigbake.bake_jiggles")
        box = layout.box()
        header = box.row()
        for title in ("muscle", "compression", "stretch", "ratio / twist", "up / side / scale"):
            header.label(text=title)
        for pose_bone in armature.pose.bones:
            if "rigbake_muscle" not in pose_bone:
                continue
            row = box.row()
            row.label(text=pose_bone["rigbake_muscle"])
            row.prop(pose_bone, '["rigbake_compression"]', text="")
            row.prop(pose_bone, '["rigbake_stretch"]', text="")
            row.label(text="%.3f / %+.2f rad" % (pose_bone.get("rigbake_ratio", 1.0), pose_bone.get("rigbake_twist", 0.0)))
            row.label(text="%.4f / %.4f / %.3f" % (pose_bone.location[1], pose_bone.location[2], pose_bone.scale[1]))


CLASSES = (RigbakePreferences, RIGBAKE_OT_place, RIGBAKE_OT_bake, RIGBAKE_OT_validate,
           RIGBAKE_OT_export_muscles, RIGBAKE_OT_mirror, RIGBAKE_OT_bake_jiggles, RIGBAKE_PT_panel)


def register():
    for cls in CLASSES:
        bpy.utils.register_class(cls)
    scene = bpy.types.Scene
    scene.rigbake_character = StringProperty(name="Character", subtype='FILE_PATH',
                                             description="The unbaked character (.glb, .gltf, .vrm, .fbx)")
    scene.rigbake_muscles = StringProperty(name="Muscle file", subtype='FILE_PATH',
                                           description="The muscle JSON that place writes and bake reads")
    scene.rigbake_baked = StringProperty(name="Baked file", subtype='FILE_PATH', description="The bake to write and load")
    scene.rigbake_import_muscles = StringProperty(
        name="Muscle file for import", subtype='FILE_PATH',
        description="The muscle JSON a glTF import of a bake attaches to its rig (needed to export it back)")
    jiggle_play.register()


def unregister():
    jiggle_play.unregister()
    for name in ("rigbake_character", "rigbake_muscles", "rigbake_baked", "rigbake_import_muscles"):
        delattr(bpy.types.Scene, name)
    for cls in reversed(CLASSES):
        bpy.utils.unregister_class(cls)
