# The muscle JSON (docs/muscle-json.md) written back from the live rig: the file the rig was built
# from, with every moved locator's `joint` and `local` (and its talk-shaped world position) and every
# edited factor replaced. An unmoved locator keeps its numbers as they were, digit for digit: Blender
# keeps object transforms in float, so recomputing it would move it by ~1e-7 m.
import json
import os

import bpy
import numpy
from mathutils import Matrix

from . import gltf_frames, rig_build

ROLE_KEYS = {"origin": "_muscleOrigin", "insertion": "_muscleInsertion", "driver": "_muscleDriver"}


class MuscleFileError(Exception):
    """A one-line, coded error for a Blender report (codes in docs/errors.md)."""


def rig_armature(context):
    """The armature of the active object's rig (the active object, its parent, or a locator's)."""
    obj = context.active_object
    while obj is not None and not (obj.type == 'ARMATURE' and "rigbake_rig" in obj):
        obj = obj.parent
    return obj


def locators(armature):
    return [obj for obj in bpy.data.objects if "rigbake_role" in obj and obj.parent == armature]


def rest_world(empty):
    """The empty's world position at the rest (bind) pose, Blender frame."""
    if empty.parent_type == 'BONE':
        parent = rig_build._bone_parent_rest(empty.parent, empty.parent_bone)
    else:
        parent = empty.parent.matrix_world if empty.parent else Matrix.Identity(4)
    return (parent @ empty.matrix_parent_inverse @ empty.matrix_basis).translation


def _moved(empty):
    return (empty.parent_bone != empty["rigbake_joint"] or
            list(empty.matrix_basis.translation) != list(empty["rigbake_basis"]))


def muscle_text(armature):
    name = armature.get("rigbake_muscles_text")
    if not name or name not in bpy.data.texts:
        raise MuscleFileError("BLENDER_NO_MUSCLE_FILE %s: the rig was imported without its muscle file; "
                              "import the bake again with one (rigbake panel, Muscle file)" % armature.name)
    return bpy.data.texts[name].as_string()


def export_data(armature):
    data = json.loads(muscle_text(armature))
    binds = json.loads(armature["rigbake_binds"])
    block = data["rigbake"]["muscles"]
    for empty in locators(armature):
        item = block.get(empty["rigbake_muscle"])
        if item is None or not _moved(empty):
            continue
        role = empty["rigbake_role"]
        joint = empty.parent_bone
        if joint not in binds:
            raise MuscleFileError("BLENDER_LOCATOR_UNATTACHED %s: parent it to a joint of the skin (bone '%s' is not one)"
                                  % (empty.name, joint))
        world = gltf_frames.point_to_gltf(rest_world(empty))
        local = numpy.linalg.solve(numpy.array(binds[joint]).reshape(4, 4).T, numpy.append(world, 1.0))[:3]
        item[role] = {"joint": joint, "local": [float(v) for v in local]}
        group = data.setdefault(item["group"], {}).setdefault(item["side"], {})
        group[empty["rigbake_muscle"] + ROLE_KEYS[role]] = [float(v) for v in world]
    for pose_bone in armature.pose.bones:
        item = block.get(pose_bone.get("rigbake_muscle"))
        if item is None:
            continue
        for key in ("compression", "stretch"):
            value = float(pose_bone["rigbake_" + key])
            if value != item[key]:
                item[key] = value
    return data


def write_atomic(path, text):
    """Writes through a temporary file and a rename: a failed export leaves no partial file."""
    temporary = path + ".tmp-rigbake"
    with open(temporary, "w", encoding="utf-8") as stream:
        stream.write(text)
    os.replace(temporary, path)


def export(armature, path):
    write_atomic(path, json.dumps(export_data(armature), indent=2) + "\n")


def mirror_left_to_right(armature):
    """Puts every Right locator at the mirror image (x -> -x, the body's sagittal plane) of its Left
    counterpart's rest position and copies the factors; returns the number of parts mirrored."""
    by_key = {(e["rigbake_muscle"], e["rigbake_role"]): e for e in locators(armature)}
    mirrored = set()
    for (muscle, role), left in by_key.items():
        if not muscle.startswith("Left"):
            continue
        right = by_key.get(("Right" + muscle[4:], role))
        if right is None:
            continue
        x, y, z = rest_world(left)
        parent = rig_build._bone_parent_rest(armature, right.parent_bone) if right.parent_type == 'BONE' else \
            right.parent.matrix_world
        basis = (parent @ right.matrix_parent_inverse).inverted() @ Matrix.Translation((-x, y, z))
        right.location = basis.translation
        mirrored.add(muscle)
    bones = {b.get("rigbake_muscle"): b for b in armature.pose.bones if "rigbake_muscle" in b}
    for muscle in mirrored:
        left, right = bones.get(muscle), bones.get("Right" + muscle[4:])
        if left is not None and right is not None:
            for key in ("rigbake_compression", "rigbake_stretch"):
                right[key] = left[key]
    return len(mirrored)
