# The part of the rig Blender's constraints and drivers cannot express, played each frame by rigbake's
# runtime library (librigbake_runtime.so, the C API of runtime/rigbake_runtime.h) through ctypes: the
# jiggles (equation 10 of docs/extensions/RIGBAKE_muscle_rig.md), a spring whose state is carried from
# frame to frame, which no driver can hold. The muscles themselves are Blender drivers (rig_build.py);
# the library evaluates them too, from Blender's pose, because the jiggles read the un-jiggled muscle
# matrices. No equation is written here: this file only moves matrices between Blender and the library.
import ctypes
import ctypes.util
import json
import os
import shutil

import bpy
from bpy.app.handlers import persistent
from mathutils import Matrix

from . import gltf_frames

_float_p = ctypes.POINTER(ctypes.c_float)
_library = None
_rigs = {}  # armature name -> _JiggleRig


class RuntimeMissing(Exception):
    pass


def library_candidates():
    """Where the library is looked for, in order: the add-on's preference, $RIGBAKE_RUNTIME_LIBRARY,
    beside the rigbake executable (a build tree holds both), the system's library path."""
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
    found = ctypes.util.find_library("rigbake_runtime")
    if found:
        out.append(found)
    return out


def library():
    global _library
    if _library is not None:
        return _library
    tried = library_candidates()
    for path in tried:
        if os.path.exists(path) or "/" not in path:
            try:
                lib = ctypes.CDLL(path)
                break
            except OSError:
                continue
    else:
        raise RuntimeMissing("BLENDER_RUNTIME_MISSING librigbake_runtime.so: not found (tried %s)" % (", ".join(tried) or "nothing"))
    lib.rigbake_runtime_version.restype = ctypes.c_uint
    lib.rigbake_last_error.restype = ctypes.c_char_p
    lib.rigbake_rig_create.restype = ctypes.c_void_p
    lib.rigbake_rig_create.argtypes = [ctypes.c_char_p, ctypes.c_size_t, ctypes.c_int]
    lib.rigbake_rig_destroy.argtypes = [ctypes.c_void_p]
    for name in ("rigbake_rig_muscle_count", "rigbake_rig_jiggle_count"):
        getattr(lib, name).argtypes = [ctypes.c_void_p]
    lib.rigbake_rig_jiggle_node.argtypes = [ctypes.c_void_p, ctypes.c_int, ctypes.c_int]
    lib.rigbake_rig_muscle_node.argtypes = [ctypes.c_void_p, ctypes.c_int, ctypes.c_int]
    lib.rigbake_rig_node_used.argtypes = [ctypes.c_void_p, ctypes.c_int]
    lib.rigbake_rig_evaluate.argtypes = [ctypes.c_void_p, _float_p, _float_p, _float_p, _float_p]
    lib.rigbake_rig_store_skinned.argtypes = [ctypes.c_void_p, _float_p, _float_p]
    lib.rigbake_jiggle_reset.argtypes = [ctypes.c_void_p, _float_p, _float_p, ctypes.c_float]
    lib.rigbake_jiggle_step.argtypes = [ctypes.c_void_p, _float_p, ctypes.c_float, ctypes.c_int,
                                        _float_p, _float_p, _float_p, _float_p]
    if lib.rigbake_runtime_version() // 10000 != 1:
        raise RuntimeMissing("BLENDER_RUNTIME_MISSING %s: C API version %d, this add-on needs 1.x"
                             % (path, lib.rigbake_runtime_version()))
    _library = lib
    return lib


def _check(lib, status, what):
    if status != 0:
        raise RuntimeError("rigbake runtime %s: %s" % (what, lib.rigbake_last_error().decode("utf-8", "replace")))


class _JiggleRig:
    """A library rig for one armature, the glTF node of each bone, and the jiggles' last frame."""

    def __init__(self, armature):
        lib = library()
        text = armature["rigbake_rig"].encode("utf-8")
        self.node_count = int(armature["rigbake_node_count"])
        self.handle = lib.rigbake_rig_create(text, len(text), self.node_count)
        if not self.handle:
            raise RuntimeError("rigbake runtime: " + lib.rigbake_last_error().decode("utf-8", "replace"))
        nodes = json.loads(armature["rigbake_nodes"])  # node index -> [bone, bone-to-node matrix]
        self.bones = [(int(n), bone, Matrix([m[i * 4:i * 4 + 4] for i in range(4)]))
                      for n, (bone, m) in nodes.items() if lib.rigbake_rig_node_used(self.handle, int(n)) == 1]
        self.muscles = lib.rigbake_rig_muscle_count(self.handle)
        self.jiggles = lib.rigbake_rig_jiggle_count(self.handle)
        by_node = {int(n): bone for n, (bone, _) in nodes.items()}
        skinned = {lib.rigbake_rig_muscle_node(self.handle, m, 0) for m in range(self.muscles)}
        # Jiggles on a muscle's skinned bone turn its rotation, which no driver or clip sets; a jiggling
        # skeleton joint would need its animated rotation kept apart from the jiggle's, so it is left out.
        self.played = [(j, by_node[node]) for j in range(self.jiggles)
                       for node in [lib.rigbake_rig_jiggle_node(self.handle, j, 0)] if node in skinned and node in by_node]
        self.last_time, self.last_clip = None, ""

    def __del__(self):
        if _library is not None and getattr(self, "handle", None):
            _library.rigbake_rig_destroy(self.handle)

    def node_matrices(self, armature):
        """The pose as the library reads it: every used node's glTF world matrix, column-major."""
        values = (ctypes.c_float * (16 * self.node_count))()
        to_gltf = gltf_frames.Z_UP_TO_Y_UP @ armature.matrix_world
        for node, bone, bone_to_node in self.bones:
            world = to_gltf @ armature.pose.bones[bone].matrix @ bone_to_node
            values[16 * node:16 * node + 16] = [world[r][c] for c in range(4) for r in range(4)]
        return values

    def evaluate(self, armature):
        """(node matrices with the muscles stored, the muscles' skinned matrices) for this pose."""
        lib = library()
        nodes = self.node_matrices(armature)
        skinned = (ctypes.c_float * (16 * self.muscles))()
        _check(lib, lib.rigbake_rig_evaluate(self.handle, nodes, skinned, None, None), "evaluate")
        _check(lib, lib.rigbake_rig_store_skinned(self.handle, skinned, nodes), "store")
        return nodes, skinned

    def frame(self, armature, time):
        """Steps the jiggles to `time` (seconds) and turns each jiggled bone: a step forward in the same
        clip integrates; any other move (the first frame, a jump back, another clip) starts them at rest."""
        lib = library()
        nodes, _ = self.evaluate(armature)
        corrections = (ctypes.c_float * (4 * max(self.jiggles, 1)))()
        action = armature.animation_data.action if armature.animation_data else None
        clip = action.name if action else ""
        if self.last_time is None or time < self.last_time or clip != self.last_clip:
            _check(lib, lib.rigbake_jiggle_reset(self.handle, nodes, None, 0.0), "jiggle reset")
            _check(lib, lib.rigbake_jiggle_step(self.handle, nodes, 0.0, 0, corrections, None, None, None), "jiggle step")
        else:
            _check(lib, lib.rigbake_jiggle_step(self.handle, nodes, time - self.last_time, 0, corrections, None, None, None),
                   "jiggle step")
        self.last_time, self.last_clip = time, clip
        for jiggle, bone in self.played:
            x, y, z, w = corrections[4 * jiggle:4 * jiggle + 4]
            # The skinned bone's axes are its node's (rig_build.py), so the correction applies as it is.
            armature.pose.bones[bone].rotation_quaternion = (w, x, y, z)


def attach(armature, rig, bone_to_node_matrices, node_count):
    armature["rigbake_node_count"] = node_count
    armature["rigbake_nodes"] = json.dumps(bone_to_node_matrices)
    armature["rigbake_jiggles"] = len(rig.get("jiggles", []))
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
    return "%d jiggles: %d played live by the runtime library" % (count, len(rig.played))


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


def bake_jiggles(context, armature):
    """Keys every jiggled bone's rotation at every frame of the scene's range into the armature's
    action, played from the start, so the jiggles play without the add-on; returns the key count."""
    scene = context.scene
    rig = jiggle_rig(armature)
    rig.last_time = None
    keys = 0
    for frame in range(scene.frame_start, scene.frame_end + 1):
        scene.frame_set(frame)
        for _, bone in rig.played:
            armature.pose.bones[bone].keyframe_insert("rotation_quaternion", frame=frame)
            keys += 1
    action = armature.animation_data.action if armature.animation_data else None
    armature["rigbake_jiggles_baked"] = action.name if action else "the scene"
    return keys


def register():
    if _on_frame not in bpy.app.handlers.frame_change_post:
        bpy.app.handlers.frame_change_post.append(_on_frame)


def unregister():
    if _on_frame in bpy.app.handlers.frame_change_post:
        bpy.app.handlers.frame_change_post.remove(_on_frame)
    _rigs.clear()
