// The rigbake player: loads a baked glTF with three.js, evaluates its RIGBAKE_muscle_rig muscles and
// jiggles every frame with the runtime's equations (muscle_rig.js, jiggle.js) and skins 4, 7 or 10
// influences (skinning.js). docs/view.md describes what it shows; `rigbake view` writes a page that
// runs it from file:// (page.js).

import * as THREE from 'three';
import { GLTFLoader } from 'three/examples/jsm/loaders/GLTFLoader.js';
import { OrbitControls } from 'three/examples/jsm/controls/OrbitControls.js';
import { evaluateMuscle, readMuscleRig, rotationOf } from './muscle_rig.js';
import { LiveJiggle } from './jiggle.js';
import { makeBoneTexture, patchSkinningMaterial, preparePackedAttributes } from './skinning.js';

export const MUSCLE_MODES = ['runtime', 'sampled', 'off'];
export const INFLUENCE_COUNTS = [4, 7, 10];

const _matrix = new THREE.Matrix4();
const _position = new THREE.Vector3();
const _quaternion = new THREE.Quaternion();
const _rotation = new THREE.Quaternion();
const _scale = new THREE.Vector3();

// The glTF node index of every object GLTFLoader made for a node.
function nodeObjects(gltf) {
  const nodes = [];
  gltf.scene.traverse((object) => {
    const association = gltf.parser.associations.get(object);
    if (association && association.nodes !== undefined) nodes[association.nodes] = object;
  });
  return nodes;
}

// Where a skinned mesh came from: {node, mesh, primitive} of the glTF.
function meshSource(gltf, mesh) {
  const own = gltf.parser.associations.get(mesh) || {};
  const parent = mesh.parent ? gltf.parser.associations.get(mesh.parent) || {} : {};
  return { node: own.nodes !== undefined ? own.nodes : parent.nodes, mesh: own.meshes, primitive: own.primitives || 0 };
}

export class RigbakePlayer {
  // container: the element the canvas goes in. options: {width, height} for a fixed size (tests),
  // preserveDrawingBuffer (tests read pixels back).
  constructor(container, options = {}) {
    this.container = container;
    this.options = options;
    this.renderer = new THREE.WebGLRenderer({ antialias: !options.width, preserveDrawingBuffer: !!options.preserveDrawingBuffer });
    this.renderer.setPixelRatio(options.width ? 1 : Math.min(window.devicePixelRatio || 1, 2));
    this.renderer.outputColorSpace = THREE.SRGBColorSpace;
    container.appendChild(this.renderer.domElement);
    this.scene = new THREE.Scene();
    this.scene.background = new THREE.Color(0x2b2f36);
    this.camera = new THREE.PerspectiveCamera(35, 1, 0.01, 1000);
    this.scene.add(new THREE.HemisphereLight(0xffffff, 0x444455, 2.2));
    const sun = new THREE.DirectionalLight(0xffffff, 2.0);
    sun.position.set(2, 4, 3);
    this.scene.add(sun);
    this.controls = new OrbitControls(this.camera, this.renderer.domElement);
    this.muscleMode = 'runtime';
    this.influences = 4;
    this.heatmap = false;
    this.heatScale = 0.01; // metres at full red
    this.jigglesEnabled = true;
    this.playing = true;
    this.clipIndex = 0;
    this.time = 0;
    this.listeners = new Set();
    this.resize();
  }

  // ---- loading ----

  async load(arrayBuffer) {
    const gltf = await new GLTFLoader().parseAsync(arrayBuffer, '');
    this.gltf = gltf;
    this.json = gltf.parser.json;
    this.root = gltf.scene;
    this.scene.add(this.root);
    this.nodes = nodeObjects(gltf);
    const { rig, problems } = readMuscleRig(this.json);
    if (problems.length) throw new Error(`RIGBAKE_muscle_rig is malformed: ${problems.slice(0, 5).join('; ')}`);
    this.rig = rig;
    this.findMuscleNodes();
    this.prepareMeshes();
    this.prepareClips();
    this.prepareJiggles();
    this.influences = this.fileInfluences;
    this.muscleMode = this.rig ? 'runtime' : this.hasSampledMuscles ? 'sampled' : 'off';
    this.applyMaterialState();
    this.selectClip(0);
    this.frame();
    this.emit();
  }

  // The muscle joints: from the extension, or (a `sampled` bake) from the nodes' extras
  // {"rigbake": {"role": "skinned"}}, which the bake writes on every muscle joint.
  findMuscleNodes() {
    this.muscles = [];
    if (this.rig) {
      for (const muscle of this.rig.muscles) {
        this.muscles.push({
          muscle,
          name: muscle.name,
          node: this.nodes[muscle.skinnedNode],
          carrier: this.nodes[muscle.carrierNode],
          helpers: muscle.helperNodes.map((index) => this.nodes[index]),
          rest: muscle.skinnedInCarrier,
        });
      }
    } else {
      (this.json.nodes || []).forEach((node, index) => {
        const info = node.extras && node.extras.rigbake;
        if (!info || info.role !== 'skinned' || !this.nodes[index]) return;
        const object = this.nodes[index];
        this.muscles.push({ muscle: null, name: info.muscle, node: object, carrier: object.parent, helpers: [], rest: null });
      });
    }
    const skinnedNodes = new Set();
    (this.rig ? this.rig.muscles : []).forEach((m) => skinnedNodes.add(m.skinnedNode));
    (this.json.nodes || []).forEach((node, index) => {
      if (node.extras && node.extras.rigbake && node.extras.rigbake.role === 'skinned') skinnedNodes.add(index);
    });
    this.hasSampledMuscles = (this.json.animations || []).some((animation) =>
      animation.channels.some((channel) => channel.target && skinnedNodes.has(channel.target.node)),
    );
  }

  prepareMeshes() {
    this.skinnedMeshes = [];
    this.fileInfluences = 4;
    this.hasPacked = false;
    this.root.traverse((object) => {
      if (!object.isSkinnedMesh) return;
      object.frustumCulled = false;
      const layout = preparePackedAttributes(object.geometry);
      const state = {
        mesh: object,
        source: meshSource(this.gltf, object),
        layout,
        fileInfluences: layout ? layout.influences : 0,
        influences: 4,
        heatmap: false,
        plainTexture: makeBoneTexture(object.skeleton),
        uniforms: { rbPlainBones: { value: null }, rbHeatScale: { value: this.heatScale } },
      };
      state.uniforms.rbPlainBones.value = state.plainTexture;
      object.material = Array.isArray(object.material) ? object.material.map((m) => m.clone()) : object.material.clone();
      if (layout) {
        this.hasPacked = true;
        this.fileInfluences = Math.max(this.fileInfluences, layout.influences);
      }
      this.skinnedMeshes.push(state);
    });
    this.vertexCount = this.skinnedMeshes.reduce((n, s) => n + s.mesh.geometry.getAttribute('position').count, 0);
    // Plain skinning (muscles off) needs each muscle joint's rest matrix relative to its carrier: the
    // extension's skinnedInCarrier, or, for a file without it, the bind matrices: K = B_carrier^-1 B_skinned.
    for (const entry of this.muscles) {
      if (entry.rest || !entry.carrier) continue;
      const bindOf = (object) => {
        for (const { mesh } of this.skinnedMeshes) {
          const k = mesh.skeleton.bones.indexOf(object);
          if (k >= 0) return mesh.skeleton.boneInverses[k].clone().invert();
        }
        return null;
      };
      const carrierBind = bindOf(entry.carrier);
      const skinnedBind = bindOf(entry.node);
      entry.rest = carrierBind && skinnedBind ? carrierBind.invert().multiply(skinnedBind).elements.slice() : entry.node.matrix.elements.slice();
    }
  }

  prepareClips() {
    this.mixer = new THREE.AnimationMixer(this.root);
    this.clips = this.gltf.animations.map((clip, index) => {
      const extras = (this.json.animations[index] || {}).extras || {};
      const baked = ((extras.rigbake || {}).jiggle || []).filter((j) => j.host === 'joint').map((j) => j.joint);
      return { clip, index, name: clip.name || `animation ${index}`, duration: clip.duration, action: this.mixer.clipAction(clip), bakedJiggles: new Set(baked) };
    });
  }

  prepareJiggles() {
    this.jiggles = (this.rig ? this.rig.jiggles : []).map((setup) => {
      const node = this.nodes[setup.node];
      const muscle = this.muscles.find((m) => m.node === node) || null;
      return { setup, live: new LiveJiggle(setup), node, root: this.nodes[setup.rootNode], muscle, animated: null };
    });
  }

  // ---- state ----

  onChange(listener) {
    this.listeners.add(listener);
  }
  emit() {
    for (const listener of this.listeners) listener(this);
  }

  availableMuscleModes() {
    // runtime needs the extension, sampled the file's channels; off (the input's own skinning) always works.
    return MUSCLE_MODES.filter((mode) => (mode === 'runtime' ? !!this.rig : mode === 'sampled' ? this.hasSampledMuscles : true));
  }
  availableInfluences() {
    return INFLUENCE_COUNTS.filter((n) => n === 4 || (this.hasPacked && n <= this.fileInfluences));
  }

  setMuscleMode(mode) {
    if (!this.availableMuscleModes().includes(mode)) throw new Error(`muscles ${mode} is not available for this file`);
    this.muscleMode = mode;
    for (const entry of this.muscles) {
      entry.node.matrixAutoUpdate = mode === 'sampled';
      for (const helper of entry.helpers) if (helper) helper.matrixAutoUpdate = mode === 'sampled';
    }
    this.resetJiggles();
    this.frame();
    this.emit();
  }

  setInfluences(count) {
    if (!this.availableInfluences().includes(count)) throw new Error(`${count} influences are not available for this file`);
    this.influences = count;
    this.applyMaterialState();
    this.emit();
  }

  setHeatmap(on, scale = this.heatScale) {
    this.heatmap = !!on;
    this.heatScale = scale;
    this.applyMaterialState();
    this.frame();
    this.emit();
  }

  applyMaterialState() {
    for (const state of this.skinnedMeshes) {
      const influences = state.fileInfluences ? Math.min(this.influences, state.fileInfluences) : 4;
      state.uniforms.rbHeatScale.value = this.heatScale;
      if (state.influences === influences && state.heatmap === this.heatmap && state.patched) continue;
      state.influences = influences;
      state.heatmap = this.heatmap;
      state.patched = true;
      for (const material of Array.isArray(state.mesh.material) ? state.mesh.material : [state.mesh.material]) {
        patchSkinningMaterial(material, state);
      }
    }
  }

  selectClip(index) {
    if (!this.clips.length) return;
    this.clipIndex = index;
    this.mixer.stopAllAction();
    const clip = this.clips[index];
    clip.action.reset().setLoop(THREE.LoopRepeat, Infinity).play();
    this.time = 0;
    this.mixer.setTime(0);
    this.resetJiggles();
    this.frame(0);
    this.emit();
  }

  resetJiggles() {
    for (const jiggle of this.jiggles) jiggle.live.reset();
  }

  // A hit (docs/jiggle.md "Combat Reaction"): every jiggle point gets `speed` m/s along `direction`
  // (world; default: away from the camera, as if struck from where the viewer stands).
  hit(direction = null, speed = 1.5) {
    const d = direction ? new THREE.Vector3(...direction) : new THREE.Vector3().subVectors(this.controls.target, this.camera.position);
    d.normalize().multiplyScalar(speed);
    for (const jiggle of this.jiggles) jiggle.live.hit([d.x, d.y, d.z]);
  }

  // ---- the frame ----

  // Advances the clip by dt seconds and evaluates everything for the new time.
  advance(dt) {
    if (!this.clips.length) return this.frame(dt);
    // Jiggled joints are given back their animated transforms before the mixer runs, so that a joint
    // the clip does not animate does not accumulate the jiggle frame after frame.
    this.restoreAnimated();
    this.mixer.update(dt);
    this.time = this.clips[this.clipIndex].action.time;
    this.frame(dt);
  }

  // Puts the clip at `time` seconds, as the test does; jiggles start again from rest.
  seek(time) {
    this.restoreAnimated();
    this.mixer.setTime(time);
    this.time = time;
    this.resetJiggles();
    this.frame(0);
  }

  restoreAnimated() {
    for (const jiggle of this.jiggles) {
      if (!jiggle.animated || jiggle.muscle) continue;
      jiggle.node.position.copy(jiggle.animated.position);
      jiggle.node.quaternion.copy(jiggle.animated.quaternion);
      jiggle.node.scale.copy(jiggle.animated.scale);
    }
  }

  // Everything after the skeleton is posed: muscles, jiggles, plain-skinning matrices.
  frame(dt = 0) {
    for (const jiggle of this.jiggles) {
      if (jiggle.muscle) continue;
      jiggle.animated = { position: jiggle.node.position.clone(), quaternion: jiggle.node.quaternion.clone(), scale: jiggle.node.scale.clone() };
    }
    this.root.updateMatrixWorld(true);
    if (this.muscleMode !== 'sampled') this.applyMuscles();
    if (this.muscleMode === 'runtime' && this.jigglesEnabled && this.jiggles.length) this.applyJiggles(dt);
    this.root.updateMatrixWorld(true);
    if (this.heatmap) this.updatePlainBones();
  }

  // The skeleton's model-space matrices as the runtime reads them: node index -> 16 numbers.
  jointMatrix(index) {
    return this.nodes[index].matrixWorld.elements;
  }

  // Evaluates every muscle (runtime) or puts it at rest (off), and sets its node's local matrix.
  applyMuscles() {
    const joints = new Proxy([], { get: (_, key) => this.jointMatrix(Number(key)) });
    this.lastEvaluation = [];
    for (const entry of this.muscles) {
      let local = entry.rest;
      if (this.muscleMode === 'runtime' && entry.muscle) {
        const result = evaluateMuscle(entry.muscle, joints, entry.helpers.length > 0);
        this.lastEvaluation.push(result);
        local = result.local;
        if (result.helpers) this.setWorld(entry.helpers, result.helpers);
      }
      if (!local) continue;
      if (entry.node.parent === entry.carrier) {
        entry.node.matrix.fromArray(local);
      } else {
        // Not a child of its carrier (a file edited by hand): local = parent^-1 * carrier * K T S.
        _matrix.fromArray(local).premultiply(entry.carrier.matrixWorld);
        entry.node.matrix.copy(entry.node.parent.matrixWorld).invert().multiply(_matrix);
      }
      // Only the matrix: position, quaternion and scale stay the mixer's (three's PropertyMixer writes
      // a value only when it changed, so overwriting them here would leave sampled mode showing these).
      entry.node.updateMatrixWorld(true);
    }
  }

  setWorld(objects, frames) {
    objects.forEach((object, k) => {
      if (!object) return;
      _matrix.fromArray(frames.slice(16 * k, 16 * k + 16));
      object.matrix.copy(object.parent.matrixWorld).invert().multiply(_matrix);
      object.updateMatrixWorld(true);
    });
  }

  applyJiggles(dt) {
    const baked = this.clips.length ? this.clips[this.clipIndex].bakedJiggles : new Set();
    for (const jiggle of this.jiggles) {
      if (!jiggle.node || !jiggle.root || baked.has(jiggle.setup.name)) continue;
      const world = jiggle.node.matrixWorld.elements;
      const pivotRotation = rotationOf(world);
      const frame = { translation: [world[12], world[13], world[14]], rotation: pivotRotation };
      const offset = jiggle.live.advance(frame, dt);
      const rootRotation = rotationOf(jiggle.root.matrixWorld.elements);
      const d = jiggle.live.rotationFor(offset, pivotRotation, rootRotation);
      jiggle.lastOffset = offset;
      _quaternion.set(d[0], d[1], d[2], d[3]);
      if (jiggle.muscle) {
        // R_baked = R_animated * D on the muscle joint's local T R S.
        jiggle.node.matrix.decompose(_position, _rotation, _scale);
        _rotation.multiply(_quaternion);
        jiggle.node.matrix.compose(_position, _rotation, _scale);
      } else {
        jiggle.node.quaternion.multiply(_quaternion);
        jiggle.node.updateMatrix();
      }
      jiggle.node.updateMatrixWorld(true);
    }
  }

  // The bone matrices of plain skinning (every muscle joint at rest on its carrier), for the heatmap.
  updatePlainBones() {
    const restWorld = new Map();
    for (const entry of this.muscles) {
      if (entry.rest && entry.carrier) restWorld.set(entry.node, new THREE.Matrix4().fromArray(entry.rest).premultiply(entry.carrier.matrixWorld));
    }
    for (const state of this.skinnedMeshes) {
      const { bones, boneInverses } = state.mesh.skeleton;
      const data = state.plainTexture.image.data;
      bones.forEach((bone, k) => {
        _matrix.multiplyMatrices(restWorld.get(bone) || bone.matrixWorld, boneInverses[k]);
        _matrix.toArray(data, 16 * k);
      });
      state.plainTexture.needsUpdate = true;
    }
  }

  // ---- view ----

  frameCamera() {
    const box = new THREE.Box3().setFromObject(this.root, true);
    if (box.isEmpty()) box.set(new THREE.Vector3(-1, 0, -1), new THREE.Vector3(1, 2, 1));
    const center = box.getCenter(new THREE.Vector3());
    const size = box.getSize(new THREE.Vector3());
    const radius = Math.max(size.x, size.y, size.z) * 0.5;
    const distance = radius / Math.tan((this.camera.fov * Math.PI) / 360) * 1.3;
    this.camera.near = distance / 100;
    this.camera.far = distance * 100;
    this.camera.position.set(center.x + distance * 0.35, center.y + radius * 0.2, center.z + distance);
    this.camera.updateProjectionMatrix();
    this.controls.target.copy(center);
    this.controls.update();
  }

  resize() {
    const width = this.options.width || this.container.clientWidth || 640;
    const height = this.options.height || this.container.clientHeight || 480;
    this.renderer.setSize(width, height, !this.options.width);
    this.camera.aspect = width / height;
    this.camera.updateProjectionMatrix();
  }

  render() {
    this.renderer.render(this.scene, this.camera);
  }

  // The render loop: advances while playing, renders always.
  start() {
    let last = performance.now();
    const loop = (now) => {
      const dt = Math.min(0.1, Math.max(0, (now - last) / 1000));
      last = now;
      if (this.playing && this.gltf) this.advance(dt);
      this.controls.update();
      this.render();
      if (this.onFrame) this.onFrame(this);
      this.raf = requestAnimationFrame(loop);
    };
    this.raf = requestAnimationFrame(loop);
  }

  stop() {
    if (this.raf) cancelAnimationFrame(this.raf);
    this.raf = 0;
  }
}
