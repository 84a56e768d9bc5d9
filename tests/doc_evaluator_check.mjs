// The muscle rig evaluated from its document alone (tests/doc_evaluator/muscle_rig_from_doc.mjs), in node,
// on the frames tests/runtime_c_api_test.cpp writes for the WebAssembly check: for every pose of POSES.f32
// (frames * NODE_COUNT * 16 floats, each node's world matrix, column-major) it writes to OUT.f64, per frame
// and per muscle, 67 doubles: the skinned joint's world matrix (16), the base, tip and driver helper world
// matrices (48, zeros for a muscle without helperNodes) and the ratio, clamped ratio and twist (3).
// tests/doc_evaluator_test.cpp compares them with the C++ runtime's MuscleRigJob<double>.
// usage: node doc_evaluator_check.mjs EXTENSION.json NODE_COUNT POSES.f32 OUT.f64
import fs from 'node:fs';
import { prepareMuscleRig, evaluateMuscleRig } from './doc_evaluator/muscle_rig_from_doc.mjs';

const [extensionPath, nodeCountText, posesPath, outPath] = process.argv.slice(2);
const rig = prepareMuscleRig(JSON.parse(fs.readFileSync(extensionPath, 'utf8')));
const nodeCount = Number(nodeCountText);
const bytes = fs.readFileSync(posesPath);
const poses = new Float32Array(bytes.buffer, bytes.byteOffset, bytes.byteLength / 4);
const nodeFloats = 16 * nodeCount;
const frames = poses.length / nodeFloats;
const perMuscle = 16 + 48 + 3;
const out = new Float64Array(frames * rig.length * perMuscle);
for (let f = 0; f < frames; ++f) {
  const worldOf = (node) => Array.from(poses.subarray(f * nodeFloats + 16 * node, f * nodeFloats + 16 * node + 16));
  const { skinned, helpers, drivers } = evaluateMuscleRig(rig, worldOf);
  for (let m = 0; m < rig.length; ++m) {
    const at = (f * rig.length + m) * perMuscle;
    out.set(skinned[m], at);
    if (helpers[m]) helpers[m].forEach((matrix, h) => out.set(matrix, at + 16 + 16 * h));
    out.set([drivers[m].ratio, drivers[m].clampedRatio, drivers[m].twist], at + 64);
  }
}
fs.writeFileSync(outPath, Buffer.from(out.buffer));
console.log(`doc_evaluator_check: ${frames} frames, ${rig.length} muscles`);
