# Renders the pictures of docs/blender.md with Blender's Workbench engine, headless (surfaceless EGL):
#   rigbake sample -o m.glb && rigbake place m.glb -o m.json && rigbake bake m.glb --muscles m.json -o b.glb
#   blender --background --factory-startup --python scripts/blender-doc-pictures.py -- b.glb m.json docs/images/blender
# The locator empties do not render, so small spheres ride them in the pictures (green origin, red
# insertion, yellow driver).
import os
import sys

import numpy

for _name, _alias in (("bool", bool), ("int", int), ("float", float), ("object", object)):
    if _name not in numpy.__dict__:
        setattr(numpy, _name, _alias)

import addon_utils  # noqa: E402
import bpy  # noqa: E402
from mathutils import Matrix, Vector  # noqa: E402

baked, muscles, out = sys.argv[sys.argv.index("--") + 1:][:3]
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "blender"))
bpy.ops.wm.read_factory_settings(use_empty=True)
addon_utils.enable("rigbake_blender", default_set=True)
from rigbake_blender import muscle_file, rig_build  # noqa: E402

scene = bpy.context.scene
scene.rigbake_import_muscles = os.path.abspath(muscles)
bpy.ops.import_scene.gltf(filepath=os.path.abspath(baked))
armature = next(o for o in bpy.data.objects if o.type == 'ARMATURE' and "rigbake_rig" in o)
for track in armature.animation_data.nla_tracks:
    track.mute = True
track = next(t for t in armature.animation_data.nla_tracks if t.name == "ElbowFlexion")
armature.animation_data.action = track.strips[0].action

colours = {"origin": (0.1, 0.8, 0.2, 1), "insertion": (0.9, 0.1, 0.1, 1), "driver": (0.95, 0.8, 0.1, 1)}
for obj in bpy.data.objects:
    if obj.type == 'MESH':
        obj.color = (0.75, 0.75, 0.75, 1)
for empty in muscle_file.locators(armature):
    if not empty["rigbake_muscle"].startswith("LeftBicep"):
        continue
    mesh = bpy.data.meshes.new("marker")
    sphere = bpy.data.objects.new(empty.name + "_marker", mesh)
    import bmesh
    shape = bmesh.new()
    bmesh.ops.create_uvsphere(shape, u_segments=16, v_segments=8, radius=0.008)
    shape.to_mesh(mesh)
    shape.free()
    scene.collection.objects.link(sphere)
    sphere.parent = empty
    sphere.color = colours[empty["rigbake_role"]]
    sphere.show_in_front = True

scene.render.engine = 'BLENDER_WORKBENCH'
scene.display.shading.light = 'STUDIO'
scene.display.shading.color_type = 'OBJECT'
scene.display.shading.show_xray = True
scene.display.shading.xray_alpha = 0.6
scene.render.resolution_x, scene.render.resolution_y = 480, 360
camera = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
scene.collection.objects.link(camera)
camera.data.type = 'ORTHO'
# From above: the elbow flexes the forearm forwards, so the bend and the biceps' front are in view.
camera.data.ortho_scale = 0.62
camera.location = (0.45, -0.12, 2.5)
camera.rotation_euler = (0, 0, 0)
scene.camera = camera


def render(name, frame):
    scene.frame_set(frame)
    bpy.context.view_layer.update()
    scene.render.filepath = os.path.join(out, name)
    bpy.ops.render.render(write_still=True)


os.makedirs(out, exist_ok=True)
render("1-imported.png", 0)
render("2-bulge.png", 24)
insertion = bpy.data.objects[rig_build.locator_name("LeftBicep", "insertion")]
x, y, z = muscle_file.rest_world(insertion)
parent = rig_build._bone_parent_rest(armature, insertion.parent_bone)
insertion.location = ((parent @ insertion.matrix_parent_inverse).inverted() @ Matrix.Translation((x + 0.04, y, z))).translation
render("3-insertion-moved.png", 24)
print("RIGBAKE_PICTURES " + out)
