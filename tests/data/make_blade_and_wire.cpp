// Writes tests/data/blade_and_wire_ascii.fbx through Assimp's ASCII FBX exporter: a triangle skinned to two
// bones (Root, Tip 50 units above it; the FBX unit is the centimetre) and a mesh of two lines, which
// the FBX conversion leaves out with a note. Not part of the build (tests/CMakeLists.txt globs tests/*.cpp):
//   g++ -std=c++17 tests/data/make_blade_and_wire.cpp -o /tmp/make_fbx -lassimp && /tmp/make_fbx tests/data/blade_and_wire_ascii.fbx
#include <assimp/Exporter.hpp>
#include <assimp/scene.h>
#include <cstdio>
#include <cstring>
int main(int, char** argv) {
  aiScene* s = new aiScene();
  s->mRootNode = new aiNode("RootNode");
  s->mNumMaterials = 1; s->mMaterials = new aiMaterial*[1]; s->mMaterials[0] = new aiMaterial();
  aiString mname("Skin"); s->mMaterials[0]->AddProperty(&mname, AI_MATKEY_NAME);
  s->mNumMeshes = 2; s->mMeshes = new aiMesh*[2];
  aiMesh* tri = new aiMesh(); tri->mName = "Blade"; tri->mPrimitiveTypes = aiPrimitiveType_TRIANGLE;
  tri->mNumVertices = 3; tri->mVertices = new aiVector3D[3]{{0,0,0},{10,0,0},{0,100,0}};
  tri->mNormals = new aiVector3D[3]{{0,0,1},{0,0,1},{0,0,1}};
  tri->mNumFaces = 1; tri->mFaces = new aiFace[1]; tri->mFaces[0].mNumIndices = 3; tri->mFaces[0].mIndices = new unsigned[3]{0,1,2};
  tri->mNumBones = 2; tri->mBones = new aiBone*[2];
  const char* names[2] = {"Root", "Tip"};
  for (int b = 0; b < 2; ++b) {
    aiBone* bone = new aiBone(); bone->mName = names[b];
    aiMatrix4x4::Translation(aiVector3D(0, b == 0 ? 0.f : -50.f, 0), bone->mOffsetMatrix);
    bone->mNumWeights = b == 0 ? 2 : 2; bone->mWeights = new aiVertexWeight[2];
    if (b == 0) { bone->mWeights[0] = aiVertexWeight(0, 1.f); bone->mWeights[1] = aiVertexWeight(1, 1.f); }
    else { bone->mWeights[0] = aiVertexWeight(2, 0.75f); bone->mWeights[1] = aiVertexWeight(1, 0.f); }
    tri->mBones[b] = bone;
  }
  s->mMeshes[0] = tri;
  aiMesh* wire = new aiMesh(); wire->mName = "Wire"; wire->mPrimitiveTypes = aiPrimitiveType_LINE;
  wire->mNumVertices = 3; wire->mVertices = new aiVector3D[3]{{0,0,0},{0,50,0},{0,100,0}};
  wire->mNumFaces = 2; wire->mFaces = new aiFace[2];
  for (int f = 0; f < 2; ++f) { wire->mFaces[f].mNumIndices = 2; wire->mFaces[f].mIndices = new unsigned[2]{unsigned(f), unsigned(f + 1)}; }
  s->mMeshes[1] = wire;
  aiNode* arm = new aiNode("Armature"); aiNode* root = new aiNode("Root"); aiNode* tip = new aiNode("Tip");
  aiMatrix4x4::Translation(aiVector3D(0, 50, 0), tip->mTransformation);
  aiNode* blade = new aiNode("Blade"); blade->mNumMeshes = 1; blade->mMeshes = new unsigned[1]{0};
  aiNode* wiren = new aiNode("Wire"); wiren->mNumMeshes = 1; wiren->mMeshes = new unsigned[1]{1};
  aiNode* top[3] = {arm, blade, wiren};
  s->mRootNode->addChildren(3, top);
  arm->addChildren(1, &root); root->addChildren(1, &tip);
  s->mNumAnimations = 1; s->mAnimations = new aiAnimation*[1];
  aiAnimation* a = new aiAnimation(); a->mName = "Bend"; a->mTicksPerSecond = 24; a->mDuration = 12;
  a->mNumChannels = 1; a->mChannels = new aiNodeAnim*[1];
  aiNodeAnim* ch = new aiNodeAnim(); ch->mNodeName = "Tip";
  ch->mNumRotationKeys = 2; ch->mRotationKeys = new aiQuatKey[2];
  ch->mRotationKeys[0] = aiQuatKey(0, aiQuaternion()); ch->mRotationKeys[1] = aiQuatKey(12, aiQuaternion(aiVector3D(0,0,1), 1.0f));
  ch->mNumPositionKeys = 2; ch->mPositionKeys = new aiVectorKey[2];
  ch->mPositionKeys[0] = aiVectorKey(0, aiVector3D(0,50,0)); ch->mPositionKeys[1] = aiVectorKey(12, aiVector3D(0,50,0));
  ch->mNumScalingKeys = 2; ch->mScalingKeys = new aiVectorKey[2];
  ch->mScalingKeys[0] = aiVectorKey(0, aiVector3D(1,1,1)); ch->mScalingKeys[1] = aiVectorKey(12, aiVector3D(1,1,1));
  a->mChannels[0] = ch; s->mAnimations[0] = a;
  Assimp::Exporter ex;
  if (ex.Export(s, "fbxa", argv[1]) != AI_SUCCESS) { printf("ERR %s\n", ex.GetErrorString()); return 1; }
  return 0;
}
