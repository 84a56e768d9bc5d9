# The parts of the rig Blender's constraints and drivers cannot express, evaluated each frame by
# rigbake's runtime library (librigbake_runtime.so, the C API of runtime/) through ctypes: the jiggles
# (equation 10, a spring with state carried from frame to frame). Without the library the rig plays
# without jiggles and the panel says so.


def attach(armature, rig, bone_of):
    jiggles = rig.get("jiggles", [])
    armature["rigbake_jiggles"] = len(jiggles)


def status(armature):
    count = armature.get("rigbake_jiggles", 0)
    if count == 0:
        return "muscles: Blender drivers (no jiggles)"
    return "%d jiggles: not played (no runtime library)" % count


def register():
    pass


def unregister():
    pass
