// three-vrm 3.x loads a VRM 1.0 that rigbake wrote (window.RIGBAKE_VRM_BASE64, set by the page's data
// script), plays its first clip as an app that plays the file's own clips must (humanoid
// autoUpdateHumanBones off, vrm.update after the mixer), and reports what three-vrm built and how it ran:
// the spring joints' largest swing, the aim constraints' largest error after every update, and how far
// the clip turns a forearm with autoUpdateHumanBones off and (three-vrm's default) on. The page
// (tests/vrm_three_test.cpp) reads the JSON from <pre id="rigbake-test-result">, through
// player/test/run_page.mjs, once the title says "rigbake-test: done".
import * as THREE from 'three';
import { GLTFLoader } from 'three/examples/jsm/loaders/GLTFLoader.js';
import { VRMLoaderPlugin } from '@pixiv/three-vrm';

const FRAMES = 120;
const DT = 1 / 60;

function bytesOf(base64) {
  const text = atob(base64);
  const bytes = new Uint8Array(text.length);
  for (let i = 0; i < text.length; i += 1) bytes[i] = text.charCodeAt(i);
  return bytes.buffer;
}

function worldPosition(object) {
  return new THREE.Vector3().setFromMatrixPosition(object.matrixWorld);
}

// Degrees between the destination's aim axis in the world and the direction to its source.
function aimError(constraint) {
  const axis = { PositiveX: [1, 0, 0], NegativeX: [-1, 0, 0], PositiveY: [0, 1, 0], NegativeY: [0, -1, 0], PositiveZ: [0, 0, 1], NegativeZ: [0, 0, -1] }[
    constraint.aimAxis
  ];
  const m = constraint.destination.matrixWorld;
  const aim = new THREE.Vector3(...axis).transformDirection(m);
  const to = worldPosition(constraint.source).sub(worldPosition(constraint.destination)).normalize();
  return THREE.MathUtils.radToDeg(Math.acos(Math.min(1, Math.max(-1, aim.dot(to)))));
}

function underAny(object, nodes) {
  for (let o = object; o; o = o.parent) if (nodes.has(o)) return true;
  return false;
}

async function load() {
  const loader = new GLTFLoader();
  loader.register((parser) => new VRMLoaderPlugin(parser));
  return loader.parseAsync(bytesOf(window.RIGBAKE_VRM_BASE64), '');
}

// Plays the first clip for FRAMES frames with the humanoid's autoUpdateHumanBones as given.
function play(gltf, autoUpdateHumanBones) {
  const vrm = gltf.userData.vrm;
  const joints = [...vrm.springBoneManager.joints];
  const constraints = [...vrm.nodeConstraintManager.constraints];
  const springNodes = new Set(joints.map((j) => j.bone));
  vrm.humanoid.autoUpdateHumanBones = autoUpdateHumanBones;
  const mixer = new THREE.AnimationMixer(vrm.scene);
  if (gltf.animations.length > 0) mixer.clipAction(gltf.animations[0]).play();
  vrm.scene.updateMatrixWorld(true);
  const rest = joints.map((j) => new THREE.Quaternion().setFromRotationMatrix(j.bone.matrixWorld));
  // The clip's own motion: how far the right forearm turns from its rest rotation (the left one is a spring).
  const forearm = vrm.humanoid.getRawBoneNode('rightLowerArm');
  const forearmRest = forearm.quaternion.clone();
  const leftHandX = worldPosition(vrm.humanoid.getRawBoneNode('leftHand')).x;  // at rest: +X when facing +Z
  let largestSwing = 0;
  let largestAim = 0;
  let largestClipTurn = 0;
  for (let frame = 0; frame < FRAMES; frame += 1) {
    mixer.update(DT);
    vrm.update(DT);
    vrm.scene.updateMatrixWorld(true);
    joints.forEach((j, k) => {
      const now = new THREE.Quaternion().setFromRotationMatrix(j.bone.matrixWorld);
      largestSwing = Math.max(largestSwing, THREE.MathUtils.radToDeg(now.angleTo(rest[k])));
    });
    for (const c of constraints) largestAim = Math.max(largestAim, aimError(c));
    largestClipTurn = Math.max(largestClipTurn, THREE.MathUtils.radToDeg(forearm.quaternion.angleTo(forearmRest)));
  }
  return {
    metaVersion: vrm.meta.metaVersion,
    humanBones: Object.keys(vrm.humanoid.rawHumanBones).filter((name) => vrm.humanoid.getRawBoneNode(name)).length,
    springJoints: joints.length,
    colliders: [...(vrm.springBoneManager.colliders || [])].length,
    colliderGroups: [...(vrm.springBoneManager.colliderGroups || [])].length,
    constraints: constraints.length,
    constraintsUnderSprings: constraints.filter((c) => underAny(c.destination, springNodes)).length,
    clip: gltf.animations.length > 0 ? gltf.animations[0].name : '',
    frames: FRAMES,
    largestSpringSwingDeg: largestSwing,
    largestAimErrorDeg: largestAim,
    largestClipTurnDeg: largestClipTurn,
    leftHandX,
  };
}

async function run() {
  const result = play(await load(), false);
  // three-vrm's default: the normalized rig's pose is copied onto the raw bones at every update.
  result.largestClipTurnDegWithAutoUpdate = play(await load(), true).largestClipTurnDeg;
  return result;
}

function finish(result) {
  const pre = document.createElement('pre');
  pre.id = 'rigbake-test-result';
  pre.textContent = JSON.stringify(result);
  document.body.appendChild(pre);
  document.title = 'rigbake-test: done';
}

run().then(finish, (error) => finish({ error: String(error && error.stack ? error.stack : error) }));
