// Converts a loaded VRM 0.x model ("VRM" extension) into VRM 1.0 ("VRMC_vrm", "VRMC_springBone") before
// the Character is built from it, so that every stage, and the VRM 1.0 writers (spring bones, the
// helper joints' VRMC_node_constraint), see a VRM 1.0. docs/extensions.md ("VRM 0.x in, VRM 1.0 out")
// lists what is converted and what is lost.
#pragma once

#include <string>
#include <vector>

namespace tinygltf {
class Model;
}

namespace rigbake {

// The VRM 1.0 humanoid bone name of a VRM 0.x one, "" when 1.0 has none. The names are the same but
// for the thumbs: 0.x counts them Proximal, Intermediate, Distal, 1.0 Metacarpal, Proximal, Distal
// (VRMC_vrm-1.0 humanoid.md; the same three bones).
std::string vrm1HumanBoneName(const std::string& vrm0_name);

// Rewrites `model` (which must carry "VRM") as a VRM 1.0: a root node turned 180 degrees about Y so the
// avatar faces +Z, the humanoid, meta, firstPerson and lookAt as VRMC_vrm, the secondaryAnimation as
// VRMC_springBone. Returns one sentence per thing the conversion did or could not carry over, for the
// CLI to print. Throws GLTF_PARSE_FAILED (naming `path` and the JSON pointer) when the VRM 0.x
// extension is malformed.
std::vector<std::string> convertVrm0ToVrm1(tinygltf::Model* model, const std::string& path);

}  // namespace rigbake
