// The WebAssembly runtime (scripts/build-wasm.sh: rigbake_runtime.wasm + rigbake_runtime.mjs) on a real
// bake, in node, as tests/c_api/runtime_c_check.c runs the native library: for every pose of POSES.f32
// (frames * NODE_COUNT * 16 floats) it evaluates the muscles, stores them into the pose, steps the
// jiggles by FRAME_SECONDS (after a hit on every jiggle at frame 5) and writes the skinned matrices
// then the jiggles' corrections of every frame to OUT.f32. tests/runtime_c_api_test.cpp compares that
// with the native C API's. With BENCH=1 it instead prints the ns per muscle-rig evaluation over the
// poses (bench/run, beside runtime_bench capi's native figure).
// usage: node runtime_wasm_check.mjs WASM_DIR EXTENSION.json NODE_COUNT POSES.f32 FRAME_SECONDS OUT.f32
import fs from 'node:fs';
import path from 'node:path';
import { pathToFileURL } from 'node:url';

const [wasmDir, extensionPath, nodeCountText, posesPath, frameSecondsText, outPath] = process.argv.slice(2);
const { loadRigbakeRuntime } = await import(pathToFileURL(path.join(wasmDir, 'rigbake_runtime.mjs')).href);
const runtime = await loadRigbakeRuntime(fs.readFileSync(path.join(wasmDir, 'rigbake_runtime.wasm')));
const nodeCount = Number(nodeCountText);
const rig = runtime.createRig(fs.readFileSync(extensionPath, 'utf8'), nodeCount);
const posesBytes = fs.readFileSync(posesPath);
const poses = new Float32Array(posesBytes.buffer, posesBytes.byteOffset, posesBytes.byteLength / 4);
const nodeFloats = 16 * nodeCount;
const frames = poses.length / nodeFloats;

if (process.env.BENCH) {
  // As runtime_bench capi times the native library: every frame in memory (the WebAssembly heap here),
  // rigbake_rig_evaluate on each in turn.
  const e = runtime.exports;
  const base = runtime.alloc(poses.byteLength);
  new Float32Array(e.memory.buffer, base, poses.length).set(poses);
  // As runtime_bench times the native rig: windows of 64 consecutive frames, per window the fastest of
  // 9 passes (a pass takes some 0.1 ms, so one the scheduler interrupted is rarely the fastest), summed
  // over the windows: the mean over every frame. Half a second of warm-up first, so that V8 has tiered
  // the module up from its baseline compiler.
  const window = 64;
  const run = (begin, end) => {
    for (let f = begin; f < end; ++f) e.rigbake_rig_evaluate(rig._handle, base + 4 * f * nodeFloats, rig._skinned, 0, 0);
  };
  for (const warm = Date.now(); Date.now() - warm < 500;) run(0, frames);
  let total = 0;
  for (let begin = 0; begin < frames; begin += window) {
    const end = Math.min(frames, begin + window);
    let fastest = Infinity;
    for (let pass = 0; pass < 9; ++pass) {
      const start = process.hrtime.bigint();
      run(begin, end);
      fastest = Math.min(fastest, Number(process.hrtime.bigint() - start));
    }
    total += fastest;
  }
  const fastest = total / frames;
  console.log(JSON.stringify({ muscles: rig.muscleCount, frames, wasm_float_ns: fastest }));
  process.exit(0);
}

const out = [];
for (let f = 0; f < frames; ++f) {
  rig.nodeMatrices.set(poses.subarray(f * nodeFloats, (f + 1) * nodeFloats));
  out.push(Float32Array.from(rig.evaluate()));
  rig.storeSkinned();
  if (f === 5 && rig.jiggleCount > 0) rig.jiggleImpulse(-1, [0, 0, 1], 2.0);
  // As the C program: FRAME_SECONDS read as a float.
  const { corrections } = rig.jiggleStep(f === 0 ? 0 : Math.fround(Number(frameSecondsText)));
  out.push(Float32Array.from(corrections));
}
const total = out.reduce((n, a) => n + a.length, 0);
const all = new Float32Array(total);
let at = 0;
for (const a of out) {
  all.set(a, at);
  at += a.length;
}
fs.writeFileSync(outPath, Buffer.from(all.buffer));
console.log(`runtime_wasm_check: ${frames} frames, ${rig.muscleCount} muscles, ${rig.jiggleCount} jiggles`);
rig.destroy();
