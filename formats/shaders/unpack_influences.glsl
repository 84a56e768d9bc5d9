// rigbake packed skin influences, layout version 1 (docs/packed-influences.md): GLSL 4.50 decoders.
//
// After the God of War Ragnarök talk (Tenghao Wang, "Joint-Based Skin Deformation in God of War
// Ragnarök", "Increase Bone Influences per Vertex"): weights at 0.001 precision in 10-bit fields, three
// per 32-bit word (bits 0-9, 10-19, 20-29; bits 30-31 reserved, 0); N influences store N - 1 weights and
// the shader rebuilds the last as 1000 minus the others, in integers, so the weights sum to exactly 1.
//
// Include after `#version 450`. This file declares no inputs or buffers: bind the words and indices
// however the renderer fetches them (the glTF carrier attributes below, or a storage buffer holding the
// --packed-out arrays) and pass them in.

const uint RIGBAKE_WEIGHT_SCALE = 1000u;

// A 32-bit word from the glTF carrier's two UNSIGNED_SHORT components (low half first).
uint rigbakeWordFromShorts(uvec2 halves) {
  return halves.x | (halves.y << 16u);
}

// The three 10-bit weights of one word, in thousandths.
uvec3 rigbakeWeightFields(uint word) {
  return uvec3(bitfieldExtract(word, 0, 10), bitfieldExtract(word, 10, 10), bitfieldExtract(word, 20, 10));
}

// 4 influences: one word (the talk's R10G10B10A2 weights).
vec4 rigbakeUnpackWeights4(uint word) {
  uvec3 w = rigbakeWeightFields(word);
  uint last = RIGBAKE_WEIGHT_SCALE - (w.x + w.y + w.z);
  return vec4(vec3(w), float(last)) / float(RIGBAKE_WEIGHT_SCALE);
}

// 4 influences fetched through an R10G10B10A2_UNORM vertex format: the hardware hands over field / 1023,
// so the thousandths come back by scaling with 1023 and rounding (exact: fields are integers <= 1000).
vec4 rigbakeUnpackWeights4Unorm(vec4 unorm) {
  uvec3 w = uvec3(round(unorm.xyz * 1023.0));
  uint last = RIGBAKE_WEIGHT_SCALE - (w.x + w.y + w.z);
  return vec4(vec3(w), float(last)) / float(RIGBAKE_WEIGHT_SCALE);
}

// 7 influences: two words, 6 stored weights.
void rigbakeUnpackWeights7(uvec2 words, out float weights[7]) {
  uvec3 a = rigbakeWeightFields(words.x);
  uvec3 b = rigbakeWeightFields(words.y);
  uint last = RIGBAKE_WEIGHT_SCALE - (a.x + a.y + a.z + b.x + b.y + b.z);
  const float scale = 1.0 / float(RIGBAKE_WEIGHT_SCALE);
  weights[0] = float(a.x) * scale;
  weights[1] = float(a.y) * scale;
  weights[2] = float(a.z) * scale;
  weights[3] = float(b.x) * scale;
  weights[4] = float(b.y) * scale;
  weights[5] = float(b.z) * scale;
  weights[6] = float(last) * scale;
}

// 10 influences: three words, 9 stored weights.
void rigbakeUnpackWeights10(uvec3 words, out float weights[10]) {
  uvec3 a = rigbakeWeightFields(words.x);
  uvec3 b = rigbakeWeightFields(words.y);
  uvec3 c = rigbakeWeightFields(words.z);
  uint last = RIGBAKE_WEIGHT_SCALE - (a.x + a.y + a.z + b.x + b.y + b.z + c.x + c.y + c.z);
  const float scale = 1.0 / float(RIGBAKE_WEIGHT_SCALE);
  weights[0] = float(a.x) * scale;
  weights[1] = float(a.y) * scale;
  weights[2] = float(a.z) * scale;
  weights[3] = float(b.x) * scale;
  weights[4] = float(b.y) * scale;
  weights[5] = float(b.z) * scale;
  weights[6] = float(c.x) * scale;
  weights[7] = float(c.y) * scale;
  weights[8] = float(c.z) * scale;
  weights[9] = float(last) * scale;
}

// Joint index of slot k when the index records are read as 32-bit words (a storage buffer holding the
// --packed-out index array; records are 4-byte aligned): pass word (k * index_bytes) / 4 of the
// vertex's record. The glTF carrier needs no decoding: _RIGBAKE_PACKED_JOINTS_m arrive as uvec4/uvec2.
uint rigbakeJointIndex8(uint record_word, uint k) {
  return bitfieldExtract(record_word, int(8u * (k & 3u)), 8);
}

uint rigbakeJointIndex16(uint record_word, uint k) {
  return bitfieldExtract(record_word, int(16u * (k & 1u)), 16);
}
