// Prints bench/run's runtime tables as markdown from the JSON that runtime_bench and `rigbake bake
// --stats` wrote. Usage (one table per call):
//   node runtime_tables.js rig NAME:RIG.json...             runtime_bench rig lines, one file each
//   node runtime_tables.js wasm NAME:NATIVE.json:WASM.json...  runtime_bench capi and runtime_wasm_check.mjs lines
//   node runtime_tables.js jiggle JIGGLE.json               a runtime_bench jiggle line
//   node runtime_tables.js bytes NAME:MODE:STATS:GLB...     a bake's stats and its output file
//   node runtime_tables.js volume NAME:PRESET:STATS...      a bake's stats
"use strict";
const fs = require("fs");

const readJson = (file) => JSON.parse(fs.readFileSync(file, "utf8"));
const fixed = (x, d) => (x === null || x === undefined || Number.isNaN(x) ? "n/a" : Number(x).toFixed(d));
const signed = (x, d) => (x > 0 ? "+" : "") + fixed(x, d);
const table = (header, rows) => {
  console.log("| " + header.join(" | ") + " |");
  console.log("|" + header.map((h, i) => (i === 0 ? " :--- " : " ---: ")).join("|") + "|");
  // A "|" inside a cell (Quaternius' clips are "CharacterArmature|Run") would end it: escape it.
  for (const row of rows) console.log("| " + row.map((cell) => String(cell).replace(/\|/g, "\\|")).join(" | ") + " |");
};
const baseName = (file) => require("path").basename(file).replace(/\.(glb|gltf|vrm)$/, "");

// Issue 12: the sample's 28-muscle rig (bench/run bakes it without the armpit correctives as
// sample_muscles_only) evaluated in under a microsecond (float, skinned joints only).
const RIG_GOAL_MUSCLES = 28;
const RIG_GOAL_NS = 1000;

function rig(items) {
  const results = items.map((item) => {
    const [name, file] = item.split(":");
    return Object.assign({name}, readJson(file));
  });
  console.log("### Runtime muscle rig: ns per evaluation of the whole rig (one thread)");
  console.log();
  table(["character", "muscles", "keys", "frames", "float skinned", "float +helpers", "double skinned",
         "double +helpers", "float skinned / muscle", "float skinned, FTZ/DAZ"],
        results.map((r) => [r.name, r.muscles, r.keys, r.clips > 0 ? r.frames : "1 (no clips: rest pose)",
                            fixed(r.float_skinned_ns, 0), fixed(r.float_helpers_ns, 0), fixed(r.double_skinned_ns, 0),
                            fixed(r.double_helpers_ns, 0), fixed(r.float_skinned_ns / Math.max(1, r.muscles), 1),
                            fixed(r.float_skinned_ftz_ns, 0)]));
  console.log();
  console.log("runtime::MuscleRigJob::Run on the rig each file's RIGBAKE_muscle_rig extension holds (bake " +
              "--muscle-motion runtime), at every key time of every clip, model-space joint matrices " +
              "precomputed and in cache (windows of 64 KB of consecutive frames, the fastest of 9 passes per " +
              "window, the mean over every frame). \"+helpers\" also writes base, tip and driver. The FTZ/DAZ " +
              "column runs float with denormals flushed to zero, as games usually do; the others run in the " +
              "default floating-point environment.");
  const goal = results.filter((r) => r.muscles === RIG_GOAL_MUSCLES);
  const verdict = (ns) => (ns < RIG_GOAL_NS ? "met" : "NOT met");
  console.log(`goal (issue 12): the ${RIG_GOAL_MUSCLES}-muscle rig under ${RIG_GOAL_NS / 1000} µs per evaluation ` +
              "(float, skinned matrices only): " +
              (goal.length === 0 ? `no ${RIG_GOAL_MUSCLES}-muscle rig among these bakes`
                                 : goal.map((r) => `${r.name} ${fixed(r.float_skinned_ns, 0)} ns ${verdict(r.float_skinned_ns)}`).join("; ")));
}

// Issue 31: the WebAssembly build's rig evaluation within 2x of the native float one.
const WASM_GOAL_RATIO = 2;

function wasm(items) {
  const results = items.map((item) => {
    const [name, native, web] = item.split(":");
    return Object.assign({name}, readJson(native), readJson(web));
  });
  console.log("### Runtime C API: ns per evaluation of the whole rig, native float vs WebAssembly (node, one thread)");
  console.log();
  table(["character", "muscles", "frames", "native float", "WebAssembly float", "WebAssembly / native"],
        results.map((r) => [r.name, r.muscles, r.frames, fixed(r.native_float_ns, 0), fixed(r.wasm_float_ns, 0),
                            fixed(r.wasm_float_ns / r.native_float_ns, 2)]));
  console.log();
  console.log("rigbake_rig_evaluate (runtime/rigbake_runtime.h, skinned matrices only) on the rig of each runtime bake, " +
              "over every key time of every clip, node matrices precomputed: natively (runtime_bench capi, " +
              "librigbake_runtime's code in the benchmark binary) and as WebAssembly (scripts/build-wasm.sh, -O3 -msimd128) " +
              `in node ${process.version} (tests/runtime_wasm_check.mjs, frames in the WebAssembly heap); ` +
              "both timed alike: half a second of warm-up, then windows of 64 consecutive frames, the fastest of 9 passes per " +
              "window, the mean over every frame.");
  const worst = results.reduce((w, r) => Math.max(w, r.wasm_float_ns / r.native_float_ns), 0);
  console.log(`goal (issue 31): WebAssembly within ${WASM_GOAL_RATIO}x of native float: largest ratio ${fixed(worst, 2)} ` +
              (worst <= WASM_GOAL_RATIO ? "met" : "NOT met"));
}

function jiggle(file) {
  const r = readJson(file);
  console.log(`### Jiggle step cost: runtime::JiggleJob, preset ${r.preset} on ${baseName(r.input)} ` +
              `(${r.jiggles.length} jiggles: ${r.jiggles.join(", ")}), one thread`);
  console.log();
  table(["real", "fps", "steps/frame", "frames", "ns/frame (all jiggles)", "ns/jiggle/frame", "ns/jiggle/step"],
        r.rows.map((row) => [row.real, row.fps, row.steps_per_frame, row.frames, fixed(row.frame_ns, 0),
                             fixed(row.jiggle_frame_ns, 0), fixed(row.jiggle_step_ns, 1)]));
  console.log();
  // Per jiggle, a frame at 30 fps costs 8 steps + the frame's outputs, at 60 fps 4 steps + outputs: the
  // difference gives the step alone and what is left the per-frame work (interpolation, outputs).
  for (const real of ["float", "double"]) {
    const at = (fps) => r.rows.find((row) => row.real === real && row.fps === fps);
    const a = at(30), b = at(60);
    if (!a || !b || a.steps_per_frame === b.steps_per_frame) continue;
    const step = (a.jiggle_frame_ns - b.jiggle_frame_ns) / (a.steps_per_frame - b.steps_per_frame);
    const rest = b.jiggle_frame_ns - b.steps_per_frame * step;
    console.log(`${real}: from the 30 and 60 fps rows, one 240 Hz step ≈ ${fixed(step, 1)} ns per jiggle and ` +
                `the per-frame work (targets, outputs) ≈ ${fixed(rest, 0)} ns per jiggle`);
  }
  console.log("Fixed 240 Hz steps with the leftover time carried; one JiggleJob::Run per frame over every clip " +
              "(reset untimed on each clip's first frame), outputs the corrections; joint matrices (skeleton, " +
              "then the muscle rig's skinned joints) precomputed; each frame the fastest of 9 Runs from the same " +
              "state, the mean over every frame. ns/jiggle/step = " +
              "ns/jiggle/frame / steps per frame (the frame's outputs included).");
}

function bytes(items) {
  const rows = items.map((item) => {
    const [name, mode, stats, glb] = item.split(":");
    const s = readJson(stats);
    const a = s.animation_bytes;
    return {name, mode, input: a.input, output: a.output, motion: a.muscle_motion, file: fs.statSync(glb).size,
            muscles: s.muscle_joints};
  });
  console.log("### Animation bytes per muscle motion mode (bake --influences 10)");
  console.log();
  table(["character", "muscles", "mode", "input animation B", "output animation B", "added B", "added %", "file B"],
        rows.map((r) => [r.name, r.muscles, r.motion, r.input, r.output, signed(r.output - r.input, 0),
                         r.input > 0 ? signed(100 * (r.output - r.input) / r.input, 1) : "n/a", r.file]));
  console.log();
  console.log("animation_bytes {input, output, muscle_motion} from bake --stats; file B is the size of the " +
              "written .glb (the stats do not hold it).");
  const runtime = rows.filter((r) => r.motion === "runtime");
  const over = runtime.filter((r) => r.output !== r.input);
  console.log("goal: runtime adds 0 animation bytes: " +
              (over.length === 0 ? `MET on all ${runtime.length} characters`
                                 : "NOT MET on " + over.map((r) => `${r.name} (${signed(r.output - r.input, 0)} B)`).join(", ")));
}

function volume(items) {
  console.log("### Whole-body volume change per clip (issue 11): input skinning / dual quaternions / rigbake");
  console.log();
  const rows = [];
  for (const item of items) {
    const [name, preset, stats] = item.split(":");
    const s = readJson(stats);
    const clips = s.deformation_quality.body.per_clip;
    for (const clip of Object.keys(clips)) {
      const v = clips[clip];
      // Within the printed precision (0.005 %) the two are the same.
      const gain = Math.abs(v.input.change_percent) - Math.abs(v.rig.change_percent);
      rows.push([name, preset, clip, signed(v.input.change_percent, 2), signed(v.dual_quaternion.change_percent, 2),
                 signed(v.rig.change_percent, 2), gain >= 0.005 ? "yes" : gain > -0.005 ? "same" : "no"]);
    }
  }
  table(["character", "preset", "clip", "input skinning %", "dual quaternion %", "rigbake %", "rigbake closer to 0"], rows);
  console.log();
  console.log("deformation_quality.body.per_clip change_percent from bake --stats: the whole body's volume change " +
              "V(t) / V(bind) - 1 with the largest magnitude over the clip's sampled frames, in percent (- lost).");
}

const [mode, ...args] = process.argv.slice(2);
if (mode === "rig") rig(args);
else if (mode === "wasm") wasm(args);
else if (mode === "jiggle") jiggle(args[0]);
else if (mode === "bytes") bytes(args);
else if (mode === "volume") volume(args);
else {
  console.error("usage: node runtime_tables.js rig|wasm|jiggle|bytes|volume FILES...");
  process.exit(1);
}
