// The extensions rigbake honours. An extension is listed only when rigbake's results are right for a
// file that requires it: rigbake reads it, or what it changes (materials, textures, lights, metadata)
// is something rigbake never looks at and writes back untouched. Extensions that change the skeleton,
// the skinned geometry or the animation rigbake samples (EXT_mesh_gpu_instancing,
// KHR_animation_pointer, VRMC_node_constraint, ...) are refused when required: rigbake would bake as if
// they were not there.
#include "formats/gltf_extensions.h"

#include <algorithm>

#include "core/error.h"

namespace rigbake {

const std::vector<HonouredExtension>& honouredExtensions() {
  static const std::vector<HonouredExtension> kExtensions = {
      {"KHR_mesh_quantization", ExtensionHandling::kRead,
       "Integer and normalized-integer positions, normals, texture coordinates, weights and animation "
       "values are dequantized on load. Outputs keep the file's accessors quantized and the extension required."},
      {"EXT_meshopt_compression", ExtensionHandling::kDecoded,
       "Compressed buffer views (ATTRIBUTES, TRIANGLES, INDICES; filters OCTAHEDRAL, QUATERNION, EXPONENTIAL) are "
       "decoded with meshoptimizer on load; outputs are written uncompressed, without the extension."},
      {"KHR_draco_mesh_compression", ExtensionHandling::kDecoded,
       "Compressed primitives are decoded with Draco on load; outputs are written uncompressed, without the "
       "extension."},
      {"KHR_texture_transform", ExtensionHandling::kPassedThrough,
       "rigbake never samples textures; materials and texture coordinates are written as they were."},
      {"KHR_texture_basisu", ExtensionHandling::kPassedThrough,
       "Images are kept as their encoded bytes (KTX2 included) and embedded with their MIME type."},
      {"EXT_texture_webp", ExtensionHandling::kPassedThrough,
       "Images are kept as their encoded bytes (WebP included) and embedded with their MIME type."},
      {"KHR_materials_pbrSpecularGlossiness", ExtensionHandling::kPassedThrough, "Materials are written as they were."},
      {"KHR_materials_unlit", ExtensionHandling::kPassedThrough, "Materials are written as they were."},
      {"KHR_materials_emissive_strength", ExtensionHandling::kPassedThrough, "Materials are written as they were."},
      {"KHR_materials_clearcoat", ExtensionHandling::kPassedThrough, "Materials are written as they were."},
      {"KHR_materials_ior", ExtensionHandling::kPassedThrough, "Materials are written as they were."},
      {"KHR_materials_specular", ExtensionHandling::kPassedThrough, "Materials are written as they were."},
      {"KHR_materials_sheen", ExtensionHandling::kPassedThrough, "Materials are written as they were."},
      {"KHR_materials_transmission", ExtensionHandling::kPassedThrough, "Materials are written as they were."},
      {"KHR_materials_volume", ExtensionHandling::kPassedThrough, "Materials are written as they were."},
      {"KHR_materials_iridescence", ExtensionHandling::kPassedThrough, "Materials are written as they were."},
      {"KHR_materials_anisotropy", ExtensionHandling::kPassedThrough, "Materials are written as they were."},
      {"KHR_materials_dispersion", ExtensionHandling::kPassedThrough, "Materials are written as they were."},
      {"KHR_materials_diffuse_transmission", ExtensionHandling::kPassedThrough, "Materials are written as they were."},
      {"KHR_materials_variants", ExtensionHandling::kPassedThrough,
       "Variants and each primitive's mappings are written as they were (the bake only replaces JOINTS_n/WEIGHTS_n)."},
      {"KHR_lights_punctual", ExtensionHandling::kPassedThrough,
       "Lights and the nodes' references to them are written as they were."},
      {"KHR_xmp_json_ld", ExtensionHandling::kPassedThrough, "Metadata is written as it was."},
      {"VRM", ExtensionHandling::kRead,
       "VRM 0.x: humanoid.humanBones map landmarks (presets/skeletons/vrm_humanoid.json); a bake with jiggles adds "
       "secondaryAnimation boneGroups; everything else is written as it was."},
      {"VRMC_vrm", ExtensionHandling::kRead,
       "VRM 1.0: humanoid.humanBones map landmarks; everything else is written as it was."},
      {"VRMC_springBone", ExtensionHandling::kRead,
       "VRM 1.0 spring bones: a bake with jiggles writes them as springs; a file's own springs are kept."},
      {"VRMC_materials_mtoon", ExtensionHandling::kPassedThrough, "Materials are written as they were."},
  };
  return kExtensions;
}

bool honoursExtension(const std::string& name) {
  const std::vector<HonouredExtension>& all = honouredExtensions();
  return std::any_of(all.begin(), all.end(), [&](const HonouredExtension& e) { return name == e.name; });
}

std::vector<std::string> unhonouredExtensions(const std::vector<std::string>& required) {
  std::vector<std::string> unhonoured;
  for (const std::string& name : required) {
    if (!honoursExtension(name) && std::find(unhonoured.begin(), unhonoured.end(), name) == unhonoured.end())
      unhonoured.push_back(name);
  }
  return unhonoured;
}

void requireHonouredExtensions(const std::vector<std::string>& required, const std::string& file) {
  const std::vector<std::string> unhonoured = unhonouredExtensions(required);
  if (unhonoured.empty()) return;
  std::string names;
  for (const std::string& name : unhonoured) names += (names.empty() ? "" : ", ") + name;
  fail(errc::GLTF_EXTENSION_UNSUPPORTED, file,
       "extensionsRequired names " + names + (unhonoured.size() == 1 ? ", an extension" : ", extensions") +
           " rigbake cannot honour, so the file cannot be read as its author meant (docs/extensions.md lists "
           "the extensions rigbake reads)");
}

}  // namespace rigbake
