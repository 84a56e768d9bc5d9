# rigbake's runtime library (librigbake_runtime.so, the C API of runtime/rigbake_runtime.h) through
# ctypes: the one declaration of its signatures in Python. It imports neither bpy nor mathutils, so the
# add-on (jiggle_play.py) and tests/runtime_ctypes_check.py (plain /usr/bin/python3) load the library
# the same way; a signature changed in the header is changed here only.
import ctypes
import ctypes.util
import os

API_MAJOR = 1  # rigbake_runtime_version() / 10000 this binding is written for

_rig = ctypes.c_void_p
_floats = ctypes.POINTER(ctypes.c_float)
_int, _float = ctypes.c_int, ctypes.c_float
# name: (return type, argument types), in the header's order.
SIGNATURES = {
    "rigbake_runtime_version": (ctypes.c_uint, []),
    "rigbake_last_error": (ctypes.c_char_p, []),
    "rigbake_rig_create": (_rig, [ctypes.c_char_p, ctypes.c_size_t, _int]),
    "rigbake_rig_destroy": (None, [_rig]),
    "rigbake_rig_node_count": (_int, [_rig]),
    "rigbake_rig_muscle_count": (_int, [_rig]),
    "rigbake_rig_jiggle_count": (_int, [_rig]),
    "rigbake_rig_muscle_name": (ctypes.c_char_p, [_rig, _int]),
    "rigbake_rig_muscle_is_corrective": (_int, [_rig, _int]),
    "rigbake_rig_muscle_node": (_int, [_rig, _int, _int]),
    "rigbake_rig_jiggle_name": (ctypes.c_char_p, [_rig, _int]),
    "rigbake_rig_jiggle_node": (_int, [_rig, _int, _int]),
    "rigbake_rig_node_used": (_int, [_rig, _int]),
    "rigbake_rig_evaluate": (_int, [_rig, _floats, _floats, _floats, _floats]),
    "rigbake_rig_store_skinned": (_int, [_rig, _floats, _floats]),
    "rigbake_jiggle_reset": (_int, [_rig, _floats, _floats, _float]),
    "rigbake_jiggle_step": (_int, [_rig, _floats, _float, _int, _floats, _floats, _floats, _floats]),
    "rigbake_jiggle_impulse": (_int, [_rig, _int, _floats, _float]),
}


class RuntimeMissing(Exception):
    """The library is not found or is of another major version (BLENDER_RUNTIME_MISSING, docs/errors.md)."""


def declare(lib):
    """Sets every function's ctypes signature on a loaded library; returns it."""
    for name, (restype, argtypes) in SIGNATURES.items():
        function = getattr(lib, name)
        function.restype = restype
        function.argtypes = argtypes
    return lib


def load(candidates):
    """The first of `candidates` (paths, or bare names for the system's loader) that loads, declared
    and of API_MAJOR; RuntimeMissing naming what was tried otherwise."""
    candidates = list(candidates)
    found = ctypes.util.find_library("rigbake_runtime")
    if found:
        candidates.append(found)
    for path in candidates:
        if not (os.path.exists(path) or "/" not in path):
            continue
        try:
            lib = declare(ctypes.CDLL(path))
        except OSError:
            continue
        if lib.rigbake_runtime_version() // 10000 != API_MAJOR:
            raise RuntimeMissing("BLENDER_RUNTIME_MISSING %s: C API version %d, this add-on needs %d.x"
                                 % (path, lib.rigbake_runtime_version(), API_MAJOR))
        return lib
    raise RuntimeMissing("BLENDER_RUNTIME_MISSING librigbake_runtime.so: not found (tried %s)"
                         % (", ".join(candidates) or "nothing"))


def check(lib, status, what):
    """Raises RuntimeError with the library's own message when a call returned non-zero."""
    if status != 0:
        raise RuntimeError("rigbake runtime %s: %s" % (what, lib.rigbake_last_error().decode("utf-8", "replace")))


def floats(count, values=()):
    """A ctypes float array of `count` (at least 1, so a null-sized output is still a valid pointer)."""
    array = (ctypes.c_float * max(count, 1))()
    if values:
        array[:len(values)] = values
    return array


def create_rig(lib, extension_json, node_count):
    """rigbake_rig_create on the extension's JSON text (str or bytes); RuntimeError with the
    library's message when it refuses it. The caller frees it with rigbake_rig_destroy."""
    text = extension_json.encode("utf-8") if isinstance(extension_json, str) else extension_json
    handle = lib.rigbake_rig_create(text, len(text), node_count)
    if not handle:
        raise RuntimeError("rigbake runtime: " + lib.rigbake_last_error().decode("utf-8", "replace"))
    return handle
