# rigbake's Blender add-on (docs/blender.md): on glTF import of a rigbake bake it rebuilds the
# RIGBAKE_muscle_rig extension (docs/extensions/RIGBAKE_muscle_rig.md) as a live rig of empties,
# constraints and drivers, lists the muscles in a panel, writes the muscle JSON back
# (docs/muscle-json.md) and runs `rigbake place`, `bake` and `validate` on the character.
bl_info = {
    "name": "rigbake muscle rig",
    "author": "The rigbake project",
    # rigbake's version (CMakeLists.txt `project(rigbake VERSION ...)`); a test keeps them equal.
    "version": (0, 1, 0),
    "blender": (3, 4, 0),
    "location": "glTF import; View3D > Sidebar > rigbake",
    "description": "Plays rigbake's muscle rig live, edits its locators and writes the muscle file back",
    "doc_url": "https://github.com/rigbake/rigbake/blob/main/docs/blender.md",
    "category": "Rigging",
}

if "bpy" in locals():
    import importlib
    for _module in (gltf_frames, runtime_lib, rig_build, muscle_file, cli, jiggle_play, ui):  # noqa: F821
        importlib.reload(_module)
else:
    from . import gltf_frames, runtime_lib, rig_build, muscle_file, cli, jiggle_play, ui

import bpy  # noqa: E402


class glTF2ImportUserExtension:
    """Hook the glTF importer calls (io_scene_gltf2, Blender 3.4): after the nodes and the animations
    exist, builds the rig of every armature the file's RIGBAKE_muscle_rig names."""

    def __init__(self):
        from io_scene_gltf2.io.com.gltf2_io_extensions import Extension
        # Listed as handled (the importer only reads the list of "required" ones), so it does not warn
        # that the extension is unsupported; the file itself is not changed.
        self.extensions = [Extension(name=rig_build.EXTENSION, extension={}, required=True)]

    def gather_import_scene_after_animation_hook(self, gltf_scene, blender_scene, gltf):
        try:
            rig_build.build_from_import(gltf, bpy.context.scene.rigbake_import_muscles)
        except Exception as error:  # the importer swallows hook exceptions; say it once, plainly
            print("RIGBAKE_IMPORT_FAILED " + str(error))
            raise


def register():
    ui.register()


def unregister():
    ui.unregister()
