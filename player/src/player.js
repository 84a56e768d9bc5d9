// The rigbake player: loads a baked glTF with three.js and the rigbake-three plugin (player/plugin/),
// which evaluates its RIGBAKE_muscle_rig muscles and jiggles every frame with the WebAssembly runtime
// and skins 7 or 10 packed influences; the player adds the modes a rigger compares (muscles sampled or
// at rest, 4 influences, the heatmap). docs/view.md describes what it shows; `rigbake view` writes a page
// that runs it from file:// (page.js).

import * as THREE from 'three';
import { GLTFLoader } from 'three/examples/jsm/loaders/GLTFLoader.js';
import { DRACOLoader } from 'three/examples/jsm/loaders/DRACOLoader.js';
import { MeshoptDecoder } from 'three/examples/jsm/libs/meshopt_decoder.module.js';
import { OrbitControls } from 'three/examples/jsm/controls/OrbitControls.js';
import { RigbakeMuscleRigPlugin, applySkinningState, nodeObjects } from '../plugin/src/index.js';

export const MUSCLE_MODES = ['runtime', 'sampled', 'off'];
export const INFLUENCE_COUNTS = [4, 7, 10];

const _matrix = new THREE.Matrix4();

// Draco's decoder, given as its two files' contents (window.RIGBAKE_DRACO, rigbake-draco.js, which
// `rigbake view` writes beside a Draco file's page): a file:// page cannot fetch them, so the loader is
// handed them instead of loading them from a path.
class EmbeddedDracoLoader extends DRACOLoader {
  constructor(files) {
    super();
    this.files = files;
  }
  _loadLibrary(url) {
    if (url.endsWith('draco_wasm_wrapper.js')) return Promise.resolve(this.files.wrapper);
    if (url.endsWith('draco_decoder.wasm')) return Promise.resolve(this.files.wasm.slice(0));
    return Promise.reject(new Error(`the Draco decoder file ${url} is not embedded`));
  }
}

// Where a skinned mesh came from: {node, mesh, primitive} of the glTF.
function meshSource(gltf, mesh) {
  const own = gltf.parser.associations.get(mesh) || {};
  const parent = mesh.parent ? gltf.parser.associations.get(mesh.parent) || {} : {};
  return { node: own.nodes !== undefined ? own.nodes : parent.nodes, mesh: own.meshes, primitive: own.primitives || 0 };
}

export class RigbakePlayer {
  // container: the element the canvas goes in. options: runtime (loadRigbakeRuntime()'s, required),
  // draco ({wrapper, wasm}: Draco's decoder files, for Draco-compressed files), {width, height} for a
  // fixed size (tests), preserveDrawingBuffer (tests read pixels back).
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
    const loader = new GLTFLoader().register((parser) => new RigbakeMuscleRigPlugin(parser, this.options.runtime));
    loader.setMeshoptDecoder(MeshoptDecoder);
    if (this.options.draco) loader.setDRACOLoader(new EmbeddedDracoLoader(this.options.draco));
    const gltf = await loader.parseAsync(arrayBuffer, '');
    this.gltf = gltf;
    this.json = gltf.parser.json;
    this.root = gltf.scene;
    this.scene.add(this.root);
    this.nodes = nodeObjects(gltf);
    this.rig = gltf.userData.rigbake; // the plugin's RigbakeRig, null without the extension
    this.findMuscleNodes();
    this.prepareMeshes();
    this.prepareClips();
    this.prepareJiggles();
    this.influences = this.fileInfluences;
    this.muscleMode = this.rig ? 'runtime' : this.hasSampledMuscles ? 'sampled' : 'off';
    for (const entry of this.muscles) entry.node.matrixAutoUpdate = this.muscleMode === 'sampled';
    this.applyMaterialState();
    this.selectClip(this.armClipIndex());
    this.frame();
    this.emit();
  }

  // The clip a rigger sees first: the one whose upper arms rotate the most (the largest angle between
  // any key of an upper arm's rotation track and its first key), because the muscles a bake adds are
  // mostly the arm's; the first clip when no clip turns an upper arm (or none is found by name or VRM).
  armClipIndex() {
    const arms = this.upperArmNodes();
    const q0 = new THREE.Quaternion();
    const q = new THREE.Quaternion();
    this.armAngles = this.clips.map((clip) => {
      let angle = 0;
      for (const track of clip.clip.tracks) {
        if (!(track instanceof THREE.QuaternionKeyframeTrack) || !arms.has(track.name.slice(0, track.name.lastIndexOf('.')))) continue;
        q0.fromArray(track.values, 0);
        for (let k = 4; k < track.values.length; k += 4) angle = Math.max(angle, q0.angleTo(q.fromArray(track.values, k)));
      }
      return angle;
    });
    let best = 0;
    // Strictly larger, so that ties keep the earlier clip; below 1e-3 rad an arm does not visibly move.
    this.armAngles.forEach((angle, index) => {
      if (angle > 1e-3 && angle > this.armAngles[best]) best = index;
    });
    return best;
  }

  // The upper arms' three.js object names (what a track's name starts with): VRM's humanoid bones when
  // the file has them, else the skeleton's joints whose names say upper arm (UpperArm, upper_arm,
  // upperarm, Arm.L / arm_l style, not forearm, lower arm or their twist bones).
  upperArmNodes() {
    const names = new Set();
    const ext = this.json.extensions || {};
    const add = (index) => index !== undefined && this.nodes[index] && names.add(this.nodes[index].name);
    if (ext.VRMC_vrm && ext.VRMC_vrm.humanoid) {
      const bones = ext.VRMC_vrm.humanoid.humanBones || {};
      for (const key of ['leftUpperArm', 'rightUpperArm']) if (bones[key]) add(bones[key].node);
    } else if (ext.VRM && ext.VRM.humanoid) {
      for (const bone of ext.VRM.humanoid.humanBones || []) if (bone.bone === 'leftUpperArm' || bone.bone === 'rightUpperArm') add(bone.node);
    }
    if (names.size) return names;
    const bones = new Set();
    for (const state of this.skinnedMeshes) for (const bone of state.mesh.skeleton.bones) bones.add(bone);
    for (const bone of bones) {
      const name = bone.name.toLowerCase();
      if (/twist|roll|fore|lower|hand|helper|muscle/.test(name)) continue;
      if (/upper[_. ]?arm|arm[_. ]?upper|(^|[^a-z])arm([_. ]?[lr])?([^a-z]|$)|(left|right)arm([^a-z]|$)/.test(name)) names.add(bone.name);
    }
    return names;
  }

  // The muscle joints: from the extension, or (a `sampled` bake) from the nodes' extras
  // {"rigbake": {"role": "skinned"}}, which the bake writes on every muscle joint.
  findMuscleNodes() {
    this.muscles = [];
    if (this.rig) {
      // Muscles off puts each joint at rest on its carrier: the extension's skinnedInCarrier (K).
      const stored = this.json.extensions.RIGBAKE_muscle_rig.muscles;
      this.rig.muscles.forEach((muscle, m) => {
        this.muscles.push({ name: muscle.name, node: muscle.node, carrier: muscle.carrier, helpers: muscle.helpers.filter(Boolean), rest: stored[m].skinnedInCarrier.slice() });
      });
    } else {
      (this.json.nodes || []).forEach((node, index) => {
        const info = node.extras && node.extras.rigbake;
        if (!info || info.role !== 'skinned' || !this.nodes[index]) return;
        const object = this.nodes[index];
        this.muscles.push({ name: info.muscle, node: object, carrier: object.parent, helpers: [], rest: null });
      });
    }
    const skinnedNodes = new Set();
    (this.rig ? this.rig.muscles : []).forEach((m) => m.node && skinnedNodes.add(this.nodes.indexOf(m.node)));
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
      // The plugin prepared the packed skinning (and the plain-skinning texture the heatmap reads).
      const state = object.userData.rigbakeSkinning;
      state.mesh = object;
      state.source = meshSource(this.gltf, object);
      const layout = state.layout;
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
    this.jiggles = this.rig ? this.rig.jiggles : [];
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
    if (this.rig && mode !== 'runtime') this.rig.deactivate();
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
      state.influences = influences;
      state.heatmap = this.heatmap;
      applySkinningState(state.mesh);
    }
  }

  selectClip(index) {
    if (!this.clips.length) return;
    this.clipIndex = index;
    this.mixer.stopAllAction();
    const clip = this.clips[index];
    clip.action.reset().setLoop(THREE.LoopRepeat, Infinity).play();
    if (this.rig) this.rig.playedFromClip = clip.bakedJiggles;
    this.time = 0;
    this.mixer.setTime(0);
    this.resetJiggles();
    this.frame(0);
    this.emit();
  }

  resetJiggles() {
    if (this.rig) this.rig.resetJiggles();
  }

  // A hit (docs/jiggle.md "Combat Reaction"): every jiggle point gets `speed` m/s along `direction`
  // (world; default: away from the camera, as if struck from where the viewer stands).
  hit(direction = null, speed = 1.5) {
    const d = direction ? new THREE.Vector3(...direction) : new THREE.Vector3().subVectors(this.controls.target, this.camera.position);
    if (this.rig) this.rig.hit(d.normalize(), speed);
  }

  // ---- the frame ----

  // Advances the clip by dt seconds and evaluates everything for the new time.
  advance(dt) {
    if (!this.clips.length) return this.frame(dt);
    this.mixer.update(dt);
    this.time = this.clips[this.clipIndex].action.time;
    this.frame(dt);
  }

  // One frame of the current clip: its keys' spacing when they are evenly spaced (the rate the clip was
  // sampled at), else 1/30 s.
  frameStep() {
    const clip = this.clips[this.clipIndex];
    if (!clip) return 1 / 30;
    let times = null;
    for (const track of clip.clip.tracks) if (!times || track.times.length > times.length) times = track.times;
    if (!times || times.length < 3) return 1 / 30;
    const step = (times[times.length - 1] - times[0]) / (times.length - 1);
    for (let k = 1; k < times.length; ++k) if (Math.abs(times[k] - times[k - 1] - step) > 1e-3 * step) return 1 / 30;
    return step > 1e-4 ? step : 1 / 30;
  }

  // Pauses and moves `frames` frames (negative: back), wrapping at the clip's ends as it loops.
  step(frames) {
    this.playing = false;
    const clip = this.clips[this.clipIndex];
    if (!clip || !(clip.duration > 0)) return;
    const dt = this.frameStep();
    // Frame numbers, not times, are stepped: repeated steps do not accumulate rounding.
    const count = Math.max(1, Math.round(clip.duration / dt));
    const frame = (((Math.round(this.time / dt) + frames) % (count + 1)) + count + 1) % (count + 1);
    this.seek(Math.min(clip.duration, frame * dt));
    this.emit();
  }

  // Puts the clip at `time` seconds, as the test does; jiggles start again from rest.
  seek(time) {
    this.mixer.setTime(time);
    this.time = time;
    this.resetJiggles();
    this.frame(0);
  }

  // Everything after the skeleton is posed: muscles and jiggles (the plugin's rig), plain-skinning matrices.
  frame(dt = 0) {
    if (this.muscleMode === 'runtime' && this.rig) {
      this.rig.jigglesEnabled = this.jigglesEnabled;
      this.rig.update(dt);
    } else {
      this.root.updateMatrixWorld(true);
      if (this.muscleMode === 'off') this.restMuscles();
    }
    if (this.heatmap) this.updatePlainBones();
  }

  // Muscles off: every muscle joint at rest on its carrier (K), the input's own skinning.
  restMuscles() {
    for (const entry of this.muscles) {
      if (!entry.rest || !entry.carrier) continue;
      if (entry.node.parent === entry.carrier) {
        entry.node.matrix.fromArray(entry.rest);
      } else {
        // Not a child of its carrier (a file edited by hand): local = parent^-1 * carrier * K.
        _matrix.fromArray(entry.rest).premultiply(entry.carrier.matrixWorld);
        entry.node.matrix.copy(entry.node.parent.matrixWorld).invert().multiply(_matrix);
      }
      // Only the matrix: position, quaternion and scale stay the mixer's (three's PropertyMixer writes
      // a value only when it changed, so overwriting them here would leave sampled mode showing these).
      entry.node.updateMatrixWorld(true);
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

  // The whole character in view, and the floor grid under it.
  frameCamera() {
    const box = new THREE.Box3().setFromObject(this.root, true);
    if (box.isEmpty()) box.set(new THREE.Vector3(-1, 0, -1), new THREE.Vector3(1, 2, 1));
    const center = box.getCenter(new THREE.Vector3());
    const size = box.getSize(new THREE.Vector3());
    // The character's height from its skin at bind (T- or A-pose, standing: the geometry as stored, placed
    // by the mesh's world matrix, where three draws it when every bone matrix is the identity), not from
    // the pose the page opened on, which may crouch or roll; the pose's box when there is no skin.
    const bind = new THREE.Box3();
    for (const state of this.skinnedMeshes) {
      const geometry = state.mesh.geometry;
      if (!geometry.boundingBox) geometry.computeBoundingBox();
      bind.union(geometry.boundingBox.clone().applyMatrix4(state.mesh.matrixWorld));
    }
    const height = bind.isEmpty() ? size.y : bind.max.y - bind.min.y;
    this.characterHeight = height > 0 ? height : Math.max(size.x, size.z, 1);
    this.selectedJoint = null;
    if (!this.grid) this.addFloorGrid(box); // once, at the pose the page opened with
    const radius = Math.max(size.x, size.y, size.z) * 0.5;
    const distance = radius / Math.tan((this.camera.fov * Math.PI) / 360) * 1.3;
    this.camera.near = distance / 100;
    this.camera.far = distance * 100;
    this.camera.position.set(center.x + distance * 0.35, center.y + radius * 0.2, center.z + distance);
    this.camera.updateProjectionMatrix();
    this.controls.target.copy(center);
    this.controls.update();
  }

  // A floor grid at the character's lowest point (the skinned surface as posed when the page opened),
  // twice its height across in 20 cells, so a pose's contact with the floor and its scale read at once.
  addFloorGrid(box) {
    const size = 2 * this.characterHeight;
    this.grid = new THREE.GridHelper(size, 20, 0x8a93a3, 0x4a505b);
    const center = box.getCenter(new THREE.Vector3());
    this.grid.position.set(center.x, box.min.y, center.z);
    this.scene.add(this.grid);
  }

  // The orbit camera's target at a joint (any three.js object of the scene) as it is posed now, the
  // camera kept on its side of the joint at a close-up distance (half the character's height).
  frameJoint(object) {
    if (!object) return this.frameCamera();
    this.selectedJoint = object;
    object.updateWorldMatrix(true, false);
    const target = new THREE.Vector3().setFromMatrixPosition(object.matrixWorld);
    const direction = new THREE.Vector3().subVectors(this.camera.position, this.controls.target);
    if (direction.lengthSq() === 0) direction.set(0, 0, 1);
    direction.setLength(0.5 * (this.characterHeight || 1.8));
    this.camera.position.copy(target).add(direction);
    this.controls.target.copy(target);
    this.controls.update();
  }

  // 'F': frames the selected joint again where it is now (or the whole character).
  reframe() {
    if (this.selectedJoint) this.frameJoint(this.selectedJoint);
    else this.frameCamera();
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
