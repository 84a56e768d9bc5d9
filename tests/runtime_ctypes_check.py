"""The runtime's shared library from Python ctypes, through the Blender add-on's own binding
(blender/rigbake_blender/runtime_lib.py, which needs no bpy): the same frames and output as
tests/c_api/runtime_c_check.c, which tests/runtime_c_api_test.cpp compares with the in-process C API
bit for bit. A signature declared wrongly in the add-on's binding fails here.

usage: python3 runtime_ctypes_check.py LIBRARY EXTENSION.json NODE_COUNT POSES.f32 FRAME_SECONDS OUT.f32
"""
import array
import ctypes
import os
import sys

# The add-on's package directory, imported as plain modules: runtime_lib imports nothing of Blender's.
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "blender", "rigbake_blender"))
import runtime_lib  # noqa: E402


def main():
    library, extension_path, node_count, poses_path, frame_seconds, out_path = sys.argv[1:7]
    node_count = int(node_count)
    # Only this path: the check must load the library the C program links, not one on the system's path.
    lib = runtime_lib.declare(ctypes.CDLL(library))
    assert lib.rigbake_runtime_version() // 10000 == runtime_lib.API_MAJOR, lib.rigbake_runtime_version()
    rig = runtime_lib.create_rig(lib, open(extension_path, "rb").read(), node_count)
    assert lib.rigbake_rig_node_count(rig) == node_count
    muscles, jiggles = lib.rigbake_rig_muscle_count(rig), lib.rigbake_rig_jiggle_count(rig)
    poses = array.array("f")
    poses.frombytes(open(poses_path, "rb").read())
    per_frame = 16 * node_count
    skinned = runtime_lib.floats(16 * muscles)
    corrections = runtime_lib.floats(4 * jiggles)
    hit = runtime_lib.floats(3, (0.0, 0.0, 1.0))
    dt = float(frame_seconds)
    out = array.array("f")
    for frame in range(len(poses) // per_frame):
        pose = runtime_lib.floats(per_frame, poses[frame * per_frame:(frame + 1) * per_frame])
        runtime_lib.check(lib, lib.rigbake_rig_evaluate(rig, pose, skinned, None, None), "evaluate")
        runtime_lib.check(lib, lib.rigbake_rig_store_skinned(rig, skinned, pose), "store")
        if frame == 5 and jiggles > 0:
            runtime_lib.check(lib, lib.rigbake_jiggle_impulse(rig, -1, hit, 2.0), "impulse")
        runtime_lib.check(lib, lib.rigbake_jiggle_step(rig, pose, 0.0 if frame == 0 else dt, 0, corrections, None, None, None),
                          "step")
        out.extend(skinned[:16 * muscles])
        out.extend(corrections[:4 * jiggles])
    lib.rigbake_rig_destroy(rig)
    with open(out_path, "wb") as file:
        file.write(out.tobytes())
    print("runtime_ctypes_check: %d frames, %d muscles, %d jiggles" % (len(poses) // per_frame, muscles, jiggles))


if __name__ == "__main__":
    main()
