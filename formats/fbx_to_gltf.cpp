// Converts an FBX scene, as Assimp 5.2 imports it, into a glTF 2.0 model in memory.
//
// Why Assimp: it is the maintained library Debian packages (libassimp-dev) that reads binary FBX 7.x
// with skins and animations; Autodesk's FBX SDK is not free software, and ufbx and OpenFBX are not in
// Debian.
//
// Sources:
// - glTF 2.0 specification, "Skins": jointMatrix = world(joint) * inverseBindMatrix, the transform of
//   the node instancing a skinned mesh is ignored; "Animations": times in seconds, strictly
//   increasing, rotations unit quaternions (x, y, z, w); "Meshes": JOINTS_n/WEIGHTS_n in sets of 4,
//   weights summing to 1, unused slots weight 0 on joint 0; TEXCOORD_0 has its origin top left.
// - Assimp, aiBone::mOffsetMatrix "transforms from mesh space to bone space in bind pose": a skinned
//   vertex in the scene is world(bone) * offset * v, so glTF's inverse bind matrix is the offset.
// - FBX GlobalSettings: UpAxis, FrontAxis and CoordAxis (0 = X, 1 = Y, 2 = Z) with their signs name
//   the file's up, front and right axes, UnitScaleFactor is centimetres per file unit (1 = cm, 100 =
//   m). Assimp 5.2 passes them through as scene metadata and converts nothing by default; here one
//   root node maps the file's axes to glTF's (+X right, +Y up, +Z front) and its units to metres.
#include "formats/fbx_to_gltf.h"

#include <assimp/config.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <assimp/version.h>
#include <tiny_gltf.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <assimp/Importer.hpp>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <map>
#include <set>

#include "core/error.h"
#include "formats/atomic_file.h"
#include "formats/gltf_buffer.h"

namespace rigbake {

bool isFbxPath(const std::string& path) {
  if (path.size() < 4) return false;
  std::string tail = path.substr(path.size() - 4);
  for (char& c : tail) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return tail == ".fbx";
}

namespace {

constexpr int kArrayBuffer = 34962;
constexpr int kElementArrayBuffer = 34963;

Eigen::Matrix4d toEigen(const aiMatrix4x4& m) {
  Eigen::Matrix4d e;
  e << m.a1, m.a2, m.a3, m.a4, m.b1, m.b2, m.b3, m.b4, m.c1, m.c2, m.c3, m.c4, m.d1, m.d2, m.d3, m.d4;
  return e;
}

std::string firstLine(const std::string& text) {
  std::string line = text.substr(0, text.find('\n'));
  while (!line.empty() && (line.back() == '\r' || line.back() == ' ')) line.pop_back();
  return line.empty() ? "Assimp gave no reason" : line;
}

// The FBX importer's own checks come after Assimp has picked an importer by content, so a file that is
// not FBX at all could be read as OBJ or STL: refuse it first, by the FBX signatures.
bool looksLikeFbx(const std::string& bytes) {
  if (bytes.compare(0, 18, "Kaydara FBX Binary") == 0) return true;
  const std::string head = bytes.substr(0, 4096);
  return head.find("FBXHeaderExtension") != std::string::npos;
}

int metaInt(const aiMetadata* meta, const char* key, int fallback) {
  int32_t value = 0;
  return meta && meta->Get(std::string(key), value) ? value : fallback;
}

double metaNumber(const aiMetadata* meta, const char* key, double fallback) {
  float single = 0.0f;
  double value = 0.0;
  if (meta && meta->Get(std::string(key), value)) return value;
  if (meta && meta->Get(std::string(key), single)) return single;
  return fallback;
}

// The transform from the file's space to glTF's: rows are the file's right, up and front axes, times
// the size of a file unit in metres.
Eigen::Matrix4d fileToGltf(const aiScene& scene, const std::string& where) {
  const aiMetadata* meta = scene.mMetaData;
  const int axis[3] = {metaInt(meta, "CoordAxis", 0), metaInt(meta, "UpAxis", 1), metaInt(meta, "FrontAxis", 2)};
  const int sign[3] = {metaInt(meta, "CoordAxisSign", 1), metaInt(meta, "UpAxisSign", 1),
                       metaInt(meta, "FrontAxisSign", 1)};
  const double unit_cm = metaNumber(meta, "UnitScaleFactor", 1.0);
  Eigen::Matrix3d axes = Eigen::Matrix3d::Zero();
  for (int row = 0; row < 3; ++row) {
    if (axis[row] < 0 || axis[row] > 2 || (sign[row] != 1 && sign[row] != -1))
      fail(errc::FBX_PARSE_FAILED, where, "GlobalSettings names an invalid axis or axis sign");
    axes(row, axis[row]) = sign[row];
  }
  if (std::abs(std::abs(axes.determinant()) - 1.0) > 1e-9)
    fail(errc::FBX_PARSE_FAILED, where, "GlobalSettings names the same axis twice (up, front, right)");
  if (axes.determinant() < 0)
    fail(errc::FBX_PARSE_FAILED, where, "left-handed axis system (GlobalSettings CoordAxisSign): not supported");
  if (!(unit_cm > 0.0) || !std::isfinite(unit_cm))
    fail(errc::FBX_PARSE_FAILED, where, "GlobalSettings UnitScaleFactor is not a positive number");
  Eigen::Matrix4d to_gltf = Eigen::Matrix4d::Identity();
  to_gltf.block<3, 3>(0, 0) = axes * (unit_cm / 100.0);
  return to_gltf;
}

void setTrs(const Eigen::Matrix4d& matrix, tinygltf::Node* node) {
  const Eigen::Affine3d affine(matrix);
  Eigen::Matrix3d rotation, scaling;
  affine.computeRotationScaling(&rotation, &scaling);
  const Eigen::Vector3d t = affine.translation();
  const Eigen::Quaterniond q = Eigen::Quaterniond(rotation).normalized();
  const Eigen::Vector3d s = scaling.diagonal();
  if (!t.isZero(0.0)) node->translation = {t.x(), t.y(), t.z()};
  if (!q.isApprox(Eigen::Quaterniond::Identity(), 0.0)) node->rotation = {q.x(), q.y(), q.z(), q.w()};
  if (s != Eigen::Vector3d::Ones()) node->scale = {s.x(), s.y(), s.z()};
}

// Assimp's nodes in depth-first order (parents first), their world transforms in the file's space and
// the names the glTF gets: FBX allows two nodes of one name (a second armature's `Bone`), glTF
// consumers and rigbake's naming maps want them unique, so later ones get Blender's ".001" suffix.
struct SceneIndex {
  std::vector<const aiNode*> nodes;
  std::vector<int> parent;
  std::vector<int> top;  // the root's child above each node (the root: 0)
  std::vector<Eigen::Matrix4d> world;
  std::vector<std::string> names;
  std::multimap<std::string, int> by_name;  // Assimp's names, as bones and channels use them
};

SceneIndex indexScene(const aiScene& scene) {
  SceneIndex index;
  std::vector<std::pair<const aiNode*, int>> stack = {{scene.mRootNode, -1}};
  while (!stack.empty()) {
    auto [node, parent] = stack.back();
    stack.pop_back();
    const int i = static_cast<int>(index.nodes.size());
    index.nodes.push_back(node);
    index.parent.push_back(parent);
    index.top.push_back(parent <= 0 ? (parent < 0 ? 0 : i) : index.top[parent]);
    const Eigen::Matrix4d local = toEigen(node->mTransformation);
    index.world.push_back(parent < 0 ? local : Eigen::Matrix4d(index.world[parent] * local));
    index.by_name.emplace(node->mName.C_Str(), i);
    for (unsigned c = node->mNumChildren; c-- > 0;) stack.push_back({node->mChildren[c], i});
  }
  std::set<std::string> used;
  for (size_t i = 0; i < index.nodes.size(); ++i) {
    std::string base = index.nodes[i]->mName.length ? index.nodes[i]->mName.C_Str() : "node" + std::to_string(i);
    std::string name = base;
    for (int k = 1; used.count(name); ++k) {
      char suffix[16];
      std::snprintf(suffix, sizeof(suffix), ".%03d", k);
      name = base + suffix;
    }
    used.insert(name);
    index.names.push_back(name);
  }
  return index;
}

// The node a bone of a mesh on `mesh_node` deforms with. Bones refer to nodes by name only; when two
// nodes share it, the one whose rest pose agrees with the bone's offset (bind pose) is the one.
int boneNode(const SceneIndex& index, const aiBone& bone, int mesh_node, const std::string& where) {
  auto range = index.by_name.equal_range(bone.mName.C_Str());
  if (range.first == range.second)
    fail(errc::FBX_PARSE_FAILED, where, std::string("bone '") + bone.mName.C_Str() + "' has no node");
  const Eigen::Matrix4d offset = toEigen(bone.mOffsetMatrix);
  int best = -1;
  double best_mismatch = 0.0;
  for (auto it = range.first; it != range.second; ++it) {
    const Eigen::Matrix4d expected = index.world[it->second].inverse() * index.world[mesh_node];
    const double mismatch = (expected - offset).norm();
    if (best < 0 || mismatch < best_mismatch || (mismatch == best_mismatch && it->second < best)) {
      best = it->second;
      best_mismatch = mismatch;
    }
  }
  return best;
}

struct SkinBuild {
  std::vector<int> joints;  // scene node indices
  std::vector<Eigen::Matrix4d> inverse_binds;
  std::map<int, int> slot_of_node;
};

struct PrimitiveSource {
  const aiMesh* mesh = nullptr;
  std::vector<int> slot_of_bone;  // per aiBone, its slot in the skin's joint list
};

struct MeshGroup {
  int owner = -1;  // scene node index
  int skin = -1;   // index into the skins being built, -1 for a rigid mesh
  std::vector<PrimitiveSource> primitives;
};

bool sameMatrix(const Eigen::Matrix4d& a, const Eigen::Matrix4d& b) {
  return (a - b).cwiseAbs().maxCoeff() <= 1e-6 * std::max(1.0, a.cwiseAbs().maxCoeff());
}

bool hasTriangles(const aiMesh& mesh) {
  for (unsigned f = 0; f < mesh.mNumFaces; ++f) {
    if (mesh.mFaces[f].mNumIndices == 3) return true;
  }
  return false;
}

// Meshes of one node that share a skin become the primitives of one glTF mesh. Meshes whose bones
// bind differently (another armature's bone of the same name, another bind pose) get a skin of their
// own.
void groupMeshes(const aiScene& scene, const SceneIndex& index, const std::string& where,
                 std::vector<MeshGroup>* groups, std::vector<SkinBuild>* skins, FbxConversion* conversion) {
  for (size_t n = 0; n < index.nodes.size(); ++n) {
    const aiNode& node = *index.nodes[n];
    const size_t first_group = groups->size();
    for (unsigned k = 0; k < node.mNumMeshes; ++k) {
      const aiMesh* mesh = scene.mMeshes[node.mMeshes[k]];
      if (!hasTriangles(*mesh)) {
        conversion->notes.push_back("mesh '" + std::string(mesh->mName.C_Str()) + "' on node '" + index.names[n] +
                                    "' has no triangles (lines or points only): left out");
        continue;
      }
      PrimitiveSource source;
      source.mesh = mesh;
      std::vector<std::pair<int, Eigen::Matrix4d>> bones;
      for (unsigned b = 0; b < mesh->mNumBones; ++b)
        bones.push_back({boneNode(index, *mesh->mBones[b], static_cast<int>(n), where), toEigen(mesh->mBones[b]->mOffsetMatrix)});
      MeshGroup* group = nullptr;
      for (size_t g = first_group; g < groups->size() && !group; ++g) {
        MeshGroup& candidate = (*groups)[g];
        if ((candidate.skin < 0) != bones.empty()) continue;
        bool fits = true;
        if (candidate.skin >= 0) {
          const SkinBuild& skin = (*skins)[candidate.skin];
          for (const auto& [joint, offset] : bones) {
            auto it = skin.slot_of_node.find(joint);
            if (it != skin.slot_of_node.end() && !sameMatrix(skin.inverse_binds[it->second], offset)) fits = false;
          }
        }
        if (fits) group = &candidate;
      }
      if (!group) {
        groups->push_back(MeshGroup{static_cast<int>(n), bones.empty() ? -1 : static_cast<int>(skins->size()), {}});
        if (!bones.empty()) skins->emplace_back();
        group = &groups->back();
      }
      if (group->skin >= 0) {
        SkinBuild& skin = (*skins)[group->skin];
        for (const auto& [joint, offset] : bones) {
          auto inserted = skin.slot_of_node.emplace(joint, static_cast<int>(skin.joints.size()));
          if (inserted.second) {
            skin.joints.push_back(joint);
            skin.inverse_binds.push_back(offset);
          }
          source.slot_of_bone.push_back(inserted.first->second);
        }
      }
      group->primitives.push_back(std::move(source));
    }
  }
}

struct Influence {
  int slot;
  double weight;
};

// Per kept vertex, its influences by weight (heaviest first, then by slot), normalised to sum 1.
// A vertex that no bone weights is bound to the skin's first joint.
std::vector<std::vector<Influence>> vertexInfluences(const PrimitiveSource& source, const std::vector<int>& kept_index,
                                                     size_t kept, int* unweighted) {
  std::vector<std::vector<Influence>> influences(kept);
  const aiMesh& mesh = *source.mesh;
  for (unsigned b = 0; b < mesh.mNumBones; ++b) {
    const aiBone& bone = *mesh.mBones[b];
    for (unsigned w = 0; w < bone.mNumWeights; ++w) {
      const aiVertexWeight& weight = bone.mWeights[w];
      if (weight.mVertexId >= mesh.mNumVertices || kept_index[weight.mVertexId] < 0) continue;
      if (!(weight.mWeight > 0.0f) || !std::isfinite(weight.mWeight)) continue;
      std::vector<Influence>& list = influences[kept_index[weight.mVertexId]];
      auto same = std::find_if(list.begin(), list.end(), [&](const Influence& i) { return i.slot == source.slot_of_bone[b]; });
      if (same != list.end()) same->weight += weight.mWeight;
      else list.push_back({source.slot_of_bone[b], weight.mWeight});
    }
  }
  for (std::vector<Influence>& list : influences) {
    if (list.empty()) {
      list.push_back({0, 1.0});
      ++*unweighted;
      continue;
    }
    std::sort(list.begin(), list.end(), [](const Influence& a, const Influence& b) {
      return a.weight != b.weight ? a.weight > b.weight : a.slot < b.slot;
    });
    double sum = 0.0;
    for (const Influence& i : list) sum += i.weight;
    for (Influence& i : list) i.weight /= sum;
  }
  return influences;
}

void addSkinAttributes(const std::vector<std::vector<Influence>>& influences, GltfBufferAppender* buffers,
                       tinygltf::Primitive* primitive) {
  size_t most = 1;
  for (const std::vector<Influence>& list : influences) most = std::max(most, list.size());
  const size_t sets = (most + 3) / 4;
  for (size_t set = 0; set < sets; ++set) {
    std::vector<uint16_t> joints(influences.size() * 4, 0);
    std::vector<float> weights(influences.size() * 4, 0.0f);
    for (size_t v = 0; v < influences.size(); ++v) {
      for (size_t k = 0; k < 4 && set * 4 + k < influences[v].size(); ++k) {
        joints[v * 4 + k] = static_cast<uint16_t>(influences[v][set * 4 + k].slot);
        weights[v * 4 + k] = static_cast<float>(influences[v][set * 4 + k].weight);
      }
    }
    primitive->attributes["JOINTS_" + std::to_string(set)] =
        buffers->add(joints, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT, TINYGLTF_TYPE_VEC4, influences.size(), kArrayBuffer);
    primitive->attributes["WEIGHTS_" + std::to_string(set)] =
        buffers->add(weights, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC4, influences.size(), kArrayBuffer);
  }
}

// One primitive from an Assimp mesh: its triangles (faces of another size are left out, with the
// vertices only they use), positions, unit normals, the first UV set and, when skinned, its weights.
tinygltf::Primitive convertPrimitive(const PrimitiveSource& source, bool skinned, GltfBufferAppender* buffers,
                                     int* unweighted) {
  const aiMesh& mesh = *source.mesh;
  std::vector<int> kept_index(mesh.mNumVertices, -1);
  std::vector<unsigned> kept;
  std::vector<uint32_t> indices;
  for (unsigned f = 0; f < mesh.mNumFaces; ++f) {
    const aiFace& face = mesh.mFaces[f];
    if (face.mNumIndices != 3) continue;
    for (unsigned k = 0; k < 3; ++k) {
      const unsigned v = face.mIndices[k];
      if (kept_index[v] < 0) {
        kept_index[v] = static_cast<int>(kept.size());
        kept.push_back(v);
      }
      indices.push_back(static_cast<uint32_t>(kept_index[v]));
    }
  }
  std::vector<float> positions, normals, uvs;
  for (unsigned v : kept) {
    const aiVector3D& p = mesh.mVertices[v];
    positions.insert(positions.end(), {p.x, p.y, p.z});
    if (mesh.HasNormals()) {
      Eigen::Vector3f n(mesh.mNormals[v].x, mesh.mNormals[v].y, mesh.mNormals[v].z);
      n = n.norm() > 1e-12f && n.allFinite() ? Eigen::Vector3f(n.normalized()) : Eigen::Vector3f(0.0f, 1.0f, 0.0f);
      normals.insert(normals.end(), {n.x(), n.y(), n.z()});
    }
    if (mesh.HasTextureCoords(0)) uvs.insert(uvs.end(), {mesh.mTextureCoords[0][v].x, 1.0f - mesh.mTextureCoords[0][v].y});
  }
  tinygltf::Primitive primitive;
  primitive.mode = TINYGLTF_MODE_TRIANGLES;
  primitive.material = static_cast<int>(mesh.mMaterialIndex);
  std::vector<double> min, max;
  floatBounds(positions, 3, &min, &max);
  primitive.attributes["POSITION"] =
      buffers->add(positions, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC3, kept.size(), kArrayBuffer, min, max);
  if (!normals.empty())
    primitive.attributes["NORMAL"] = buffers->add(normals, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC3, kept.size(), kArrayBuffer);
  if (!uvs.empty())
    primitive.attributes["TEXCOORD_0"] = buffers->add(uvs, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC2, kept.size(), kArrayBuffer);
  if (skinned) addSkinAttributes(vertexInfluences(source, kept_index, kept.size(), unweighted), buffers, &primitive);
  primitive.indices = buffers->add(indices, TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT, TINYGLTF_TYPE_SCALAR, indices.size(),
                                   kElementArrayBuffer);
  return primitive;
}

void addMaterials(const aiScene& scene, tinygltf::Model* model) {
  for (unsigned m = 0; m < scene.mNumMaterials; ++m) {
    const aiMaterial& source = *scene.mMaterials[m];
    tinygltf::Material material;
    aiString name;
    if (source.Get(AI_MATKEY_NAME, name) == AI_SUCCESS) material.name = name.C_Str();
    aiColor4D diffuse(0.8f, 0.8f, 0.8f, 1.0f);
    source.Get(AI_MATKEY_COLOR_DIFFUSE, diffuse);
    float opacity = 1.0f;
    source.Get(AI_MATKEY_OPACITY, opacity);
    auto unit = [](float value) { return std::isfinite(value) ? std::clamp(static_cast<double>(value), 0.0, 1.0) : 1.0; };
    material.pbrMetallicRoughness.baseColorFactor = {unit(diffuse.r), unit(diffuse.g), unit(diffuse.b), unit(opacity)};
    // FBX's Lambert and Phong materials are not metals.
    material.pbrMetallicRoughness.metallicFactor = 0.0;
    material.pbrMetallicRoughness.roughnessFactor = 1.0;
    if (unit(opacity) < 1.0) material.alphaMode = "BLEND";
    model->materials.push_back(material);
  }
}

void addMeshes(const aiScene& scene, const SceneIndex& index, const std::string& where, tinygltf::Model* model,
               GltfBufferAppender* buffers, FbxConversion* conversion) {
  std::vector<MeshGroup> groups;
  std::vector<SkinBuild> skins;
  groupMeshes(scene, index, where, &groups, &skins, conversion);
  for (const SkinBuild& build : skins) {
    tinygltf::Skin skin;
    skin.joints = build.joints;
    std::vector<float> matrices;
    for (const Eigen::Matrix4d& inverse_bind : build.inverse_binds) {
      for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r) matrices.push_back(static_cast<float>(inverse_bind(r, c)));
    }
    skin.inverseBindMatrices = buffers->add(matrices, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_MAT4, build.joints.size(), 0);
    model->skins.push_back(skin);
  }
  int unweighted = 0;
  std::set<int> owners_used;
  for (const MeshGroup& group : groups) {
    tinygltf::Mesh mesh;
    mesh.name = group.primitives.front().mesh->mName.C_Str();
    for (const PrimitiveSource& source : group.primitives)
      mesh.primitives.push_back(convertPrimitive(source, group.skin >= 0, buffers, &unweighted));
    model->meshes.push_back(mesh);
    // The first group sits on its FBX node; another one on a child node with no transform of its own.
    int node = group.owner;
    if (!owners_used.insert(group.owner).second) {
      tinygltf::Node extra;
      extra.name = index.names[group.owner] + ".mesh" + std::to_string(model->nodes.size());
      node = static_cast<int>(model->nodes.size());
      model->nodes.push_back(extra);
      model->nodes[group.owner].children.push_back(node);
    }
    model->nodes[node].mesh = static_cast<int>(model->meshes.size()) - 1;
    model->nodes[node].skin = group.skin;
  }
  if (unweighted > 0)
    conversion->notes.push_back(std::to_string(unweighted) + " vertices of skinned meshes have no bone weight: bound to their skin's first joint");
}

// The node an animation channel drives. Channels name nodes, so a name two nodes share goes to the
// one under the top-level node (armature) that holds most of the clip's other channels.
std::vector<int> channelNodes(const aiAnimation& animation, const SceneIndex& index) {
  std::vector<int> targets(animation.mNumChannels, -1);
  std::map<int, int> votes;
  for (unsigned c = 0; c < animation.mNumChannels; ++c) {
    auto range = index.by_name.equal_range(animation.mChannels[c]->mNodeName.C_Str());
    if (range.first != range.second && std::next(range.first) == range.second) {
      targets[c] = range.first->second;
      ++votes[index.top[targets[c]]];
    }
  }
  for (unsigned c = 0; c < animation.mNumChannels; ++c) {
    auto range = index.by_name.equal_range(animation.mChannels[c]->mNodeName.C_Str());
    if (targets[c] >= 0 || range.first == range.second) continue;
    int best_votes = -1;
    for (auto it = range.first; it != range.second; ++it) {
      const int count = votes.count(index.top[it->second]) ? votes[index.top[it->second]] : 0;
      if (count > best_votes) {
        best_votes = count;
        targets[c] = it->second;
      }
    }
  }
  return targets;
}

struct Sampled {
  std::vector<float> times;
  std::vector<float> values;
};

// Keys in seconds, strictly increasing once stored as floats (a key at the time of the one before is
// dropped), as glTF requires of a sampler's input.
template <typename Key, typename Push>
Sampled sampleKeys(const Key* keys, unsigned count, double ticks_per_second, double start, Push push) {
  Sampled sampled;
  for (unsigned k = 0; k < count; ++k) {
    const float time = static_cast<float>(keys[k].mTime / ticks_per_second - start);
    if (!std::isfinite(time) || (!sampled.times.empty() && !(time > sampled.times.back()))) continue;
    sampled.times.push_back(time);
    push(keys[k].mValue, &sampled.values);
  }
  return sampled;
}

void addSampler(const Sampled& sampled, int node, const char* path, int type, GltfBufferAppender* buffers,
                tinygltf::Animation* animation) {
  if (sampled.times.empty()) return;
  const int input = buffers->addFloats(sampled.times, TINYGLTF_TYPE_SCALAR, 1, true);
  const int width = type == TINYGLTF_TYPE_VEC4 ? 4 : 3;
  addLinearChannel(input, buffers->addFloats(sampled.values, type, width), node, path, animation);
}

void addAnimations(const aiScene& scene, const SceneIndex& index, tinygltf::Model* model, GltfBufferAppender* buffers,
                   FbxConversion* conversion) {
  for (unsigned a = 0; a < scene.mNumAnimations; ++a) {
    const aiAnimation& source = *scene.mAnimations[a];
    const double ticks = source.mTicksPerSecond > 0.0 ? source.mTicksPerSecond : 25.0;
    // glTF times start at 0 or later: a clip keyed before 0 is shifted.
    double start = 0.0;
    for (unsigned c = 0; c < source.mNumChannels; ++c) {
      const aiNodeAnim& channel = *source.mChannels[c];
      if (channel.mNumPositionKeys) start = std::min(start, channel.mPositionKeys[0].mTime / ticks);
      if (channel.mNumRotationKeys) start = std::min(start, channel.mRotationKeys[0].mTime / ticks);
      if (channel.mNumScalingKeys) start = std::min(start, channel.mScalingKeys[0].mTime / ticks);
    }
    tinygltf::Animation animation;
    animation.name = source.mName.length ? source.mName.C_Str() : "animation" + std::to_string(a);
    const std::vector<int> targets = channelNodes(source, index);
    for (unsigned c = 0; c < source.mNumChannels; ++c) {
      const aiNodeAnim& channel = *source.mChannels[c];
      // The root node carries the axis and unit conversion, which a key would overwrite.
      if (targets[c] <= 0) {
        conversion->notes.push_back("clip '" + animation.name + "': channel of node '" + channel.mNodeName.C_Str() +
                                    "' left out (" + (targets[c] == 0 ? "the scene root" : "no such node") + ")");
        continue;
      }
      auto vec3 = [](const aiVector3D& v, std::vector<float>* out) { out->insert(out->end(), {v.x, v.y, v.z}); };
      auto quat = [](const aiQuaternion& q, std::vector<float>* out) {
        Eigen::Quaternionf r(q.w, q.x, q.y, q.z);
        r.normalize();
        const size_t n = out->size();
        // Consecutive keys in one hemisphere, so every engine's interpolation takes the short way.
        if (n >= 4 && r.x() * (*out)[n - 4] + r.y() * (*out)[n - 3] + r.z() * (*out)[n - 2] + r.w() * (*out)[n - 1] < 0.0f)
          r.coeffs() = -r.coeffs();
        out->insert(out->end(), {r.x(), r.y(), r.z(), r.w()});
      };
      addSampler(sampleKeys(channel.mPositionKeys, channel.mNumPositionKeys, ticks, start, vec3), targets[c],
                 "translation", TINYGLTF_TYPE_VEC3, buffers, &animation);
      addSampler(sampleKeys(channel.mRotationKeys, channel.mNumRotationKeys, ticks, start, quat), targets[c], "rotation",
                 TINYGLTF_TYPE_VEC4, buffers, &animation);
      addSampler(sampleKeys(channel.mScalingKeys, channel.mNumScalingKeys, ticks, start, vec3), targets[c], "scale",
                 TINYGLTF_TYPE_VEC3, buffers, &animation);
    }
    if (!animation.channels.empty()) model->animations.push_back(animation);
  }
}

}  // namespace

FbxConversion convertFbxToGltf(const std::string& path, tinygltf::Model* model) {
  const std::string bytes = readFile(path);
  if (!looksLikeFbx(bytes))
    fail(errc::FBX_PARSE_FAILED, path, "not an FBX file (neither the 'Kaydara FBX Binary' magic nor an ASCII FBX header)");
  Assimp::Importer importer;
  // Pivots as "$AssimpFbx$" helper nodes would stand between bones in the hierarchy.
  importer.SetPropertyBool(AI_CONFIG_IMPORT_FBX_PRESERVE_PIVOTS, false);
  importer.SetPropertyBool(AI_CONFIG_IMPORT_FBX_READ_CAMERAS, false);
  importer.SetPropertyBool(AI_CONFIG_IMPORT_FBX_READ_LIGHTS, false);
  const aiScene* scene = importer.ReadFileFromMemory(
      bytes.data(), bytes.size(), aiProcess_Triangulate | aiProcess_JoinIdenticalVertices | aiProcess_ValidateDataStructure,
      "fbx");
  if (!scene || !scene->mRootNode) fail(errc::FBX_PARSE_FAILED, path, firstLine(importer.GetErrorString()));
  if (scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE) fail(errc::FBX_PARSE_FAILED, path, "Assimp read the scene only in part");

  FbxConversion conversion;
  const SceneIndex index = indexScene(*scene);
  *model = tinygltf::Model();
  model->asset.version = "2.0";
  model->asset.generator = "rigbake (FBX through Assimp " + std::to_string(aiGetVersionMajor()) + "." +
                           std::to_string(aiGetVersionMinor()) + "." + std::to_string(aiGetVersionPatch()) + ")";
  for (size_t i = 0; i < index.nodes.size(); ++i) {
    tinygltf::Node node;
    node.name = index.names[i];
    const Eigen::Matrix4d local = toEigen(index.nodes[i]->mTransformation);
    setTrs(i == 0 ? Eigen::Matrix4d(fileToGltf(*scene, path) * local) : local, &node);
    model->nodes.push_back(node);
    if (index.parent[i] >= 0) model->nodes[index.parent[i]].children.push_back(static_cast<int>(i));
  }
  GltfBufferAppender buffers(model);
  addMaterials(*scene, model);
  addMeshes(*scene, index, path, model, &buffers, &conversion);
  addAnimations(*scene, index, model, &buffers, &conversion);
  tinygltf::Scene gltf_scene;
  gltf_scene.nodes = {0};
  model->scenes.push_back(gltf_scene);
  model->defaultScene = 0;
  return conversion;
}

}  // namespace rigbake
