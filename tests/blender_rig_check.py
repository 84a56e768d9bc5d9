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
import time

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


def column_major(matrix):
    """A 4x4 matrix's 16 numbers, column by column (glTF's order)."""
    return [value for column in matrix.transposed() for value in column]


def sample(armature, only=None, whole_frames=False):
    """sample_clips with the meshes out of the depsgraph: their skinning (Cyberpunk: 7778 vertices)
    was nine tenths of a key's time, and nothing sampled reads them."""
    meshes = [o for o in bpy.data.objects if o.type == 'MESH' and not o.hide_viewport]
    for mesh in meshes:
        mesh.hide_viewport = True
    try:
        return sample_clips(armature, only, whole_frames)
    finally:
        for mesh in meshes:
            mesh.hide_viewport = False


def sample_clips(armature, only=None, whole_frames=False):
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
    # A bone has no scale of its own: under an armature object scaled x100 (Cyberpunk) a skinned
    # bone's world matrix scales by 100 where its glTF node's (M, unit columns) does not. The node's
    # matrix is the bone's with the armature's uniform scale taken out.
    scale = armature.matrix_world.to_scale()
    assert max(scale) - min(scale) <= 1e-6 * max(scale), "a non-uniformly scaled armature: %s" % scale
    to_node = Matrix.Scale(1.0 / scale[0], 4)
    # The jiggling skeleton joints (the extension's jiggle indices), each as its glTF node's world
    # matrix: the bone's times the add-on's bone-to-node matrix (the importer turns bones along Y).
    nodes = json.loads(armature["rigbake_nodes"])
    skinned_nodes = {m["skinnedNode"] for m in rig["muscles"]}
    skeleton_jiggles = [(j, armature.pose.bones[nodes[str(jiggle["node"])][0]],
                         Matrix([nodes[str(jiggle["node"])][1][r * 4:r * 4 + 4] for r in range(4)]))
                        for j, jiggle in enumerate(rig.get("jiggles", []))
                        if jiggle["node"] not in skinned_nodes and str(jiggle["node"]) in nodes]
    rest_pose = json.loads(armature["rigbake_rest_pose"])
    helper_objects = [bpy.data.objects[name] for muscle in rig["muscles"] for name in helpers.get(muscle["name"], [])]
    out = {}
    for track in armature.animation_data.nla_tracks if armature.animation_data else []:
        if track.name not in tracks or not track.strips or (only is not None and track.name != only):
            continue
        action = track.strips[0].action
        armature.animation_data.action = action
        # A clip that does not key a joint leaves it where the previous clip put it: start at the
        # file's rest pose, as glTF does (the skinned bones at their bind frames).
        for pose_bone in armature.pose.bones:
            basis = rest_pose.get(pose_bone.name)
            pose_bone.matrix_basis = Matrix([basis[r * 4:r * 4 + 4] for r in range(4)]) if basis else Matrix.Identity(4)
        clip = {"times": [], "skinned": [], "ratio": [], "twist": [], "helpers": [],
                "skeleton_jiggles": [j for j, _, _ in skeleton_jiggles], "skeleton_jiggled": []}
        frames = key_frames(action)
        if whole_frames:  # every whole frame from the clip's first key to its last, as a bake keys them
            frames = [float(f) for f in range(int(frames[0]), int(frames[-1]) + 1)]
        for frame in frames:
            scene.frame_set(int(frame), subframe=frame - int(frame))
            # The add-on's frame handler turns the jiggled bones after the frame's evaluation.
            bpy.context.view_layer.update()
            clip["times"].append(frame * scene.render.fps_base / scene.render.fps)
            to_gltf = Z_UP_TO_Y_UP @ armature.matrix_world
            clip["skinned"].append([v for pose_bone in bones for v in column_major(to_gltf @ pose_bone.matrix @ to_node)])
            # Helper joints (base, tip, driver) are empties: their world matrices, glTF frame.
            clip["helpers"].append([v for helper in helper_objects for v in column_major(Z_UP_TO_Y_UP @ helper.matrix_world)])
            clip["skeleton_jiggled"].append([v for _, pose_bone, bone_to_node in skeleton_jiggles
                                             for v in column_major(to_gltf @ pose_bone.matrix @ bone_to_node)])
            clip["ratio"].append([b["rigbake_ratio"] for b in bones])
            clip["twist"].append([b["rigbake_twist"] for b in bones])
        out[str(tracks.index(track.name))] = clip
    return out


def write(path, value):
    with open(path, "w", encoding="utf-8") as stream:
        stream.write(json.dumps(value))  # dumps uses the C encoder, json.dump the Python one


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
    if armature.get("rigbake_jiggles", 0):
        bake_jiggles(job, armature)
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


def bake_jiggles(job, armature):
    """The panel's *Bake jiggles to action* over the first clip's frames, then that clip sampled again
    at the same whole frames with the frame handler off (the keys play the jiggles): baked_jiggles.json."""
    from rigbake_blender import jiggle_play
    track = armature.animation_data.nla_tracks[armature["rigbake_clips"][0]]
    armature.animation_data.action = track.strips[0].action
    rest_pose = json.loads(armature["rigbake_rest_pose"])
    for pose_bone in armature.pose.bones:
        basis = rest_pose.get(pose_bone.name)
        pose_bone.matrix_basis = Matrix([basis[r * 4:r * 4 + 4] for r in range(4)]) if basis else Matrix.Identity(4)
    frames = key_frames(track.strips[0].action)
    scene = bpy.context.scene
    scene.frame_start, scene.frame_end = int(frames[0]), int(frames[-1])
    keys = jiggle_play.bake_jiggles(bpy.context, armature)
    write(os.path.join(job["dir"], "baked_jiggles.json"),
          {"keys": keys, "clips": sample(armature, only=track.name, whole_frames=True)})


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
        # The repository's add-on, not the copy installed in the user's add-on folder (which may be
        # another checkout's): the import must resolve to this directory.
        import rigbake_blender
        where = os.path.dirname(os.path.realpath(rigbake_blender.__file__))
        assert where == os.path.realpath(os.path.join(jobs["addon_dir"], "rigbake_blender")), where
    for job in jobs["jobs"]:
        started = time.process_time()
        (live if mode == "live" else reopen)(job)
        print("RIGBAKE_JOB_DONE %s %s: %.1f s of CPU" % (mode, job["dir"], time.process_time() - started))
    if mode == "live" and "operators" in jobs:
        operators(jobs["operators"])


main()
