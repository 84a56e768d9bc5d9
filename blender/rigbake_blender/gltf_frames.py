# Frames shared by glTF and Blender. glTF is Y-up, Blender Z-up: the glTF importer maps a glTF point
# (x, y, z) to (x, -z, y) (io_scene_gltf2 `Yup2Zup`), the rotation Y_UP_TO_Z_UP below. Bind matrices are
# computed in double from the file itself (numpy), as rigbake's reader does (formats/gltf_read.cpp
# `buildSkeleton`): B_n = G_s · IBM_{s,n}⁻¹ from the first skin listing n, G_s = W_root · IBM_{s,root}.
import numpy
from mathutils import Matrix

Y_UP_TO_Z_UP = Matrix(((1, 0, 0, 0), (0, 0, -1, 0), (0, 1, 0, 0), (0, 0, 0, 1)))
Z_UP_TO_Y_UP = Y_UP_TO_Z_UP.transposed()


def to_blender(matrix_gltf):
    """A glTF model-space matrix (numpy 4x4) as the Blender world matrix of the same frame."""
    return Y_UP_TO_Z_UP @ Matrix(matrix_gltf.tolist())


def point_to_gltf(point_blender):
    """A Blender world point as a glTF model-space point (numpy, double)."""
    x, y, z = point_blender
    return numpy.array([x, z, -y], dtype=float)


def point_to_blender(point_gltf):
    x, y, z = (float(c) for c in point_gltf)
    return (x, -z, y)


def _quaternion_matrix(x, y, z, w):
    return numpy.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])


def node_local(node):
    """A glTF node's local matrix (numpy 4x4, double) from its matrix or TRS."""
    if node.matrix is not None:
        return numpy.array(node.matrix, dtype=float).reshape(4, 4).T
    out = numpy.identity(4)
    rotation = node.rotation if node.rotation is not None else (0, 0, 0, 1)
    scale = node.scale if node.scale is not None else (1, 1, 1)
    out[:3, :3] = _quaternion_matrix(*rotation) @ numpy.diag(scale)
    if node.translation is not None:
        out[:3, 3] = node.translation
    return out


def rest_worlds(gltf):
    """Every node's world matrix at the file's rest pose."""
    nodes = gltf.data.nodes
    parent = [-1] * len(nodes)
    for index, node in enumerate(nodes):
        for child in node.children or []:
            parent[child] = index
    worlds = [None] * len(nodes)

    def world(index):
        if worlds[index] is None:
            local = node_local(nodes[index])
            worlds[index] = local if parent[index] < 0 else world(parent[index]) @ local
        return worlds[index]

    for index in range(len(nodes)):
        world(index)
    return worlds, parent


def bind_matrices(gltf):
    """{node index: bind matrix B_n} for every skin joint (numpy 4x4, double)."""
    from io_scene_gltf2.io.imp.gltf2_io_binary import BinaryData
    worlds, parent = rest_worlds(gltf)
    binds = {}
    for skin in gltf.data.skins or []:
        joints = list(skin.joints)
        if skin.inverse_bind_matrices is not None:
            data = BinaryData.get_data_from_accessor(gltf, skin.inverse_bind_matrices)
            inverse_binds = [numpy.array(m, dtype=float).reshape(4, 4).T for m in data]
        else:
            inverse_binds = [numpy.identity(4) for _ in joints]
        members = set(joints)

        def has_ancestor_in_skin(node):
            node = parent[node]
            while node >= 0:
                if node in members:
                    return True
                node = parent[node]
            return False

        root = next(k for k, joint in enumerate(joints) if not has_ancestor_in_skin(joint))
        skin_to_model = worlds[joints[root]] @ inverse_binds[root]
        for k, joint in enumerate(joints):
            if joint not in binds:
                binds[joint] = skin_to_model @ numpy.linalg.inv(inverse_binds[k])
    return binds
