// Bounds-checked reading of glTF accessors as doubles (normalized integers are mapped to [0,1] or
// [-1,1] as the glTF spec says; sparse substitutions are applied). Used by the loader only.
#pragma once

#include <string>
#include <vector>

namespace tinygltf {
class Model;
}

namespace rigbake {

struct AccessorData {
  int count = 0;
  int components = 0;          // 1 SCALAR, 2 VEC2, 3 VEC3, 4 VEC4, 16 MAT4
  std::vector<double> values;  // count * components, element-major
};

// Numbers per element of a glTF accessor type (TINYGLTF_TYPE_SCALAR ... MAT4); 0 for an unknown type.
int accessorComponentCount(int type);

// `where` names the file for error messages. Throws GLTF_ACCESSOR_INVALID on any range problem.
AccessorData readAccessor(const tinygltf::Model& model, int accessor, const std::string& where);

}  // namespace rigbake
