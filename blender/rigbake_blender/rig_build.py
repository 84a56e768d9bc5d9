# Builds the live muscle rig in Blender from a RIGBAKE_muscle_rig extension
# (docs/extensions/RIGBAKE_muscle_rig.md, equations 1-9), with Blender's own constraints and drivers
# only, so a saved .blend plays without this add-on (docs/blender.md lists what needs it: the jiggles).
#
# Per muscle, with o, i the origin and insertion locators and (r_c, θ) the drivers:
#   - the locators (and the muscle file's driver locator) are empties parented to their attach bones;
#   - the length ratio r_c = clamp(|i - o| / L_rest, c, t) is a driver expression over a Distance
#     variable between the two locator empties (equations 1-2);
#   - the twist θ is a Swing+Twist driver variable: an empty riding the origin bone and one riding the
#     insertion bone both start in the frame F whose X axis is the rest fibre; a third empty, child of
#     the first, copies the second's transform, so its local rotation is F⁻¹ R̂(B_o) Δ R̂(B_o)⁻¹ F and
#     its twist about X is the twist of Δ about â (equation 4; the decomposition commutes with the
#     change of frame because F's X axis is R̂(B_o) â);
#   - each response curve (ratio and twist keys: up, side, scale) is a driver F-curve with the keys
#     as linear keyframes and constant extrapolation, the clamped piecewise-linear curve of equation 5;
#   - the skinned bone's rest is set to the skinned joint's bind frame M_bind (fibre, up, side as its
#     X, Y, Z axes), so that K' = K · T(0, up, side) · diag(1, s, s) of equation 7 is its location
#     (0, up, side) and scale (1, s, s), the sums of equation 6, as driver expressions; its parent, the
#     carrier bone, gives W_c of equation 8. Moving the rest of a deforming bone with its pose keeps the
#     skin as it was (Blender deforms by pose · rest⁻¹).
#   - with helper joints (equation 9): base = Damped Track (X) of the insertion locator from the
#     origin bone (the minimal rotation swinging f0 to f carries u0 with it), tip = the base turned
#     half a turn about up at the insertion (Copy Location), driver = Copy Location at influence φ
#     between the base and tip points offset by (δ_up, δ_side).
import json
import math

import bpy
import numpy
from mathutils import Matrix, Vector

from . import gltf_frames

EXTENSION = "RIGBAKE_muscle_rig"
COLLECTION = "rigbake muscle rig"
ROLES = ("origin", "insertion", "driver")
# Blender evaluates an F-curve at x within 1e-4 of a key as the segment starting at that key (its
# binary search's "exact" threshold in BKE_fcurve_bezt_binarysearch_index_ex), so just
# below a key it reads the next segment: on a ratio curve of slope 12 that is 1.2e-3 of scale. The
# curves' x axis is stretched by this factor (keys at `at` x 1000, the driver value x 1000), which
# leaves 1e-7 of ratio or radian inside the threshold; float keys at 1000 still resolve 6e-8.
CURVE_X_FACTOR = 1000
# The response channels of equation 6: (curve, column of a key, name).
CHANNELS = (("ratioKeys", 1, "ratio_up"), ("ratioKeys", 2, "ratio_side"), ("ratioKeys", 3, "ratio_scale"),
            ("twistKeys", 1, "twist_up"), ("twistKeys", 2, "twist_side"), ("twistKeys", 3, "twist_scale"))


def locator_name(muscle, role):
    return "%s_%sLocator" % (muscle, role)


def _matrix(values):
    return numpy.array(values, dtype=float).reshape(4, 4).T


def _unit(v):
    return v / numpy.linalg.norm(v)


def _bone_parent_rest(armature, bone_name):
    """The world matrix an object parented to the bone is relative to, at the rest pose (the bone's
    tail, as Blender parents objects to bones)."""
    bone = armature.data.bones[bone_name]
    return armature.matrix_world @ bone.matrix_local @ Matrix.Translation((0.0, bone.length, 0.0))


def _new_empty(name, collection, display, size):
    empty = bpy.data.objects.new(name, None)
    empty.empty_display_type = display
    empty.empty_display_size = size
    collection.objects.link(empty)
    return empty


def _attach_to_bone(empty, armature, bone_name, world):
    empty.parent = armature
    empty.parent_type = 'BONE'
    empty.parent_bone = bone_name
    empty.matrix_parent_inverse = Matrix.Identity(4)
    empty.matrix_basis = _bone_parent_rest(armature, bone_name).inverted() @ world


def _frame_with_x(x_axis):
    """A rotation (mathutils 4x4) whose X axis is the unit `x_axis` (Blender world)."""
    x = Vector(x_axis).normalized()
    helper = Vector((0, 0, 1)) if abs(x.z) < 0.9 else Vector((0, 1, 0))
    y = helper.cross(x).normalized()
    z = x.cross(y)
    return Matrix(((x.x, y.x, z.x, 0), (x.y, y.y, z.y, 0), (x.z, y.z, z.z, 0), (0, 0, 0, 1)))


def _prop_var(driver, name, armature, path):
    var = driver.variables.new()
    var.name = name
    var.type = 'SINGLE_PROP'
    var.targets[0].id_type = 'OBJECT'
    var.targets[0].id = armature
    var.targets[0].data_path = path
    return var


def _set_curve(fcurve, points):
    """The driver F-curve as the clamped piecewise-linear curve through `points` (equation 5)."""
    for modifier in list(fcurve.modifiers):
        fcurve.modifiers.remove(modifier)
    fcurve.keyframe_points.add(len(points))
    for keyframe, (x, y) in zip(fcurve.keyframe_points, points):
        keyframe.co = (x, y)
        keyframe.interpolation = 'LINEAR'
    fcurve.extrapolation = 'CONSTANT'
    fcurve.update()


def _bone_path(bone, prop):
    return 'pose.bones["%s"]["%s"]' % (bone, prop)


def _driver_input(driver, curve, armature, bone, origin_empty, insertion_empty, twist_reader, factor=1):
    """The driver's value: the clamped length ratio r_c (equations 1-2) or the twist θ (equation 4),
    times `factor`."""
    driver.type = 'SCRIPTED'
    if curve == "ratioKeys":
        distance = driver.variables.new()
        distance.name = "d"
        distance.type = 'LOC_DIFF'
        distance.targets[0].id = origin_empty
        distance.targets[1].id = insertion_empty
        _prop_var(driver, "rest", armature, _bone_path(bone, "rigbake_rest_length"))
        _prop_var(driver, "lo", armature, _bone_path(bone, "rigbake_compression"))
        _prop_var(driver, "hi", armature, _bone_path(bone, "rigbake_stretch"))
        driver.expression = "min(max(d / rest, lo), hi)" + (" * %d" % factor if factor != 1 else "")
    else:
        twist = driver.variables.new()
        twist.name = "theta"
        twist.type = 'TRANSFORMS'
        twist.targets[0].id = twist_reader
        twist.targets[0].transform_type = 'ROT_X'
        twist.targets[0].rotation_mode = 'SWING_TWIST_X'
        twist.targets[0].transform_space = 'LOCAL_SPACE'
        driver.expression = "theta" + (" * %d" % factor if factor != 1 else "")


def _drive_skinned(armature, muscle, bone, origin_empty, insertion_empty, twist_reader):
    pose_bone = armature.pose.bones[bone]
    pose_bone["rigbake_muscle"] = muscle["name"]
    pose_bone["rigbake_rest_length"] = float(muscle["restLength"])
    pose_bone["rigbake_compression"] = float(muscle["compression"])
    pose_bone["rigbake_stretch"] = float(muscle["stretch"])
    pose_bone.rotation_mode = 'QUATERNION'
    pose_bone.rotation_quaternion = (1, 0, 0, 0)
    pose_bone.location = (0, 0, 0)
    pose_bone.scale = (1, 1, 1)
    # The two drivers themselves, shown in the panel (the curves below read the locators directly,
    # so that no driver waits on another).
    for prop in ("rigbake_ratio", "rigbake_twist"):
        pose_bone[prop] = 1.0 if prop == "rigbake_ratio" else 0.0
        _driver_input(pose_bone.driver_add('["%s"]' % prop).driver, "ratioKeys" if prop == "rigbake_ratio" else "twistKeys",
                      armature, bone, origin_empty, insertion_empty, twist_reader)
    for curve, column, name in CHANNELS:
        keys = muscle.get(curve, [])
        prop = "rigbake_" + name
        pose_bone[prop] = 1.0 if column == 3 else 0.0
        if not keys:
            continue
        _driver_input(pose_bone.driver_add('["%s"]' % prop).driver, curve, armature, bone, origin_empty, insertion_empty,
                      twist_reader, CURVE_X_FACTOR)
        fcurve = armature.animation_data.drivers.find(_bone_path(bone, prop))
        _set_curve(fcurve, [(key[0] * CURVE_X_FACTOR, key[column]) for key in keys])
    # Equations 6-7: location (0, up, side), scale (1, s, s) in the bind frame's axes. A pose bone's
    # location is in the armature's units: under an armature object scaled x100 (Cyberpunk's
    # CharacterArmature) one unit of it is 100 scene metres, while up and side are metres (the
    # extension's model-space units), so they are divided by the bone's rest scale in the scene.
    up_scale, side_scale = (_rest_scale(armature, bone, axis) for axis in (1, 2))
    for path, index, variables, expression in (
            ("location", 1, (("ru", "ratio_up"), ("tu", "twist_up")), _over("ru + tu", up_scale)),
            ("location", 2, (("rs", "ratio_side"), ("ts", "twist_side")), _over("rs + ts", side_scale)),
            ("scale", 1, (("rk", "ratio_scale"), ("tk", "twist_scale")), "rk + tk - 1"),
            ("scale", 2, (("rk", "ratio_scale"), ("tk", "twist_scale")), "rk + tk - 1")):
        driver = pose_bone.driver_add(path, index).driver
        driver.type = 'SCRIPTED'
        for var_name, channel in variables:
            _prop_var(driver, var_name, armature, _bone_path(bone, "rigbake_" + channel))
        driver.expression = expression


def _rest_scale(armature, bone, axis):
    """How many scene metres one armature unit along the bone's rest `axis` is (its length through
    the armature object's world matrix; 1 for an unscaled armature)."""
    return (armature.matrix_world @ armature.data.bones[bone].matrix_local).col[axis].to_3d().length


def _over(expression, scale):
    """`expression` (metres) in armature units; left as it is when the armature is unscaled, so a
    simple expression Blender evaluates without Python either way."""
    if abs(scale - 1.0) <= 1e-6:
        return expression
    return "(%s) / %r" % (expression, scale)


def _helpers(armature, muscle, objects, origin_bone, origin_empty, insertion_empty, binds, collection):
    base, tip, drive = (objects[node] for node in muscle["helperNodes"])
    helpers = json.loads(armature.get("rigbake_helpers", "{}"))
    helpers[muscle["name"]] = [base.name, tip.name, drive.name]
    armature["rigbake_helpers"] = json.dumps(helpers)
    phi = float(muscle["driverFraction"])
    up_offset, side_offset = (float(v) for v in muscle["driverOffset"])
    for helper in (base, tip, drive):
        helper.animation_data_clear()
        for constraint in list(helper.constraints):
            helper.constraints.remove(constraint)
    # The base's rest is equation 9 at the bind pose, from the extension in double: [f0, u0, f0 x u0]
    # at the origin locator. (The base node's own rest in the file is not used: under Cyberpunk's
    # armature node, scaled x100, it is not that frame.)
    origin_bind = binds[muscle["originNode"]]
    fibre = _unit(origin_bind[:3, :3] @ numpy.array(muscle["fibreLocal"], dtype=float))
    up = _unit(origin_bind[:3, :3] @ numpy.array(muscle["upLocal"], dtype=float))
    up = _unit(up - numpy.dot(up, fibre) * fibre)
    frame = numpy.identity(4)
    frame[:3, :3] = numpy.column_stack([fibre, up, numpy.cross(fibre, up)])
    frame[:3, 3] = (origin_bind @ numpy.append(muscle["originLocal"], 1.0))[:3]
    base_rest = gltf_frames.to_blender(frame)
    _attach_to_bone(base, armature, origin_bone, base_rest)
    track = base.constraints.new('DAMPED_TRACK')
    track.target = insertion_empty
    track.track_axis = 'TRACK_X'
    for child in (tip, drive):
        child.parent = base
        child.parent_type = 'OBJECT'
        child.matrix_parent_inverse = Matrix.Identity(4)
    tip.matrix_basis = Matrix.Rotation(math.pi, 4, 'Y')
    at_insertion = tip.constraints.new('COPY_LOCATION')
    at_insertion.target = insertion_empty
    # The driver point o + φ L f + δ: the blend, at influence φ, of the two points offset by δ.
    aim = _new_empty(muscle["name"] + "_driverAim", collection, 'PLAIN_AXES', 0.01)
    aim.hide_viewport = True
    aim.parent = tip
    aim.matrix_parent_inverse = Matrix.Identity(4)
    aim.matrix_basis = Matrix.Translation((0.0, up_offset, -side_offset))
    drive.matrix_basis = Matrix.Translation((0.0, up_offset, side_offset))
    along = drive.constraints.new('COPY_LOCATION')
    along.target = aim
    along.influence = phi


def _muscle_file_locators(muscle_file):
    """{muscle name: {role: (joint, local)}} from the muscle JSON's rigbake block."""
    out = {}
    if muscle_file is None:
        return out
    for name, item in muscle_file.get("rigbake", {}).get("muscles", {}).items():
        out[name] = {role: (item[role]["joint"], item[role]["local"]) for role in ROLES if role in item}
    return out


def build_from_import(gltf, muscles_path):
    extension = (gltf.data.extensions or {}).get(EXTENSION)
    if not extension:
        return
    rig = extension
    binds = gltf_frames.bind_matrices(gltf)
    vnodes = gltf.vnodes

    def bone_of(node):
        return vnodes[node].blender_bone_name

    armature = vnodes[vnodes[rig["muscles"][0]["skinnedNode"]].bone_arma].blender_object
    muscle_file, muscle_text = None, None
    if muscles_path:
        with open(bpy.path.abspath(muscles_path), encoding="utf-8") as stream:
            muscle_text = stream.read()
        muscle_file = json.loads(muscle_text)
    build(armature, rig, binds, bone_of, lambda node: vnodes[node].blender_object,
          gltf.import_settings["filepath"], muscle_file, muscle_text, muscles_path, len(gltf.data.nodes))
    # The NLA track of each glTF animation, by index (the importer names them; unnamed ones too).
    armature["rigbake_clips"] = [animation.track_name for animation in gltf.data.animations or []]


def build(armature, rig, binds, bone_of, object_of, source_path, muscle_file, muscle_text, muscles_path,
          node_count):
    scene = bpy.context.scene
    # Bind matrices of every joint by bone name, in double (JSON keeps every digit), for the export.
    bind_by_bone = {bone_of(node): list(matrix.T.flatten()) for node, matrix in binds.items() if bone_of(node)}
    armature["rigbake_rig"] = json.dumps(rig)
    armature["rigbake_binds"] = json.dumps(bind_by_bone)
    armature["rigbake_source"] = source_path
    if muscle_text is not None:
        text = bpy.data.texts.get(armature.name + ".muscles.json") or bpy.data.texts.new(armature.name + ".muscles.json")
        text.clear()
        text.write(muscle_text)
        armature["rigbake_muscles_text"] = text.name
        armature["rigbake_muscles_path"] = muscles_path
    file_locators = _muscle_file_locators(muscle_file)
    # The file's rest pose (the glTF nodes' own TRS), as the importer set it on the pose bones before
    # any clip played: a clip that does not key a joint leaves it where the last clip put it (Blender),
    # where glTF leaves it at this rest; a caller puts the pose back to it between clips. It differs from
    # the bones' rests (the bind pose) where the file's rest pose is not its bind pose (Cyberpunk's neck).
    skinned_bones = {bone_of(m["skinnedNode"]) for m in rig["muscles"]}
    armature["rigbake_rest_pose"] = json.dumps({
        b.name: [b.matrix_basis[r][c] for r in range(4) for c in range(4)]
        for b in armature.pose.bones if b.name not in skinned_bones})

    # The skinned bones' rests become their bind frames M_bind = B_c · K (edit mode), and their
    # channels belong to the drivers (a `both` bake also animates them).
    skinned = {m["name"]: bone_of(m["skinnedNode"]) for m in rig["muscles"]}
    for action in bpy.data.actions:
        for fcurve in list(action.fcurves):
            if any(fcurve.data_path.startswith('pose.bones["%s"]' % b) for b in skinned.values()):
                action.fcurves.remove(fcurve)
    view_layer = bpy.context.view_layer
    previous_active = view_layer.objects.active
    view_layer.objects.active = armature
    bpy.ops.object.mode_set(mode='EDIT')
    to_armature = armature.matrix_world.inverted()
    for muscle in rig["muscles"]:
        bind = binds[muscle["carrierNode"]] @ _matrix(muscle["skinnedInCarrier"])
        frame = numpy.identity(4)
        frame[:3, :3] = numpy.column_stack([_unit(bind[:3, c]) for c in range(3)])
        frame[:3, 3] = bind[:3, 3]
        edit_bone = armature.data.edit_bones[skinned[muscle["name"]]]
        # An edit bone has no scale: under a scaled armature object the frame is given as the rotation
        # it has in the armature's axes (its columns made unit) at its place there.
        rest = to_armature @ gltf_frames.to_blender(frame)
        edit_bone.matrix = Matrix.Translation(rest.translation) @ rest.to_3x3().normalized().to_4x4()
    bpy.ops.object.mode_set(mode='OBJECT')
    view_layer.objects.active = previous_active

    collection = bpy.data.collections.get(COLLECTION) or bpy.data.collections.new(COLLECTION)
    if collection.name not in scene.collection.children:
        scene.collection.children.link(collection)
    twist_collection = bpy.data.collections.new(COLLECTION + " twist readers")
    collection.children.link(twist_collection)
    twist_collection.hide_viewport = True
    if armature.animation_data is None:
        armature.animation_data_create()
    for muscle in rig["muscles"]:
        name = muscle["name"]
        origin_bone, insertion_bone = bone_of(muscle["originNode"]), bone_of(muscle["insertionNode"])
        o0 = binds[muscle["originNode"]] @ numpy.append(muscle["originLocal"], 1.0)
        i0 = binds[muscle["insertionNode"]] @ numpy.append(muscle["insertionLocal"], 1.0)
        from_file = file_locators.get(name, {})
        places = {"origin": (origin_bone, muscle["originLocal"], o0[:3]),
                  "insertion": (insertion_bone, muscle["insertionLocal"], i0[:3])}
        for role in ROLES:
            if role in from_file and from_file[role][0] in armature.data.bones:
                joint, local = from_file[role]
                world = numpy.array(bind_by_bone[joint]).reshape(4, 4).T @ numpy.append(local, 1.0)
                places[role] = (joint, local, world[:3])
        empties = {}
        for role, (joint, local, world) in places.items():
            empty = _new_empty(locator_name(name, role), collection, 'SPHERE', 0.01)
            _attach_to_bone(empty, armature, joint, Matrix.Translation(gltf_frames.point_to_blender(world)))
            empty["rigbake_muscle"] = name
            empty["rigbake_role"] = role
            empty["rigbake_joint"] = joint
            empty["rigbake_local"] = [float(v) for v in local]
            empty["rigbake_basis"] = list(empty.matrix_basis.translation)
            empties[role] = empty
        fibre = _unit(binds[muscle["originNode"]][:3, :3] @ numpy.array(muscle["fibreLocal"], dtype=float))
        frame = _frame_with_x(gltf_frames.Y_UP_TO_Z_UP.to_3x3() @ Vector(fibre.tolist()))
        origin_frame = _new_empty(name + "_twistOrigin", twist_collection, 'ARROWS', 0.02)
        _attach_to_bone(origin_frame, armature, origin_bone, Matrix.Translation(gltf_frames.point_to_blender(o0[:3])) @ frame)
        insertion_frame = _new_empty(name + "_twistInsertion", twist_collection, 'ARROWS', 0.02)
        _attach_to_bone(insertion_frame, armature, insertion_bone, Matrix.Translation(gltf_frames.point_to_blender(i0[:3])) @ frame)
        reader = _new_empty(name + "_twistReader", twist_collection, 'ARROWS', 0.02)
        reader.parent = origin_frame
        reader.matrix_parent_inverse = Matrix.Identity(4)
        copy = reader.constraints.new('COPY_TRANSFORMS')
        copy.target = insertion_frame
        _drive_skinned(armature, muscle, skinned[name], empties["origin"], empties["insertion"], reader)
        if "helperNodes" in muscle:
            _helpers(armature, muscle, {n: object_of(n) for n in muscle["helperNodes"]}, origin_bone,
                     empties["origin"], empties["insertion"], binds, collection)
    # Per joint, the matrix taking its bone's frame to its node's (the importer turns bones to point
    # along Y; the skinned bones' frames are their nodes' now), for the runtime library's pose.
    bone_to_node = {}
    for node, bind in binds.items():
        bone = bone_of(node)
        if bone and bone in armature.data.bones:
            matrix = (armature.matrix_world @ armature.data.bones[bone].matrix_local).inverted() @ gltf_frames.to_blender(bind)
            bone_to_node[str(node)] = [bone, [matrix[r][c] for r in range(4) for c in range(4)]]
    from . import jiggle_play
    jiggle_play.attach(armature, rig, bone_to_node, node_count, collection)
