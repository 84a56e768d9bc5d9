// rigbake runtime for JavaScript: the C API of runtime/rigbake_runtime.h compiled to WebAssembly
// (scripts/build-wasm.sh writes rigbake_runtime.wasm beside this module), so a browser or node
// evaluates a bake's RIGBAKE_muscle_rig extension with the very code rigbake bakes with: one
// implementation of the muscle and jiggle equations for every consumer. No dependency, no glue code:
// the wasm is a standalone reactor that imports two functions, given below.
//
//   import { loadRigbakeRuntime } from './rigbake_runtime.mjs';
//   const runtime = await loadRigbakeRuntime();            // or (bytes) in node: fs.readFileSync(...)
//   const rig = runtime.createRig(JSON.stringify(gltf.extensions.RIGBAKE_muscle_rig), gltf.nodes.length);
//   rig.nodeMatrices.set(worldMatrices);                    // node_count * 16 floats, column-major
//   const skinned = rig.evaluate();                         // muscle_count * 16 floats
//   rig.storeSkinned();                                     // jiggles on muscles read them
//   const { corrections } = rig.jiggleStep(1 / 60);         // jiggle_count * 4 floats (x, y, z, w)
//
// Arrays a call returns are views of the WebAssembly memory, valid until the next call on any rig of
// this runtime: copy what must outlive it. Every number is float32, as in the C API.

const RIGBAKE_OK = 0;

function instantiateImports() {
  return {
    // Memory growth detaches the views; they are re-made from memory.buffer on every call.
    env: { emscripten_notify_memory_growth: () => {} },
    wasi_snapshot_preview1: {
      proc_exit: (code) => {
        throw new Error(`rigbake runtime: the WebAssembly module aborted (exit ${code})`);
      },
    },
  };
}

async function compile(source) {
  if (source instanceof WebAssembly.Module) return source;
  if (source instanceof ArrayBuffer || ArrayBuffer.isView(source)) return WebAssembly.compile(source);
  const url = source ?? new URL('./rigbake_runtime.wasm', import.meta.url);
  const response = await fetch(url);
  if (!response.ok) throw new Error(`rigbake runtime: cannot fetch ${url} (${response.status})`);
  return WebAssembly.compile(await response.arrayBuffer());
}

// One rig: a RIGBAKE_muscle_rig extension instantiated for a file of nodeCount nodes, with its
// jiggles' state. Its buffers live in the WebAssembly memory, allocated once.
class Rig {
  constructor(runtime, handle) {
    const e = runtime.exports;
    this._runtime = runtime;
    this._handle = handle;
    this.nodeCount = e.rigbake_rig_node_count(handle);
    this.muscleCount = e.rigbake_rig_muscle_count(handle);
    this.jiggleCount = e.rigbake_rig_jiggle_count(handle);
    const floats = (n) => runtime.alloc(4 * Math.max(n, 1));
    this._nodes = floats(16 * this.nodeCount);
    this._velocityNodes = floats(16 * this.nodeCount);
    this._skinned = floats(16 * this.muscleCount);
    this._helpers = floats(48 * this.muscleCount);
    this._drivers = floats(3 * this.muscleCount);
    this._corrections = floats(4 * this.jiggleCount);
    this._localRotations = floats(4 * this.jiggleCount);
    this._modelMatrices = floats(16 * this.jiggleCount);
    this._points = floats(3 * this.jiggleCount);
    this._direction = floats(3);
  }

  _view(pointer, count) {
    return new Float32Array(this._runtime.exports.memory.buffer, pointer, count);
  }
  _check(code, call) {
    if (code !== RIGBAKE_OK) throw new Error(`rigbake runtime: ${call}: ${this._runtime.lastError()}`);
  }

  // The pose the next evaluate / jiggle call reads: nodeCount * 16 floats, node n's world matrix
  // (column-major) at n * 16. Write into it directly to save a copy.
  get nodeMatrices() {
    return this._view(this._nodes, 16 * this.nodeCount);
  }
  get skinnedMatrices() {
    return this._view(this._skinned, 16 * this.muscleCount);
  }

  muscleName(m) {
    return this._runtime.string(this._runtime.exports.rigbake_rig_muscle_name(this._handle, m));
  }
  // which: 0 skinned, 1 origin, 2 insertion, 3 carrier, 4-6 helpers base, tip, driver (-1: none).
  muscleNode(m, which) {
    return this._runtime.exports.rigbake_rig_muscle_node(this._handle, m, which);
  }
  jiggleName(j) {
    return this._runtime.string(this._runtime.exports.rigbake_rig_jiggle_name(this._handle, j));
  }
  // which: 0 the jiggling node, 1 its parent, 2 its root (-1: model space).
  jiggleNode(j, which) {
    return this._runtime.exports.rigbake_rig_jiggle_node(this._handle, j, which);
  }
  // rigbake_rig_node_used: true when some muscle or jiggle reads node n's matrix (a host need only
  // write those into nodeMatrices).
  nodeUsed(n) {
    return this._runtime.exports.rigbake_rig_node_used(this._handle, n) === 1;
  }

  // rigbake_rig_evaluate: the muscles' skinned world matrices for the pose in nodeMatrices (or in
  // `nodeMatrices`, copied there first). With { helpers: true } or { drivers: true } also those.
  evaluate(nodeMatrices, options = {}) {
    if (nodeMatrices) this.nodeMatrices.set(nodeMatrices);
    const code = this._runtime.exports.rigbake_rig_evaluate(this._handle, this._nodes, this._skinned,
      options.helpers ? this._helpers : 0, options.drivers ? this._drivers : 0);
    this._check(code, 'evaluate');
    const skinned = this.skinnedMatrices;
    if (!options.helpers && !options.drivers) return skinned;
    return {
      skinned,
      helpers: options.helpers ? this._view(this._helpers, 48 * this.muscleCount) : null,
      drivers: options.drivers ? this._view(this._drivers, 3 * this.muscleCount) : null,
    };
  }

  // rigbake_rig_store_skinned: the last evaluate's matrices into nodeMatrices at the skinned nodes.
  storeSkinned() {
    this._check(this._runtime.exports.rigbake_rig_store_skinned(this._handle, this._skinned, this._nodes), 'storeSkinned');
  }

  // rigbake_jiggle_reset on the pose in nodeMatrices; velocityMatrices (optional) at velocityTime s.
  jiggleReset(velocityMatrices = null, velocityTime = 0) {
    if (velocityMatrices) this._view(this._velocityNodes, 16 * this.nodeCount).set(velocityMatrices);
    const code = this._runtime.exports.rigbake_jiggle_reset(this._handle, this._nodes, velocityMatrices ? this._velocityNodes : 0,
      velocityTime);
    this._check(code, 'jiggleReset');
  }

  // rigbake_jiggle_step on the pose in nodeMatrices: every output, per jiggle.
  jiggleStep(deltaTime, maxSteps = 0) {
    const code = this._runtime.exports.rigbake_jiggle_step(this._handle, this._nodes, deltaTime, maxSteps, this._corrections,
      this._localRotations, this._modelMatrices, this._points);
    this._check(code, 'jiggleStep');
    return {
      corrections: this._view(this._corrections, 4 * this.jiggleCount),
      localRotations: this._view(this._localRotations, 4 * this.jiggleCount),
      modelMatrices: this._view(this._modelMatrices, 16 * this.jiggleCount),
      points: this._view(this._points, 3 * this.jiggleCount),
    };
  }

  // rigbake_jiggle_impulse: jiggle -1 hits every jiggle.
  jiggleImpulse(jiggle, direction, magnitude) {
    this._view(this._direction, 3).set(direction);
    this._check(this._runtime.exports.rigbake_jiggle_impulse(this._handle, jiggle, this._direction, magnitude), 'jiggleImpulse');
  }

  destroy() {
    const e = this._runtime.exports;
    e.rigbake_rig_destroy(this._handle);
    for (const p of [this._nodes, this._velocityNodes, this._skinned, this._helpers, this._drivers, this._corrections,
      this._localRotations, this._modelMatrices, this._points, this._direction]) e.free(p);
    this._handle = 0;
  }
}

class Runtime {
  constructor(instance) {
    this.exports = instance.exports;
    this.version = this.exports.rigbake_runtime_version();
  }
  alloc(bytes) {
    const p = this.exports.malloc(bytes);
    if (!p) throw new Error('rigbake runtime: out of WebAssembly memory');
    return p;
  }
  string(pointer) {
    if (!pointer) return null;
    const bytes = new Uint8Array(this.exports.memory.buffer, pointer);
    return new TextDecoder().decode(bytes.subarray(0, bytes.indexOf(0)));
  }
  lastError() {
    return this.string(this.exports.rigbake_last_error());
  }
  // rigbake_rig_create: jsonText is the extension object's JSON text; throws with the C API's message.
  createRig(jsonText, nodeCount) {
    const bytes = new TextEncoder().encode(jsonText);
    const text = this.alloc(bytes.length);
    new Uint8Array(this.exports.memory.buffer, text, bytes.length).set(bytes);
    const handle = this.exports.rigbake_rig_create(text, bytes.length, nodeCount);
    this.exports.free(text);
    if (!handle) throw new Error(`rigbake runtime: ${this.lastError()}`);
    return new Rig(this, handle);
  }
}

// Loads the WebAssembly runtime from `source`: the .wasm bytes (ArrayBuffer or typed array), a
// compiled WebAssembly.Module, or a URL to fetch (default: rigbake_runtime.wasm beside this module).
export async function loadRigbakeRuntime(source) {
  const module = await compile(source);
  const instance = await WebAssembly.instantiate(module, instantiateImports());
  instance.exports._initialize();
  return new Runtime(instance);
}
