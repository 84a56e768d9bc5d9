# The part of the rig Blender's constraints and drivers cannot express, played each frame by rigbake's
# runtime library (librigbake_runtime.so, the C API of runtime/rigbake_runtime.h) through ctypes: the
# jiggles (equation 10 of docs/extensions/RIGBAKE_muscle_rig.md), a spring whose state is carried from
# frame to frame, which no driver can hold. The muscles themselves are Blender drivers (rig_build.py);
# the library evaluates them too, from Blender's pose, because the jiggles read the un-jiggled muscle
# matrices. No equation is written here: this file only moves matrices between Blender and the library.
import ctypes
import json
import os
import shutil

import bpy
from bpy.app.handlers import persistent
from mathutils import Matrix, Quaternion

from . import gltf_frames, runtime_lib

_library = None
_rigs = {}  # armature name -> _JiggleRig
RuntimeMissing = runtime_lib.RuntimeMissing


def library_candidates():
    """Where the library is looked for, in order: the add-on's preference, $RIGBAKE_RUNTIME_LIBRARY,
    beside the rigbake executable (a build tree holds both); runtime_lib.load adds the system's path."""
    out = []
    prefs = bpy.context.preferences.addons.get(__package__)
    if prefs is not None and prefs.preferences.runtime_library:
        out.append(bpy.path.abspath(prefs.preferences.runtime_library))
    if os.environ.get("RIGBAKE_RUNTIME_LIBRARY"):
        out.append(os.environ["RIGBAKE_RUNTIME_LIBRARY"])
    for executable in (prefs.preferences.rigbake_path if prefs is not None else "", os.environ.get("RIGBAKE", ""),
                       shutil.which("rigbake") or ""):
        if executable:
            out.append(os.path.join(os.path.dirname(os.path.realpath(bpy.path.abspath(executable))), "librigbake_runtime.so"))
    return out


def library():
    global _library
    if _library is None:
        _library = runtime_lib.load(library_candidates())
    return _library


JIGGLE_CONSTRAINT = "rigbake jiggle"


class _JiggleRig:
    """A library rig for one armature, the glTF node of each bone, and the jiggles' last frame."""

    def __init__(self, armature):
        lib = library()
        self.node_count = int(armature["rigbake_node_count"])
        self.handle = runtime_lib.create_rig(lib, armature["rigbake_rig"], self.node_count)
        nodes = json.loads(armature["rigbake_nodes"])  # node index -> [bone, bone-to-node matrix]
        self.bones = [(int(n), bone, _matrix(m))
                      for n, (bone, m) in nodes.items() if lib.rigbake_rig_node_used(self.handle, int(n)) == 1]
        self.muscles = lib.rigbake_rig_muscle_count(self.handle)
        self.jiggles = lib.rigbake_rig_jiggle_count(self.handle)
        by_node = {int(n): (bone, _matrix(m)) for n, (bone, m) in nodes.items()}
        skinned = {lib.rigbake_rig_muscle_node(self.handle, m, 0) for m in range(self.muscles)}
        empties = json.loads(armature.get("rigbake_jiggle_empties", "{}"))
        # A jiggle on a muscle's skinned bone turns that bone's rotation, which no driver or clip sets.
        # A jiggling skeleton joint's rotation belongs to the clip: its jiggle is the Copy Rotation
        # constraint (after the original, local space) of an empty this handler turns (attach()).
        self.played, self.skeleton = [], []
        for j in range(self.jiggles):
            node = lib.rigbake_rig_jiggle_node(self.handle, j, 0)
            if node not in by_node:
                continue
            bone, bone_to_node = by_node[node]
            if node in skinned:
                self.played.append((j, bone))
            elif bone in empties and empties[bone] in bpy.data.objects:
                # The correction D turns the node's frame (local = animated local * D); the bone's frame
                # is the node's through bone_to_node's rotation C, so the bone turns by C D C^-1.
                self.skeleton.append((j, bone, bpy.data.objects[empties[bone]], bone_to_node.to_3x3().normalized().to_quaternion()))
        # Deepest first, so that undoing one jiggle (unjiggled_pose) sees its ancestors' still applied.
        depth = {b.name: len(b.parent_recursive) for b in armature.pose.bones}
        self.skeleton.sort(key=lambda item: -depth[item[1]])
        self.last_time, self.last_clip = None, ""

    def __del__(self):
        if _library is not None and getattr(self, "handle", None):
            _library.rigbake_rig_destroy(self.handle)

    def unjiggled_pose(self, armature):
        """Every bone's armature-space matrix of the animated pose, without the skeleton jiggles: the
        evaluated pose holds each jiggled bone at M X (X its constraint's turn, in its own frame), and
        its descendants with it, so M X^-1 M^-1 applied to the bone and its descendants takes it out."""
        pose = {b.name: b.matrix.copy() for b in armature.pose.bones}
        for _, bone, empty, _ in self.skeleton:
            turn = empty.matrix_basis.to_quaternion().to_matrix().to_4x4()
            jiggled = pose[bone]
            undo = jiggled @ turn.inverted() @ jiggled.inverted()
            for name in [bone] + [child.name for child in armature.pose.bones[bone].children_recursive]:
                pose[name] = undo @ pose[name]
        return pose

    def node_matrices(self, armature):
        """The pose as the library reads it: every used node's glTF world matrix, column-major, of the
        animated (un-jiggled) pose."""
        values = (ctypes.c_float * (16 * self.node_count))()
        to_gltf = gltf_frames.Z_UP_TO_Y_UP @ armature.matrix_world
        pose = self.unjiggled_pose(armature) if self.skeleton else None
        for node, bone, bone_to_node in self.bones:
            world = to_gltf @ (pose[bone] if pose else armature.pose.bones[bone].matrix) @ bone_to_node
            values[16 * node:16 * node + 16] = [world[r][c] for c in range(4) for r in range(4)]
        return values

    def evaluate(self, armature):
        """(node matrices with the muscles stored, the muscles' skinned matrices) for this pose."""
        lib = library()
        nodes = self.node_matrices(armature)
        skinned = (ctypes.c_float * (16 * self.muscles))()
        runtime_lib.check(lib, lib.rigbake_rig_evaluate(self.handle, nodes, skinned, None, None), "evaluate")
        runtime_lib.check(lib, lib.rigbake_rig_store_skinned(self.handle, skinned, nodes), "store")
        return nodes, skinned

    def frame(self, armature, time):
        """Steps the jiggles to `time` (seconds) and turns each jiggled bone: a step forward in the same
        clip integrates; any other move (the first frame, a jump back, another clip) starts them at rest."""
        lib = library()
        nodes, _ = self.evaluate(armature)
        corrections = runtime_lib.floats(4 * self.jiggles)
        action = armature.animation_data.action if armature.animation_data else None
        clip = action.name if action else ""
        if self.last_time is None or time < self.last_time or clip != self.last_clip:
            runtime_lib.check(lib, lib.rigbake_jiggle_reset(self.handle, nodes, None, 0.0), "jiggle reset")
            step = 0.0
        else:
            step = time - self.last_time
        runtime_lib.check(lib, lib.rigbake_jiggle_step(self.handle, nodes, step, 0, corrections, None, None, None), "jiggle step")
        self.last_time, self.last_clip = time, clip
        for jiggle, bone in self.played:
            x, y, z, w = corrections[4 * jiggle:4 * jiggle + 4]
            # The skinned bone's axes are its node's (rig_build.py), so the correction applies as it is.
            armature.pose.bones[bone].rotation_quaternion = (w, x, y, z)
        for jiggle, bone, empty, to_node in self.skeleton:
            x, y, z, w = corrections[4 * jiggle:4 * jiggle + 4]
            empty.rotation_quaternion = to_node @ Quaternion((w, x, y, z)) @ to_node.inverted()


def _matrix(values):
    return Matrix([values[i * 4:i * 4 + 4] for i in range(4)])


def attach(armature, rig, bone_to_node_matrices, node_count, collection):
    """Records what the frame handler needs on the armature, and gives every jiggling skeleton joint
    its jiggle constraint: Copy Rotation of a hidden empty, mixed after the bone's own (animated)
    rotation in local space, so the clip keeps the bone's channels and the jiggle turns it on top."""
    armature["rigbake_node_count"] = node_count
    armature["rigbake_nodes"] = json.dumps(bone_to_node_matrices)
    armature["rigbake_jiggles"] = len(rig.get("jiggles", []))
    skinned = {m["skinnedNode"] for m in rig["muscles"]}
    empties = {}
    for jiggle in rig.get("jiggles", []):
        if jiggle["node"] in skinned or str(jiggle["node"]) not in bone_to_node_matrices:
            continue
        bone = bone_to_node_matrices[str(jiggle["node"])][0]
        empty = bpy.data.objects.new(bone + "_jiggle", None)
        empty.empty_display_type = 'PLAIN_AXES'
        empty.rotation_mode = 'QUATERNION'
        empty.hide_viewport = True
        collection.objects.link(empty)
        pose_bone = armature.pose.bones[bone]
        for old in [c for c in pose_bone.constraints if c.name == JIGGLE_CONSTRAINT]:
            pose_bone.constraints.remove(old)
        constraint = pose_bone.constraints.new('COPY_ROTATION')
        constraint.name = JIGGLE_CONSTRAINT
        constraint.target = empty
        constraint.mix_mode = 'AFTER'
        constraint.owner_space = 'LOCAL'
        # The empty has no parent, so its world rotation is its own (its 'LOCAL' space as a target
        # reads as no rotation at all in Blender 3.4).
        constraint.target_space = 'WORLD'
        empties[bone] = empty.name
    armature["rigbake_jiggle_empties"] = json.dumps(empties)
    _rigs.pop(armature.name, None)


def jiggle_rig(armature):
    rig = _rigs.get(armature.name)
    if rig is None:
        rig = _rigs[armature.name] = _JiggleRig(armature)
    return rig


def status(armature):
    count = armature.get("rigbake_jiggles", 0)
    if count == 0:
        return "muscles: Blender drivers (no jiggles)"
    if armature.get("rigbake_jiggles_baked"):
        return "%d jiggles: baked into %s" % (count, armature["rigbake_jiggles_baked"])
    try:
        rig = jiggle_rig(armature)
    except (RuntimeMissing, RuntimeError) as error:
        return str(error)
    return "%d jiggles: %d played live by the runtime library" % (count, len(rig.played) + len(rig.skeleton))


def _scene_armatures(scene):
    return [o for o in scene.objects if o.type == 'ARMATURE' and o.get("rigbake_jiggles", 0) > 0
            and not o.get("rigbake_jiggles_baked")]


@persistent
def _on_frame(scene, depsgraph=None):
    time = (scene.frame_current + scene.frame_subframe) * scene.render.fps_base / scene.render.fps
    for armature in _scene_armatures(scene):
        try:
            jiggle_rig(armature).frame(armature, time)
        except (RuntimeMissing, RuntimeError) as error:
            print(str(error))


_saved_turns = []  # (datablock, rotation) the jiggles had when a save began


def _jiggle_turns():
    """(pose bone or empty, its rotation) of every live (unbaked) jiggle: the skinned bones' and the
    skeleton joints' empties."""
    out = []
    for armature in [o for o in bpy.data.objects if o.type == 'ARMATURE' and o.get("rigbake_jiggles", 0) > 0
                     and not o.get("rigbake_jiggles_baked")]:
        rig = json.loads(armature["rigbake_rig"])
        nodes = json.loads(armature["rigbake_nodes"])
        skinned = {m["skinnedNode"] for m in rig["muscles"]}
        for jiggle in rig.get("jiggles", []):
            if jiggle["node"] in skinned and str(jiggle["node"]) in nodes:
                out.append(armature.pose.bones[nodes[str(jiggle["node"])][0]])
        out += [bpy.data.objects[name] for name in json.loads(armature.get("rigbake_jiggle_empties", "{}")).values()
                if name in bpy.data.objects]
    return out


@persistent
def _before_save(*_):
    """A .blend opened without the add-on has no frame handler to move the jiggles: it is saved with
    them at rest (no turn), not frozen at the frame shown; they are put back once it is written."""
    _saved_turns.clear()
    for owner in _jiggle_turns():
        _saved_turns.append((owner, owner.rotation_quaternion.copy()))
        owner.rotation_quaternion = (1, 0, 0, 0)


@persistent
def _after_save(*_):
    for owner, rotation in _saved_turns:
        owner.rotation_quaternion = rotation
    _saved_turns.clear()


def bake_jiggles(context, armature):
    """Keys every jiggled skinned bone's rotation at every frame of the scene's range into the
    armature's action (a jiggling skeleton joint: its jiggle empty's rotation, into the empty's own
    action), played from the start, so the jiggles play without the add-on; returns the key count."""
    scene = context.scene
    rig = jiggle_rig(armature)
    rig.last_time = None
    keys = 0
    for frame in range(scene.frame_start, scene.frame_end + 1):
        scene.frame_set(frame)
        for _, bone in rig.played:
            armature.pose.bones[bone].keyframe_insert("rotation_quaternion", frame=frame)
            keys += 1
        for _, _, empty, _ in rig.skeleton:  # a skeleton joint's jiggle: its constraint's empty
            empty.keyframe_insert("rotation_quaternion", frame=frame)
            keys += 1
    action = armature.animation_data.action if armature.animation_data else None
    armature["rigbake_jiggles_baked"] = action.name if action else "the scene"
    return keys


_HANDLERS = (("frame_change_post", _on_frame), ("save_pre", _before_save), ("save_post", _after_save))


def register():
    for kind, handler in _HANDLERS:
        if handler not in getattr(bpy.app.handlers, kind):
            getattr(bpy.app.handlers, kind).append(handler)


def unregister():
    for kind, handler in _HANDLERS:
        if handler in getattr(bpy.app.handlers, kind):
            getattr(bpy.app.handlers, kind).remove(handler)
    _rigs.clear()
