// The player's JavaScript copies of the equations (player/src/muscle_rig.js, player/src/jiggle.js)
// against the runtime itself (the WebAssembly build of the C API, bit-identical to the native float
// library: tests/runtime_c_api_test.cpp), in node, on the frames tests/runtime_c_api_test.cpp writes:
// per frame the muscles (JS: float64 from the same float32 node matrices) and the jiggles stepped by
// FRAME_SECONDS, a hit of 2 m/s along +z on every jiggle at frame 5. Prints one JSON line: the largest
// difference of the skinned matrices' translations (m) and of their rotation/scale terms, and the jiggle rotations' largest and mean angle apart
// (degrees), with the largest jiggle rotation seen, for scale.
// usage: node player_conformance_check.mjs REPO WASM_DIR EXTENSION.json NODE_COUNT POSES.f32 FRAME_SECONDS
import fs from 'node:fs';
import path from 'node:path';
import { pathToFileURL } from 'node:url';

const [repo, wasmDir, extensionPath, nodeCountText, posesPath, frameSecondsText] = process.argv.slice(2);
const load = (file) => import(pathToFileURL(file).href);
const { loadRigbakeRuntime } = await load(path.join(wasmDir, 'rigbake_runtime.mjs'));
const { readMuscleRig, evaluateMuscle, rotationOf } = await load(path.join(repo, 'player/src/muscle_rig.js'));
const { LiveJiggle } = await load(path.join(repo, 'player/src/jiggle.js'));

const runtime = await loadRigbakeRuntime(fs.readFileSync(path.join(wasmDir, 'rigbake_runtime.wasm')));
const nodeCount = Number(nodeCountText);
const text = fs.readFileSync(extensionPath, 'utf8');
const rig = runtime.createRig(text, nodeCount);
const { rig: jsRig, problems } = readMuscleRig({ nodes: new Array(nodeCount).fill({}), extensions: { RIGBAKE_muscle_rig: JSON.parse(text) } });
if (!jsRig) throw new Error(problems.join('\n'));
const live = jsRig.jiggles.map((setup) => new LiveJiggle(setup));
const bytes = fs.readFileSync(posesPath);
const poses = new Float32Array(bytes.buffer, bytes.byteOffset, bytes.byteLength / 4);
const nodeFloats = 16 * nodeCount;
const frames = poses.length / nodeFloats;
const dt = Math.fround(Number(frameSecondsText));
const angle = (a, b) => {
  const d = Math.abs(a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3]);
  return (2 * Math.acos(Math.min(1, d)) * 180) / Math.PI;
};
let muscleDifference = 0, muscleTranslation = 0, jiggleLargest = 0, jiggleSum = 0, jiggleCount = 0, largestRotation = 0;
for (let f = 0; f < frames; ++f) {
  const pose = poses.subarray(f * nodeFloats, (f + 1) * nodeFloats);
  rig.nodeMatrices.set(pose);
  const skinned = rig.evaluate();
  rig.storeSkinned();
  const joints = [];
  for (let n = 0; n < nodeCount; ++n) joints.push(Array.from(pose.subarray(16 * n, 16 * n + 16)));
  const jsSkinned = jsRig.muscles.map((muscle) => evaluateMuscle(muscle, joints).skinned);
  jsRig.muscles.forEach((muscle, m) => {
    for (let k = 0; k < 16; ++k) {
      const difference = Math.abs(jsSkinned[m][k] - skinned[16 * m + k]);
      if (k >= 12) muscleTranslation = Math.max(muscleTranslation, difference);
      else muscleDifference = Math.max(muscleDifference, difference);
    }
    joints[muscle.skinnedNode] = jsSkinned[m];
  });
  if (f === 5 && rig.jiggleCount > 0) {
    rig.jiggleImpulse(-1, [0, 0, 1], 2.0);
    for (const jiggle of live) jiggle.hit([0, 0, 2]);
  }
  const { corrections } = rig.jiggleStep(f === 0 ? 0 : dt);
  live.forEach((jiggle, j) => {
    const world = joints[jiggle.setup.node];
    const pivotRotation = rotationOf(world);
    const offset = jiggle.advance({ translation: [world[12], world[13], world[14]], rotation: pivotRotation }, f === 0 ? 0 : dt);
    const root = jiggle.setup.rootNode >= 0 ? rotationOf(joints[jiggle.setup.rootNode]) : [0, 0, 0, 1];
    const d = jiggle.rotationFor(offset, pivotRotation, root);
    const c = Array.from(corrections.subarray(4 * j, 4 * j + 4));
    const apart = angle(d, c);
    jiggleLargest = Math.max(jiggleLargest, apart);
    jiggleSum += apart;
    ++jiggleCount;
    largestRotation = Math.max(largestRotation, angle(c, [0, 0, 0, 1]));
  });
}
console.log(JSON.stringify({
  frames, muscles: rig.muscleCount, jiggles: rig.jiggleCount, muscle_translation_m: muscleTranslation, muscle_terms: muscleDifference,
  jiggle_largest_deg: jiggleLargest, jiggle_mean_deg: jiggleCount ? jiggleSum / jiggleCount : 0,
  largest_jiggle_rotation_deg: largestRotation,
}));
