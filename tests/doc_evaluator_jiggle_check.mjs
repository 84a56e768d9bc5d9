// The jiggles stepped from the document alone (tests/doc_evaluator/jiggles_from_doc.mjs), in node, on the
// frames tests/doc_evaluator_test.cpp writes: POSES.f64 holds poses * NODE_COUNT * 16 doubles (each
// node's un-jiggled world matrix, muscle skinned nodes included), FRAMES.json one
// { pose, dt, maxSteps, reset, hit } per frame: pose the index of the frame's pose in POSES.f64; maxSteps
// the cap of 10b (0: none); reset false, true (at rest) or { pose, delta } (moving with the target, the
// second pose `delta` seconds from the frame's); hit [jiggle, direction, magnitude] or null. Writes to
// OUT.f64, per frame and jiggle, the correction (x, y, z, w), the jiggle point (3) and the jiggled world
// matrix (16).
// usage: node doc_evaluator_jiggle_check.mjs EXTENSION.json NODE_COUNT POSES.f64 FRAMES.json OUT.f64
import fs from 'node:fs';
import { prepareJiggles, startJiggle, hitJiggle, stepJiggle } from './doc_evaluator/jiggles_from_doc.mjs';

const [extensionPath, nodeCountText, posesPath, framesPath, outPath] = process.argv.slice(2);
const jiggles = prepareJiggles(JSON.parse(fs.readFileSync(extensionPath, 'utf8')).jiggles ?? []);
const nodeCount = Number(nodeCountText);
const bytes = fs.readFileSync(posesPath);
const poses = new Float64Array(bytes.buffer.slice(bytes.byteOffset, bytes.byteOffset + bytes.byteLength));
const frames = JSON.parse(fs.readFileSync(framesPath, 'utf8'));
const out = new Float64Array(frames.length * jiggles.length * 23);
const worldOfPose = (pose) => (node) => {
  const base = (pose * nodeCount + node) * 16;
  return Array.from(poses.subarray(base, base + 16));
};
frames.forEach((frame, f) => {
  const worldOf = worldOfPose(frame.pose);
  if (frame.reset === true) jiggles.forEach((j) => startJiggle(j, worldOf));
  else if (frame.reset) jiggles.forEach((j) => startJiggle(j, worldOf, { worldOf: worldOfPose(frame.reset.pose), delta: frame.reset.delta }));
  if (frame.hit) hitJiggle(jiggles[frame.hit[0]], frame.hit[1], frame.hit[2]);
  jiggles.forEach((j, k) => {
    const { correction, point, world } = stepJiggle(j, worldOf, frame.dt, frame.maxSteps);
    out.set([...correction, ...point, ...world], (f * jiggles.length + k) * 23);
  });
});
fs.writeFileSync(outPath, Buffer.from(out.buffer));
console.log(`doc_evaluator_jiggle_check: ${frames.length} frames, ${jiggles.length} jiggles`);
