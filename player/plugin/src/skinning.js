// Skinning 4, 7 or 10 influences from rigbake's packed attributes (docs/packed-influences.md) in the
// mesh's own vertex shader: three.js skins 4 (its skinIndex / skinWeight, from JOINTS_0 / WEIGHTS_0;
// three.js issue 26137), so the plugin patches three's skinning chunks of the mesh's own material.
// The decoder is the one of formats/shaders/unpack_influences.glsl, written for GLSL ES 3.00 (no
// bitfieldExtract there: shifts and masks). The same GLSL text is compiled into a transform-feedback
// program (readBackSkinning) that the browser test reads the GPU-skinned positions back with.

import * as THREE from 'three';

// The carrier attributes as GLTFLoader names them (glTF semantics lower-cased), and the names the
// player gives them (GLSL identifiers must not start with an underscore in every driver).
const PACKED_WEIGHTS = ['_rigbake_packed_weights_0', '_rigbake_packed_weights_1'];
const PACKED_JOINTS = ['_rigbake_packed_joints_0', '_rigbake_packed_joints_1', '_rigbake_packed_joints_2'];
const WEIGHT_NAMES = ['rbWeights0', 'rbWeights1'];
const JOINT_NAMES = ['rbJoints0', 'rbJoints1', 'rbJoints2'];

// The packed layout of a geometry, read from its attributes as docs/packed-influences.md section 7
// says (number of weight words, joint pieces): {influences, indexBytes} or null when it has none.
export function packedLayout(geometry) {
  const w0 = geometry.getAttribute(PACKED_WEIGHTS[0]) || geometry.getAttribute(WEIGHT_NAMES[0]);
  if (!w0) return null;
  const w1 = geometry.getAttribute(PACKED_WEIGHTS[1]) || geometry.getAttribute(WEIGHT_NAMES[1]);
  const words = w0.itemSize / 2 + (w1 ? w1.itemSize / 2 : 0);
  const influences = words * 3 + 1; // N - 1 = 3 W
  const j0 = geometry.getAttribute(PACKED_JOINTS[0]) || geometry.getAttribute(JOINT_NAMES[0]);
  if (!j0 || ![4, 7, 10].includes(influences)) return null;
  const indexBytes = j0.array.BYTES_PER_ELEMENT;
  return { influences, indexBytes };
}

// Renames the carrier attributes and marks them as integers, so that WebGL2 binds them with
// vertexAttribIPointer and the shader reads them as uvec4 (the values are not normalized).
export function preparePackedAttributes(geometry) {
  const rename = (from, to) => {
    const attribute = geometry.getAttribute(from);
    if (!attribute) return;
    attribute.gpuType = THREE.IntType;
    geometry.deleteAttribute(from);
    geometry.setAttribute(to, attribute);
  };
  PACKED_WEIGHTS.forEach((name, i) => rename(name, WEIGHT_NAMES[i]));
  PACKED_JOINTS.forEach((name, i) => rename(name, JOINT_NAMES[i]));
  return packedLayout(geometry);
}

// The GLSL, in three pieces. RB_INFLUENCES is the file's N (4, 7, 10), RB_KEEP the slots used (N, or
// fewer to preview a smaller budget: the kept weights are then renormalized).
export const PACKED_INPUTS_GLSL = /* glsl */ `
in uvec4 rbWeights0;
#if RB_INFLUENCES == 10
in uvec4 rbWeights1;
#endif
in uvec4 rbJoints0;
#if RB_INFLUENCES >= 7
in uvec4 rbJoints1;
#endif
#if RB_INFLUENCES == 10
in uvec4 rbJoints2;
#endif
`;

// A bone matrix from a three.js bone texture (4 RGBA32F texels per bone, row after row).
export const BONE_MATRIX_GLSL = /* glsl */ `
mat4 rbBoneMatrix(highp sampler2D bones, uint i) {
  int size = textureSize(bones, 0).x;
  int j = int(i) * 4;
  int x = j % size;
  int y = j / size;
  return mat4(texelFetch(bones, ivec2(x, y), 0), texelFetch(bones, ivec2(x + 1, y), 0),
              texelFetch(bones, ivec2(x + 2, y), 0), texelFetch(bones, ivec2(x + 3, y), 0));
}
`;

export const PACKED_FUNCTIONS_GLSL = /* glsl */ `
// rigbakeWordFromShorts: a 32-bit word from two UNSIGNED_SHORT components, low half first.
uint rbWord(uvec2 halves) { return halves.x | (halves.y << 16u); }
// rigbakeWeightFields: the three 10-bit weights of one word, in thousandths.
uvec3 rbFields(uint word) { return uvec3(word & 1023u, (word >> 10u) & 1023u, (word >> 20u) & 1023u); }

// The vertex's influences: weights (0..1 in 0.001 steps, summing to exactly 1: the last rebuilt in
// integers as 1000 minus the others, as rigbakeUnpackWeights4/7/10 do) and skin joint indices.
void rbInfluences(out float weights[10], out uint joints[12]) {
  uint fields[9];
  for (int k = 0; k < 9; ++k) fields[k] = 0u;
  uvec3 a = rbFields(rbWord(rbWeights0.xy));
  fields[0] = a.x; fields[1] = a.y; fields[2] = a.z;
#if RB_INFLUENCES >= 7
  uvec3 b = rbFields(rbWord(rbWeights0.zw));
  fields[3] = b.x; fields[4] = b.y; fields[5] = b.z;
#endif
#if RB_INFLUENCES == 10
  uvec3 c = rbFields(rbWord(rbWeights1.xy));
  fields[6] = c.x; fields[7] = c.y; fields[8] = c.z;
#endif
  uint stored = 0u;
  for (int k = 0; k < RB_INFLUENCES - 1; ++k) stored += fields[k];
  for (int k = 0; k < 10; ++k) weights[k] = 0.0;
  for (int k = 0; k < RB_INFLUENCES - 1; ++k) weights[k] = float(fields[k]) / 1000.0;
  weights[RB_INFLUENCES - 1] = float(1000u - stored) / 1000.0;
#if RB_KEEP < RB_INFLUENCES
  float kept = 0.0;
  for (int k = 0; k < RB_KEEP; ++k) kept += weights[k];
  for (int k = 0; k < RB_KEEP; ++k) weights[k] = kept > 0.0 ? weights[k] / kept : 0.0;
#endif
  joints[0] = rbJoints0.x; joints[1] = rbJoints0.y; joints[2] = rbJoints0.z; joints[3] = rbJoints0.w;
#if RB_INFLUENCES >= 7
  joints[4] = rbJoints1.x; joints[5] = rbJoints1.y; joints[6] = rbJoints1.z; joints[7] = rbJoints1.w;
#else
  joints[4] = 0u; joints[5] = 0u; joints[6] = 0u; joints[7] = 0u;
#endif
#if RB_INFLUENCES == 10
  joints[8] = rbJoints2.x; joints[9] = rbJoints2.y; joints[10] = rbJoints2.z; joints[11] = rbJoints2.w;
#else
  joints[8] = 0u; joints[9] = 0u; joints[10] = 0u; joints[11] = 0u;
#endif
}

// Linear blend skinning of a position, in three.js's order: sum_k M_k p w_k.
vec4 rbSkinPosition(highp sampler2D bones, vec4 p, float weights[10], uint joints[12]) {
  vec4 skinned = vec4(0.0);
  for (int k = 0; k < RB_KEEP; ++k) skinned += rbBoneMatrix(bones, joints[k]) * p * weights[k];
  return skinned;
}

// The blended matrix, for normals and tangents.
mat4 rbSkinMatrix(highp sampler2D bones, float weights[10], uint joints[12]) {
  mat4 m = mat4(0.0);
  for (int k = 0; k < RB_KEEP; ++k) m += weights[k] * rbBoneMatrix(bones, joints[k]);
  return m;
}
`;

export const PACKED_SKINNING_GLSL = PACKED_INPUTS_GLSL + BONE_MATRIX_GLSL + PACKED_FUNCTIONS_GLSL;

// The heat colour of a displacement d (metres) for a full scale: blue (0), green, yellow, red (full).
export const HEAT_GLSL = /* glsl */ `
vec3 rbHeat(float d, float fullScale) {
  float t = clamp(d / fullScale, 0.0, 1.0);
  vec3 blue = vec3(0.15, 0.25, 0.85), green = vec3(0.2, 0.8, 0.3), red = vec3(0.9, 0.15, 0.1);
  return t < 0.5 ? mix(blue, green, 2.0 * t) : mix(green, red, 2.0 * t - 1.0);
}
`;

// The plain-skinning bone texture of a skeleton: the same layout as three's boneTexture.
export function makeBoneTexture(skeleton) {
  const size = Math.max(4, Math.ceil(Math.sqrt(skeleton.bones.length * 4) / 4) * 4);
  const data = new Float32Array(size * size * 4);
  const texture = new THREE.DataTexture(data, size, size, THREE.RGBAFormat, THREE.FloatType);
  texture.needsUpdate = true;
  return texture;
}

// The skinning state of a skinned mesh (mesh.userData.rigbakeSkinning), made once: its packed
// attributes renamed for WebGL 2, its materials cloned (a material shared with another mesh must not
// get this mesh's shader) and patched to skin every influence the file packs. A host changes
// `influences` (4 = three's own skinning, up to fileInfluences) or `heatmap` and calls
// applySkinningState(mesh) to recompile.
export function prepareSkinning(mesh) {
  if (mesh.userData.rigbakeSkinning) return mesh.userData.rigbakeSkinning;
  const layout = preparePackedAttributes(mesh.geometry);
  const state = {
    layout,
    fileInfluences: layout ? layout.influences : 0,
    influences: layout ? layout.influences : 4,
    heatmap: false,
    plainTexture: makeBoneTexture(mesh.skeleton),
    uniforms: { rbPlainBones: { value: null }, rbHeatScale: { value: 0.01 } },
    patched: null,
  };
  state.uniforms.rbPlainBones.value = state.plainTexture;
  mesh.material = Array.isArray(mesh.material) ? mesh.material.map((m) => m.clone()) : mesh.material.clone();
  mesh.userData.rigbakeSkinning = state;
  applySkinningState(mesh);
  return state;
}

// Recompiles the mesh's materials when its state's influences or heatmap changed.
export function applySkinningState(mesh) {
  const state = mesh.userData.rigbakeSkinning;
  if (!state.fileInfluences) state.influences = 4;
  const key = `${state.influences}-${state.heatmap}`;
  if (state.patched === key) return;
  state.patched = key;
  for (const material of Array.isArray(mesh.material) ? mesh.material : [mesh.material]) patchSkinningMaterial(material, state);
}

// Patches a (cloned) material of a skinned mesh. mode: {influences: 4 | 7 | 10 (4 = three's own
// skinning of JOINTS_0 / WEIGHTS_0), fileInfluences, heatmap, uniforms: {rbPlainBones, rbHeatScale}}.
// The shader is recompiled when the key changes.
export function patchSkinningMaterial(material, state) {
  material.onBeforeCompile = (shader) => {
    const packed = state.influences > 4;
    shader.uniforms.rbPlainBones = state.uniforms.rbPlainBones;
    shader.uniforms.rbHeatScale = state.uniforms.rbHeatScale;
    let vertex = shader.vertexShader;
    const defines = `#define RB_INFLUENCES ${state.fileInfluences}\n#define RB_KEEP ${state.influences}\n`;
    let declarations = `${defines}uniform highp sampler2D rbPlainBones;\nout float vRbDisplacement;\n`;
    declarations += packed ? PACKED_SKINNING_GLSL : BONE_MATRIX_GLSL;
    vertex = vertex.replace('#include <skinning_pars_vertex>', `#include <skinning_pars_vertex>\n#ifdef USE_SKINNING\n${declarations}\n#endif`);
    if (packed) {
      vertex = vertex.replace(
        '#include <skinbase_vertex>',
        `#ifdef USE_SKINNING
  float rbW[10];
  uint rbJ[12];
  rbInfluences(rbW, rbJ);
  mat4 rbSkin = rbSkinMatrix(boneTexture, rbW, rbJ);
#endif`,
      );
      vertex = vertex.replace(
        '#include <skinnormal_vertex>',
        `#ifdef USE_SKINNING
  mat4 skinMatrix = bindMatrixInverse * rbSkin * bindMatrix;
  objectNormal = vec4(skinMatrix * vec4(objectNormal, 0.0)).xyz;
  #ifdef USE_TANGENT
  objectTangent = vec4(skinMatrix * vec4(objectTangent, 0.0)).xyz;
  #endif
#endif`,
      );
      vertex = vertex.replace(
        '#include <skinning_vertex>',
        `#ifdef USE_SKINNING
  vec4 skinVertex = bindMatrix * vec4(transformed, 1.0);
  vec4 skinned = rbSkinPosition(boneTexture, skinVertex, rbW, rbJ);
  vRbDisplacement = ${state.heatmap ? 'length((skinned - rbSkinPosition(rbPlainBones, skinVertex, rbW, rbJ)).xyz)' : '0.0'};
  transformed = (bindMatrixInverse * skinned).xyz;
#endif`,
      );
    } else {
      // Three's own 4-influence skinning; the heatmap adds the plain skinning beside it.
      vertex = vertex.replace(
        '#include <skinning_vertex>',
        `#include <skinning_vertex>
#ifdef USE_SKINNING
  ${
    state.heatmap
      ? `vec4 rbPlain = rbBoneMatrix(rbPlainBones, uint(skinIndex.x)) * skinVertex * skinWeight.x
                 + rbBoneMatrix(rbPlainBones, uint(skinIndex.y)) * skinVertex * skinWeight.y
                 + rbBoneMatrix(rbPlainBones, uint(skinIndex.z)) * skinVertex * skinWeight.z
                 + rbBoneMatrix(rbPlainBones, uint(skinIndex.w)) * skinVertex * skinWeight.w;
  vRbDisplacement = length((skinned - rbPlain).xyz);`
      : 'vRbDisplacement = 0.0;'
  }
#endif`,
      );
    }
    shader.vertexShader = vertex;
    if (state.heatmap) {
      shader.fragmentShader = shader.fragmentShader
        .replace('#include <common>', `#include <common>\nuniform float rbHeatScale;\nin float vRbDisplacement;\n${HEAT_GLSL}`)
        .replace('#include <color_fragment>', '#include <color_fragment>\n  diffuseColor.rgb = rbHeat(vRbDisplacement, rbHeatScale);');
    }
  };
  material.customProgramCacheKey = () => `rigbake-${state.fileInfluences}-${state.influences}-${state.heatmap ? 1 : 0}`;
  material.needsUpdate = true;
}

// ---- Reading the GPU's skinning back (transform feedback) ----

const READBACK_VERTEX = (fileInfluences, keep) => `#version 300 es
#define RB_INFLUENCES ${fileInfluences}
#define RB_KEEP ${keep}
precision highp float;
precision highp int;
in vec3 position;
uniform highp sampler2D boneTexture;
uniform mat4 bindMatrix;
${PACKED_SKINNING_GLSL}
out vec3 rbSkinned;
void main() {
  float rbW[10];
  uint rbJ[12];
  rbInfluences(rbW, rbJ);
  rbSkinned = rbSkinPosition(boneTexture, bindMatrix * vec4(position, 1.0), rbW, rbJ).xyz;
  gl_Position = vec4(0.0, 0.0, 0.0, 1.0);
}
`;
const READBACK_FRAGMENT = `#version 300 es
precision highp float;
out vec4 color;
void main() { color = vec4(1.0); }
`;

function compile(gl, type, source) {
  const shader = gl.createShader(type);
  gl.shaderSource(shader, source);
  gl.compileShader(shader);
  if (!gl.getShaderParameter(shader, gl.COMPILE_STATUS)) throw new Error(`skinning shader: ${gl.getShaderInfoLog(shader)}`);
  return shader;
}

// The skinned positions of a skinned mesh's vertices as the player's shader computes them, read back
// by WebGL2 transform feedback on its own context (so three's GL state is untouched): world-space
// positions (bindMatrix applied, as three's shader; bindMatrixInverse and the model matrix cancel
// out). `boneData` is three's bone texture data for this frame (Skeleton.boneMatrices, padded).
// The read-back programs of a context, one per (N, kept) pair: compiling one costs about a second under
// software WebGL, and a test reads many frames back.
const readBackPrograms = new WeakMap();
function readBackProgram(gl, fileInfluences, keep) {
  if (!readBackPrograms.has(gl)) readBackPrograms.set(gl, new Map());
  const programs = readBackPrograms.get(gl);
  const key = `${fileInfluences}-${keep}`;
  if (programs.has(key)) return programs.get(key);
  const program = gl.createProgram();
  gl.attachShader(program, compile(gl, gl.VERTEX_SHADER, READBACK_VERTEX(fileInfluences, keep)));
  gl.attachShader(program, compile(gl, gl.FRAGMENT_SHADER, READBACK_FRAGMENT));
  gl.transformFeedbackVaryings(program, ['rbSkinned'], gl.INTERLEAVED_ATTRIBS);
  gl.linkProgram(program);
  if (!gl.getProgramParameter(program, gl.LINK_STATUS)) throw new Error(`skinning program: ${gl.getProgramInfoLog(program)}`);
  programs.set(key, program);
  return program;
}

export function readBackSkinning(gl, mesh, boneData, fileInfluences, keep = fileInfluences) {
  const program = readBackProgram(gl, fileInfluences, keep);
  gl.useProgram(program);
  const geometry = mesh.geometry;
  const count = geometry.getAttribute('position').count;
  const vao = gl.createVertexArray();
  gl.bindVertexArray(vao);
  const buffers = [];
  const bind = (name, attribute, integer) => {
    const location = gl.getAttribLocation(program, name);
    if (location < 0 || !attribute) return;
    const buffer = gl.createBuffer();
    buffers.push(buffer);
    gl.bindBuffer(gl.ARRAY_BUFFER, buffer);
    // Interleaved attributes are copied out to a tight array first.
    let array = attribute.array;
    let itemSize = attribute.itemSize;
    if (attribute.isInterleavedBufferAttribute) {
      array = new array.constructor(count * itemSize);
      for (let v = 0; v < count; ++v) for (let c = 0; c < itemSize; ++c) array[v * itemSize + c] = attribute.getComponent(v, c);
    }
    gl.bufferData(gl.ARRAY_BUFFER, array, gl.STATIC_DRAW);
    gl.enableVertexAttribArray(location);
    const type = array instanceof Float32Array ? gl.FLOAT : array instanceof Uint16Array ? gl.UNSIGNED_SHORT : gl.UNSIGNED_BYTE;
    if (integer) gl.vertexAttribIPointer(location, itemSize, type, 0, 0);
    else gl.vertexAttribPointer(location, itemSize, type, !!attribute.normalized, 0, 0);
  };
  bind('position', geometry.getAttribute('position'), false);
  WEIGHT_NAMES.forEach((name) => bind(name, geometry.getAttribute(name), true));
  JOINT_NAMES.forEach((name) => bind(name, geometry.getAttribute(name), true));

  const size = Math.round(Math.sqrt(boneData.length / 4));
  const texture = gl.createTexture();
  gl.activeTexture(gl.TEXTURE0);
  gl.bindTexture(gl.TEXTURE_2D, texture);
  gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MIN_FILTER, gl.NEAREST);
  gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MAG_FILTER, gl.NEAREST);
  gl.texImage2D(gl.TEXTURE_2D, 0, gl.RGBA32F, size, size, 0, gl.RGBA, gl.FLOAT, boneData);
  gl.uniform1i(gl.getUniformLocation(program, 'boneTexture'), 0);
  gl.uniformMatrix4fv(gl.getUniformLocation(program, 'bindMatrix'), false, new Float32Array(mesh.bindMatrix.elements));

  const output = gl.createBuffer();
  gl.bindBuffer(gl.TRANSFORM_FEEDBACK_BUFFER, output);
  gl.bufferData(gl.TRANSFORM_FEEDBACK_BUFFER, count * 12, gl.STATIC_READ);
  const feedback = gl.createTransformFeedback();
  gl.bindTransformFeedback(gl.TRANSFORM_FEEDBACK, feedback);
  gl.bindBufferBase(gl.TRANSFORM_FEEDBACK_BUFFER, 0, output);
  gl.enable(gl.RASTERIZER_DISCARD);
  gl.beginTransformFeedback(gl.POINTS);
  gl.drawArrays(gl.POINTS, 0, count);
  gl.endTransformFeedback();
  gl.disable(gl.RASTERIZER_DISCARD);
  gl.bindTransformFeedback(gl.TRANSFORM_FEEDBACK, null);
  const result = new Float32Array(count * 3);
  gl.bindBuffer(gl.TRANSFORM_FEEDBACK_BUFFER, output);
  gl.getBufferSubData(gl.TRANSFORM_FEEDBACK_BUFFER, 0, result);
  gl.bindBufferBase(gl.TRANSFORM_FEEDBACK_BUFFER, 0, null);
  const error = gl.getError();
  gl.deleteTransformFeedback(feedback);
  gl.deleteBuffer(output);
  buffers.forEach((buffer) => gl.deleteBuffer(buffer));
  gl.deleteTexture(texture);
  gl.deleteVertexArray(vao);
  if (error !== gl.NO_ERROR) throw new Error(`skinning read-back: WebGL error ${error}`);
  return result;
}
