"""The runtime's shared library from Python ctypes, as the Blender add-on loads it (docs/runtime.md):
the same frames and output as tests/c_api/runtime_c_check.c, which tests/runtime_c_api_test.cpp compares
with the in-process C API bit for bit.

usage: python3 runtime_ctypes_check.py LIBRARY EXTENSION.json NODE_COUNT POSES.f32 FRAME_SECONDS OUT.f32
"""
import array
import ctypes
import sys


def main():
    library, extension_path, node_count, poses_path, frame_seconds, out_path = sys.argv[1:7]
    node_count = int(node_count)
    lib = ctypes.CDLL(library)
    floats = ctypes.POINTER(ctypes.c_float)
    lib.rigbake_last_error.restype = ctypes.c_char_p
    lib.rigbake_rig_create.restype = ctypes.c_void_p
    lib.rigbake_rig_create.argtypes = [ctypes.c_char_p, ctypes.c_size_t, ctypes.c_int]
    lib.rigbake_rig_destroy.argtypes = [ctypes.c_void_p]
    for name in ("rigbake_rig_muscle_count", "rigbake_rig_jiggle_count"):
        getattr(lib, name).argtypes = [ctypes.c_void_p]
    lib.rigbake_rig_evaluate.argtypes = [ctypes.c_void_p, floats, floats, floats, floats]
    lib.rigbake_rig_store_skinned.argtypes = [ctypes.c_void_p, floats, floats]
    lib.rigbake_jiggle_impulse.argtypes = [ctypes.c_void_p, ctypes.c_int, floats, ctypes.c_float]
    lib.rigbake_jiggle_step.argtypes = [ctypes.c_void_p, floats, ctypes.c_float, ctypes.c_int, floats, floats, floats, floats]

    text = open(extension_path, "rb").read()
    rig = lib.rigbake_rig_create(text, len(text), node_count)
    if not rig:
        sys.exit("runtime_ctypes_check: " + lib.rigbake_last_error().decode())
    muscles, jiggles = lib.rigbake_rig_muscle_count(rig), lib.rigbake_rig_jiggle_count(rig)
    poses = array.array("f")
    poses.frombytes(open(poses_path, "rb").read())
    per_frame = 16 * node_count
    skinned = (ctypes.c_float * (16 * max(muscles, 1)))()
    corrections = (ctypes.c_float * (4 * max(jiggles, 1)))()
    hit = (ctypes.c_float * 3)(0.0, 0.0, 1.0)
    dt = float(frame_seconds)
    out = array.array("f")
    for frame in range(len(poses) // per_frame):
        pose = (ctypes.c_float * per_frame)(*poses[frame * per_frame:(frame + 1) * per_frame])
        assert lib.rigbake_rig_evaluate(rig, pose, skinned, None, None) == 0, lib.rigbake_last_error()
        assert lib.rigbake_rig_store_skinned(rig, skinned, pose) == 0
        if frame == 5 and jiggles > 0:
            assert lib.rigbake_jiggle_impulse(rig, -1, hit, 2.0) == 0
        assert lib.rigbake_jiggle_step(rig, pose, 0.0 if frame == 0 else dt, 0, corrections, None, None, None) == 0
        out.extend(skinned[:16 * muscles])
        out.extend(corrections[:4 * jiggles])
    lib.rigbake_rig_destroy(rig)
    with open(out_path, "wb") as file:
        file.write(out.tobytes())
    print("runtime_ctypes_check: %d frames, %d muscles, %d jiggles" % (len(poses) // per_frame, muscles, jiggles))


if __name__ == "__main__":
    main()
