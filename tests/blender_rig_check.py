# Run by tests/blender_addon_test.cpp inside Debian's Blender, headless:
#   blender --background --factory-startup --python tests/blender_rig_check.py -- MODE JOBS.json
# MODE "live": enables the add-on from the repository's blender/ directory, and for every job imports
# the bake with its muscle file, samples every clip at every key, exports the muscle file without an
# edit, saves the .blend, moves one locator, and exports again. MODE "reopen": opens every job's saved
# .blend with the add-on NOT enabled and samples every clip again. Each job's results go to files in
# its own directory; the C++ test compares them with rigbake's C++ runtime and a bake.
import json
import os
import sys

import numpy

# Debian's Blender 3.4 glTF importer still uses numpy.bool and friends, which numpy 1.24 removed.
for _name, _alias in (("bool", bool), ("int", int), ("float", float), ("object", object)):
    if _name not in numpy.__dict__:
        setattr(numpy, _name, _alias)

import addon_utils  # noqa: E402
import bpy  # noqa: E402
from mathutils import Matrix  # noqa: E402

Z_UP_TO_Y_UP = Matrix(((1, 0, 0, 0), (0, 0, 1, 0), (0, -1, 0, 0), (0, 0, 0, 1)))


def rig_armature():
    return next(o for o in bpy.data.objects if o.type == 'ARMATURE' and "rigbake_rig" in o)


def key_frames(action):
    frames = set()
    for fcurve in action.fcurves:
        frames.update(round(k.co[0], 4) for k in fcurve.keyframe_points)
    return sorted(frames)


def sample(armature):
    """Every clip at every key: the skinned joints' world matrices in glTF model space (the bone's
    pose times its rest, mapped back: the skinned bone's rest is the joint's bind frame), and the
    drivers, as {glTF animation index: {"times", "skinned", "ratio", "twist"}}."""
    scene = bpy.context.scene
    rig = json.loads(armature["rigbake_rig"])
    bones = [next(b for b in armature.pose.bones if b.get("rigbake_muscle") == m["name"]) for m in rig["muscles"]]
    if armature.animation_data:
        for track in armature.animation_data.nla_tracks:
            track.mute = True
    tracks = list(armature.get("rigbake_clips", []))
    helpers = json.loads(armature.get("rigbake_helpers", "{}"))
    out = {}
    for track in armature.animation_data.nla_tracks if armature.animation_data else []:
        if track.name not in tracks or not track.strips:
            continue
        action = track.strips[0].action
        armature.animation_data.action = action
        # A clip that does not key a joint leaves it where the previous clip put it: start at rest.
        for pose_bone in armature.pose.bones:
            pose_bone.matrix_basis = Matrix.Identity(4)
        clip = {"times": [], "skinned": [], "ratio": [], "twist": [], "helpers": []}
        for frame in key_frames(action):
            scene.frame_set(int(frame), subframe=frame - int(frame))
            # The add-on's frame handler turns the jiggled bones after the frame's evaluation.
            bpy.context.view_layer.update()
            clip["times"].append(frame * scene.render.fps_base / scene.render.fps)
            matrices = []
            for pose_bone in bones:
                world = Z_UP_TO_Y_UP @ armature.matrix_world @ pose_bone.matrix
                matrices.extend(world[r][c] for c in range(4) for r in range(4))
            clip["skinned"].append(matrices)
            # Helper joints (base, tip, driver) are empties: their world matrices, glTF frame.
            frames = []
            for muscle in rig["muscles"]:
                for name in helpers.get(muscle["name"], []):
                    world = Z_UP_TO_Y_UP @ bpy.data.objects[name].matrix_world
                    frames.extend(world[r][c] for c in range(4) for r in range(4))
            clip["helpers"].append(frames)
            clip["ratio"].append([b["rigbake_ratio"] for b in bones])
            clip["twist"].append([b["rigbake_twist"] for b in bones])
        out[str(tracks.index(track.name))] = clip
    return out


def write(path, value):
    with open(path, "w", encoding="utf-8") as stream:
        json.dump(value, stream)


def live(job):
    from rigbake_blender import muscle_file, rig_build
    bpy.ops.wm.read_factory_settings(use_empty=True)
    os.environ["RIGBAKE_RUNTIME_LIBRARY"] = job["runtime_library"]
    addon_utils.enable("rigbake_blender", default_set=True)
    bpy.context.scene.rigbake_import_muscles = job["muscles"]
    bpy.ops.import_scene.gltf(filepath=job["baked"])
    armature = rig_armature()
    write(os.path.join(job["dir"], "live.json"), sample(armature))
    muscle_file.export(armature, os.path.join(job["dir"], "roundtrip.json"))
    bpy.ops.wm.save_as_mainfile(filepath=os.path.join(job["dir"], "rig.blend"))
    # Move one locator 2 cm along model-space x (its rest position; the bone keeps it there).
    name, role = job["move"]
    empty = bpy.data.objects[rig_build.locator_name(name, role)]
    x, y, z = muscle_file.rest_world(empty)
    target = (x + 0.02, y, z)
    parent = rig_build._bone_parent_rest(armature, empty.parent_bone)
    empty.location = ((parent @ empty.matrix_parent_inverse).inverted() @ Matrix.Translation(target)).translation
    bpy.context.view_layer.update()
    moved = muscle_file.rest_world(empty)
    write(os.path.join(job["dir"], "moved_target.json"), {"muscle": name, "role": role,
                                                           "world": [moved[0], moved[2], -moved[1]]})
    muscle_file.export(armature, os.path.join(job["dir"], "moved.json"))


def operators(job):
    """The panel's operators on an unbaked character: place, bake and reload, validate, mirror and
    export; then a bake with a muscle file made for another character, which must fail with rigbake's
    one-line error as the operator's report."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    addon_utils.enable("rigbake_blender", default_set=True)
    bpy.context.preferences.addons["rigbake_blender"].preferences.rigbake_path = job["rigbake"]
    scene = bpy.context.scene
    scene.rigbake_character = job["character"]
    scene.rigbake_muscles = os.path.join(job["dir"], "placed.json")
    scene.rigbake_baked = os.path.join(job["dir"], "baked.glb")
    results = {"place": sorted(bpy.ops.rigbake.place()), "bake": sorted(bpy.ops.rigbake.bake())}
    armature = rig_armature()
    bpy.context.view_layer.objects.active = armature
    results["validate"] = sorted(bpy.ops.rigbake.validate())
    results["mirror"] = sorted(bpy.ops.rigbake.mirror())
    results["export"] = sorted(bpy.ops.rigbake.export_muscles(filepath=os.path.join(job["dir"], "exported.json")))
    results["armatures"] = sum(1 for o in bpy.data.objects if o.type == 'ARMATURE')
    scene.rigbake_muscles = job["foreign_muscles"]
    try:
        results["foreign_bake"] = sorted(bpy.ops.rigbake.bake())
    except RuntimeError as error:  # an operator's error report, raised by bpy.ops
        results["foreign_bake_error"] = str(error)
    write(os.path.join(job["dir"], "operators.json"), results)


def reopen(job):
    bpy.ops.wm.open_mainfile(filepath=os.path.join(job["dir"], "rig.blend"))
    enabled = [a.module for a in bpy.context.preferences.addons if a.module.startswith("rigbake")]
    write(os.path.join(job["dir"], "reopened.json"), {"addons": enabled, "clips": sample(rig_armature())})


def main():
    mode, jobs_path = sys.argv[sys.argv.index("--") + 1:][:2]
    with open(jobs_path, encoding="utf-8") as stream:
        jobs = json.load(stream)
    if mode == "live":
        sys.path.insert(0, jobs["addon_dir"])
    for job in jobs["jobs"]:
        (live if mode == "live" else reopen)(job)
        print("RIGBAKE_JOB_DONE " + job["dir"])
    if mode == "live" and "operators" in jobs:
        operators(jobs["operators"])


main()
