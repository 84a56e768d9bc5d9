// A loaded file's RIGBAKE_muscle_rig, live on its three.js objects: every frame the skeleton's world
// matrices go into the WebAssembly runtime (the C API of runtime/rigbake_runtime.h, built by
// scripts/build-wasm.sh), which evaluates the muscles and steps the jiggles; the results come back as
// the muscle and jiggle nodes' local matrices. No equation is written here: the runtime is the one
// implementation (docs/runtime.md), this file only moves matrices between three.js and it.

import { Matrix4, Quaternion, Vector3 } from 'three';

const _matrix = new Matrix4();
const _parent = new Matrix4();
const _rootInverse = new Matrix4();
const _position = new Vector3();
const _rotation = new Quaternion();
const _correction = new Quaternion();
const _scale = new Vector3();
const _direction = new Vector3();

// At most this many 1/240 s jiggle steps per frame (one second): a tab left in the background for a
// minute must not simulate that minute when it comes back (rigbake_jiggle_step's max_steps).
export const MAX_JIGGLE_STEPS = 240;

// The glTF node index of every object GLTFLoader made for a node.
export function nodeObjects(gltf) {
  const nodes = [];
  gltf.scene.traverse((object) => {
    const association = gltf.parser.associations.get(object);
    if (association && association.nodes !== undefined) nodes[association.nodes] = object;
  });
  return nodes;
}

export class RigbakeRig {
  // gltf: GLTFLoader's result; runtime: loadRigbakeRuntime()'s; extension: the RIGBAKE_muscle_rig object.
  constructor(gltf, runtime, extension) {
    this.root = gltf.scene;
    this.nodes = nodeObjects(gltf);
    const nodeCount = (gltf.parser.json.nodes || []).length;
    this.rig = runtime.createRig(JSON.stringify(extension), nodeCount);
    // The nodes the runtime reads: only their matrices are copied in each frame.
    this.usedNodes = [];
    for (let n = 0; n < nodeCount; ++n) {
      if (this.rig.nodeUsed(n)) {
        if (!this.nodes[n]) throw new Error(`RIGBAKE_muscle_rig reads node ${n}, which is not in the loaded scene`);
        this.usedNodes.push(n);
      }
    }
    const object = (index) => (index >= 0 ? this.nodes[index] || null : null);
    this.muscles = [];
    for (let m = 0; m < this.rig.muscleCount; ++m) {
      this.muscles.push({
        name: this.rig.muscleName(m),
        node: object(this.rig.muscleNode(m, 0)),
        carrier: object(this.rig.muscleNode(m, 3)),
        helpers: [4, 5, 6].map((which) => object(this.rig.muscleNode(m, which))),
      });
    }
    this.hasHelpers = this.muscles.some((m) => m.helpers.some(Boolean));
    this.jiggles = [];
    for (let j = 0; j < this.rig.jiggleCount; ++j) {
      const node = object(this.rig.jiggleNode(j, 0));
      this.jiggles.push({ name: this.rig.jiggleName(j), node, muscle: this.muscles.find((m) => m.node === node) || null, angle: 0 });
    }
    // Jiggles the current clip carries as channels (a `both` bake: extras.rigbake.jiggle of the
    // animation): shown from the clip, not simulated on top.
    this.playedFromClip = new Set();
    this.jigglesEnabled = true;
    this.record = false; // keep the last evaluation's matrices, drivers and helpers (tests)
    this.active = false;
    this.needsReset = true;
  }

  // The nodes this rig sets: muscle joints, helpers, jiggling joints. While active their matrices are
  // the rig's (matrixAutoUpdate off); deactivate() gives them back to position / quaternion / scale.
  touchedNodes() {
    const nodes = new Set();
    for (const m of this.muscles) {
      if (m.node) nodes.add(m.node);
      for (const helper of m.helpers) if (helper) nodes.add(helper);
    }
    for (const j of this.jiggles) if (j.node) nodes.add(j.node);
    return nodes;
  }

  activate() {
    if (this.active) return;
    for (const node of this.touchedNodes()) node.matrixAutoUpdate = false;
    this.active = true;
    this.needsReset = true;
  }

  deactivate() {
    for (const node of this.touchedNodes()) {
      node.matrixAutoUpdate = true;
      node.updateMatrix();
    }
    this.active = false;
  }

  // The jiggles start again at rest on the next update's pose (after a seek or a clip change).
  resetJiggles() {
    this.needsReset = true;
  }

  // A hit (docs/jiggle.md "Combat Reaction"): `speed` (scene units per second) along `direction`
  // (world space) added to every jiggle point's velocity at its next step.
  hit(direction, speed) {
    if (!this.rig.jiggleCount) return;
    this.root.updateWorldMatrix(true, false);
    _rootInverse.copy(this.root.matrixWorld).invert();
    _direction.copy(direction).transformDirection(_rootInverse);
    this.rig.jiggleImpulse(-1, [_direction.x, _direction.y, _direction.z], speed);
  }

  // One frame, after the mixer has posed the skeleton: the muscles for this pose, then the jiggles
  // advanced by dt seconds (0: no step). Call it every frame the rig is shown.
  update(dt = 0) {
    this.activate();
    // The animated (un-jiggled) local matrices of the jiggling joints that are not muscles.
    for (const j of this.jiggles) if (j.node && !j.muscle) j.node.matrix.compose(j.node.position, j.node.quaternion, j.node.scale);
    this.root.updateMatrixWorld(true);
    // Matrices go to the runtime in the scene root's space (the file's), whatever the app put above it.
    _rootInverse.copy(this.root.matrixWorld).invert();
    const identityRoot = _rootInverse.equals(_matrix.identity());
    const pose = this.rig.nodeMatrices;
    for (const n of this.usedNodes) {
      const world = identityRoot ? this.nodes[n].matrixWorld : _matrix.multiplyMatrices(_rootInverse, this.nodes[n].matrixWorld);
      pose.set(world.elements, 16 * n);
    }
    const evaluation = this.rig.evaluate(null, { helpers: this.hasHelpers || this.record, drivers: this.record });
    const skinned = evaluation.skinned || evaluation;
    if (this.record) {
      this.lastSkinned = Float64Array.from(skinned);
      this.lastDrivers = Float64Array.from(evaluation.drivers);
      this.lastHelpers = Float64Array.from(evaluation.helpers);
    }
    this.muscles.forEach((muscle, m) => {
      if (muscle.node) this.setWorld(muscle.node, skinned, 16 * m, identityRoot);
      if (this.hasHelpers) muscle.helpers.forEach((helper, k) => helper && this.setWorld(helper, evaluation.helpers, 48 * m + 16 * k, identityRoot));
    });
    if (this.jiggles.length) this.updateJiggles(dt);
  }

  // node's local matrix from its world matrix (in the root's space) at values[offset].
  setWorld(node, values, offset, identityRoot) {
    _matrix.fromArray(values, offset);
    _parent.copy(node.parent.matrixWorld);
    if (!identityRoot) _parent.premultiply(_rootInverse);
    node.matrix.copy(_parent.invert().multiply(_matrix));
    node.updateMatrixWorld(true);
  }

  updateJiggles(dt) {
    if (!this.jigglesEnabled) {
      // Switched off: they start again at rest when switched back on, not from a stale state.
      this.needsReset = true;
      return;
    }
    this.rig.storeSkinned();
    if (this.needsReset) {
      this.rig.jiggleReset();
      this.needsReset = false;
      dt = 0;
    }
    const { corrections } = this.rig.jiggleStep(dt, MAX_JIGGLE_STEPS);
    if (this.record) this.lastCorrections = Float64Array.from(corrections);
    this.jiggles.forEach((j, k) => {
      if (!j.node || this.playedFromClip.has(j.name)) return;
      _correction.fromArray(corrections, 4 * k);
      j.angle = 2 * Math.acos(Math.min(1, Math.abs(_correction.w)));
      // local = animated local * correction, on the local T R S (a muscle joint's is K T(0, up, side) S).
      if (j.muscle) {
        j.node.matrix.decompose(_position, _rotation, _scale);
      } else {
        _position.copy(j.node.position);
        _rotation.copy(j.node.quaternion);
        _scale.copy(j.node.scale);
      }
      j.node.matrix.compose(_position, _rotation.multiply(_correction), _scale);
      j.node.updateMatrixWorld(true);
    });
  }

  dispose() {
    this.deactivate();
    this.rig.destroy();
  }
}
