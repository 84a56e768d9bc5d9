// The page's self-test (index.html?test=1), for tests/view_test.cpp in headless Chromium. It drives
// the page through its own controls, plays every clip, tries every muscle mode, influence count and
// the heatmap, kicks the jiggles, and, when the test handed it a reference (window.RIGBAKE_REFERENCE,
// computed by rigbake's C++ runtime and skinning), compares the muscle matrices the plugin set (the
// WebAssembly runtime's) and the GPU-skinned positions with it. The result is JSON in <pre id="rigbake-test-result">.

import * as THREE from 'three';
import { INFLUENCE_COUNTS } from './player.js';
import { readBackSkinning } from '../plugin/src/index.js';

const captured = { errors: [], warnings: [] };

// Records console errors and warnings and uncaught errors before anything else runs.
export function installErrorCapture() {
  for (const [level, list] of [['error', captured.errors], ['warn', captured.warnings]]) {
    const original = console[level].bind(console);
    console[level] = (...args) => {
      list.push(args.map((a) => (a instanceof Error ? `${a.name}: ${a.message}` : String(a))).join(' '));
      original(...args);
    };
  }
  window.addEventListener('error', (event) => captured.errors.push(`uncaught: ${event.message}`));
  window.addEventListener('unhandledrejection', (event) => captured.errors.push(`unhandled rejection: ${event.reason}`));
}

function decodeFloat64(base64) {
  const binary = atob(base64);
  const bytes = new Uint8Array(binary.length);
  for (let i = 0; i < binary.length; ++i) bytes[i] = binary.charCodeAt(i);
  return new Float64Array(bytes.buffer);
}

function decodeFloat32(base64) {
  const binary = atob(base64);
  const bytes = new Uint8Array(binary.length);
  for (let i = 0; i < binary.length; ++i) bytes[i] = binary.charCodeAt(i);
  return new Float32Array(bytes.buffer);
}

const click = (id) => document.getElementById(id).click();
function choose(id, value) {
  const select = document.getElementById(id);
  select.value = String(value);
  select.dispatchEvent(new Event('change'));
}

// Pixels that differ from the background: the character is on screen.
function visiblePixels(player) {
  const gl = player.renderer.getContext();
  const width = gl.drawingBufferWidth;
  const height = gl.drawingBufferHeight;
  const pixels = new Uint8Array(width * height * 4);
  gl.readPixels(0, 0, width, height, gl.RGBA, gl.UNSIGNED_BYTE, pixels);
  let background = [pixels[0], pixels[1], pixels[2]];
  let count = 0;
  for (let i = 0; i < pixels.length; i += 4) {
    if (Math.abs(pixels[i] - background[0]) + Math.abs(pixels[i + 1] - background[1]) + Math.abs(pixels[i + 2] - background[2]) > 24) ++count;
  }
  return count;
}

function glError(player) {
  const gl = player.renderer.getContext();
  return gl.getError();
}

// Plays every clip from its start through its end by the page's clip selector.
function playEveryClip(player) {
  const clips = [];
  for (const clip of player.clips) {
    choose('rb-clip', clip.index);
    const frames = Math.max(4, Math.ceil(clip.duration * 15));
    const dt = clip.duration / frames;
    let maxTime = 0;
    for (let f = 0; f < frames; ++f) {
      player.advance(dt);
      maxTime = Math.max(maxTime, player.time);
      if (f % 4 === 0 || f === frames - 1) player.render();
    }
    clips.push({ index: clip.index, name: clip.name, duration: clip.duration, frames, maxTime, visible: visiblePixels(player), glError: glError(player) });
  }
  return clips;
}

// Every muscle mode x influence count x heatmap, through the page's controls.
function everyMode(player) {
  const modes = [];
  for (const mode of player.availableMuscleModes()) {
    click(`rb-muscles-${mode}`);
    for (const influences of INFLUENCE_COUNTS) {
      if (!player.availableInfluences().includes(influences)) continue;
      click(`rb-influences-${influences}`);
      for (const heatmap of [false, true]) {
        const box = document.getElementById('rb-heatmap');
        if (box.checked !== heatmap) box.click();
        player.advance(1 / 30);
        player.render();
        modes.push({
          mode,
          influences,
          heatmap,
          applied: player.muscleMode === mode && player.influences === influences && player.heatmap === heatmap,
          visible: visiblePixels(player),
          glError: glError(player),
        });
      }
    }
  }
  const box = document.getElementById('rb-heatmap');
  if (box.checked) box.click();
  return modes;
}

// The hit button: jiggle points swing out and settle again.
function hitTest(player) {
  if (!player.jiggles.length || !player.availableMuscleModes().includes('runtime')) return null;
  click('rb-muscles-runtime');
  choose('rb-clip', 0);
  player.playing = false;
  // The largest jiggle correction's angle (degrees): how far the jiggle swings its joint.
  const magnitude = () => Math.max(...player.jiggles.map((j) => (j.angle * 180) / Math.PI));
  for (let f = 0; f < 10; ++f) player.advance(1 / 60);
  const before = magnitude();
  click('rb-hit');
  let peak = 0;
  for (let f = 0; f < 30; ++f) {
    player.advance(1 / 60);
    peak = Math.max(peak, magnitude());
  }
  player.render();
  // Stand still for 6 s: the clip paused at its time, the jiggle must come back to rest.
  const time = player.time;
  for (let f = 0; f < 360; ++f) {
    player.mixer.setTime(time);
    player.frame(1 / 60);
  }
  return { jiggles: player.jiggles.length, before_deg: before, peak_deg: peak, settled_deg: magnitude(), glError: glError(player) };
}

// The size of a matrix's 3x3 part (its largest column length): rotation/scale terms are compared
// relative to it, so that an armature scaled x100 (3x3 terms near 100) is held to the same float
// precision as one in metres. A relative term difference e moves a point at distance d by e * d.
function linearScale(values, at = 0) {
  let scale = 0;
  for (let c = 0; c < 3; ++c) scale = Math.max(scale, Math.hypot(values[at + 4 * c], values[at + 4 * c + 1], values[at + 4 * c + 2]));
  return scale > 0 ? scale : 1;
}

function angleDifference(a, b) {
  let d = a - b;
  while (d > Math.PI) d -= 2 * Math.PI;
  while (d <= -Math.PI) d += 2 * Math.PI;
  return Math.abs(d);
}

// The plugin against the C++ runtime's matrices at the reference's times: the skinned joints' world
// matrices as the scene holds them after the plugin set them, and the runtime's drivers and helpers.
function compareMatrices(player, reference) {
  const out = { frames: 0, muscles: player.muscles.length, translation_m: 0, linear: 0, ratio: 0, twist_rad: 0, helpers_m: 0, helpers_compared: 0, worst: '' };
  player.setMuscleMode('runtime');
  player.jigglesEnabled = false;
  player.rig.record = true;
  const withHelpers = player.rig.hasHelpers;
  for (const clip of reference.clips) {
    player.selectClip(clip.animation);
    clip.times.forEach((time, i) => {
      player.seek(time);
      const cpp = clip.skinned[i];
      if (player.muscles.length * 16 !== cpp.length) throw new Error(`reference has ${cpp.length / 16} muscles, the page ${player.muscles.length}`);
      player.muscles.forEach((entry, m) => {
        const scene = entry.node.matrixWorld.elements;
        const size = linearScale(cpp, 16 * m);
        for (let k = 0; k < 16; ++k) {
          const d = Math.abs(scene[k] - cpp[16 * m + k]) / (k >= 12 ? 1 : size);
          const key = k >= 12 ? 'translation_m' : 'linear';
          if (d > out[key]) {
            out[key] = d;
            if (d > 1e-9) out.worst = `${clip.name} t=${time} ${entry.name} element ${k}: ${scene[k]} vs ${cpp[16 * m + k]}`;
          }
        }
        out.ratio = Math.max(out.ratio, Math.abs(player.rig.lastDrivers[3 * m] - clip.drivers[i][2 * m]));
        out.twist_rad = Math.max(out.twist_rad, angleDifference(player.rig.lastDrivers[3 * m + 2], clip.drivers[i][2 * m + 1]));
        if (clip.helpers && withHelpers) {
          // The helper nodes' world matrices as the scene holds them.
          player.rig.muscles[m].helpers.forEach((helper, h) => {
            if (!helper) return;
            const values = helper.matrixWorld.elements;
            for (let k = 0; k < 16; ++k) out.helpers_m = Math.max(out.helpers_m, Math.abs(values[k] - clip.helpers[i][48 * m + 16 * h + k]));
          });
          ++out.helpers_compared;
        }
      });
      ++out.frames;
    });
  }
  player.rig.record = false;
  player.jigglesEnabled = true;
  return out;
}

// The plugin against the native C API, frame by frame (reference.capi, written by tests/view_test.cpp as
// tests/runtime_c_api_test.cpp runs the C API): the scene is set to each frame's node world matrices, the
// plugin's update runs (muscles, then the jiggles stepped by dt, a hit at hitFrame), and the muscle and
// jiggling joints' world matrices the scene then holds, and the jiggle corrections, are compared with
// the native library's.
function compareCapiFrames(player, data) {
  const out = { frames: 0, muscles: 0, jiggles: 0, muscle_m: 0, muscle_terms: 0, jiggle_m: 0, jiggle_terms: 0, correction: 0, largest_jiggle_deg: 0, worst: '' };
  const poses = decodeFloat32(data.poses);
  const expected = decodeFloat32(data.expected);
  const rig = player.rig;
  player.setMuscleMode('runtime');
  player.mixer.stopAllAction();
  rig.playedFromClip = new Set();
  rig.jigglesEnabled = true;
  rig.record = true;
  rig.resetJiggles();
  // Parents first, so that each node's local matrix is taken under its parent's new world matrix.
  const depth = (object) => (object.parent ? depth(object.parent) + 1 : 0);
  const order = data.nodes.map((n) => player.nodes[n]).sort((a, b) => depth(a) - depth(b));
  const index = new Map(data.nodes.map((n) => [player.nodes[n], n]));
  const nodeFloats = 16 * data.nodeCount;
  const perFrame = 16 * data.muscles + 4 * data.jiggles + 16 * data.jiggles;
  const frames = poses.length / nodeFloats;
  if (frames * perFrame !== expected.length) throw new Error(`capi: ${frames} poses, ${expected.length / perFrame} expected frames`);
  const jiggling = new Set(rig.jiggles.map((j) => j.node));
  const world = new THREE.Matrix4();
  const local = new THREE.Matrix4();
  const compare = (values, at, expectedAt, translationKey, termsKey, label) => {
    const size = linearScale(expected, expectedAt);
    for (let k = 0; k < 16; ++k) {
      const d = Math.abs(values[k] - expected[expectedAt + k]) / (k >= 12 ? 1 : size);
      const key = k >= 12 ? translationKey : termsKey;
      if (d > out[key]) {
        out[key] = d;
        if (d > 1e-6) out.worst = `${label} element ${k}: ${values[k]} vs ${expected[expectedAt + k]}`;
      }
    }
  };
  for (let f = 0; f < frames; ++f) {
    for (const object of order) {
      world.fromArray(poses, f * nodeFloats + 16 * index.get(object));
      local.copy(object.parent.matrixWorld).invert().multiply(world);
      local.decompose(object.position, object.quaternion, object.scale);
      object.matrix.copy(local);
      object.updateMatrixWorld(false);
      object.matrixWorld.copy(world);
    }
    if (f === data.hitFrame) rig.hit(new THREE.Vector3(0, 0, 1), 2.0);
    rig.update(f === 0 ? 0 : data.dt);
    const base = f * perFrame;
    // A jiggling muscle joint's scene matrix holds its jiggle too: the runtime's muscle matrix for it (the
    // scene's is compared with the native jiggled one below).
    rig.muscles.forEach((muscle, m) => {
      const values = jiggling.has(muscle.node) ? rig.lastSkinned.subarray(16 * m, 16 * m + 16) : muscle.node.matrixWorld.elements;
      compare(values, 0, base + 16 * m, 'muscle_m', 'muscle_terms', `frame ${f} ${muscle.name}`);
    });
    rig.jiggles.forEach((jiggle, j) => {
      for (let k = 0; k < 4; ++k) out.correction = Math.max(out.correction, Math.abs(rig.lastCorrections[4 * j + k] - expected[base + 16 * data.muscles + 4 * j + k]));
      const at = base + 16 * data.muscles + 4 * data.jiggles + 16 * j;
      compare(jiggle.node.matrixWorld.elements, 0, at, 'jiggle_m', 'jiggle_terms', `frame ${f} jiggle ${jiggle.name}`);
      out.largest_jiggle_deg = Math.max(out.largest_jiggle_deg, (jiggle.angle * 180) / Math.PI);
    });
    ++out.frames;
  }
  out.muscles = rig.muscles.length;
  out.jiggles = rig.jiggles.length;
  rig.record = false;
  return out;
}

// The GPU's skinning (the player's shader, read back by transform feedback) against rigbake's own
// skinning with the packed 0.001 weights.
function compareSkinning(player, reference) {
  const out = { frames: 0, vertices: 0, max_m: 0, worst: '' };
  if (!reference.skin || !reference.skin.length) return out;
  const gl = document.createElement('canvas').getContext('webgl2');
  if (!gl) throw new Error('no WebGL2 context for the skinning read-back');
  player.setMuscleMode('runtime');
  player.jigglesEnabled = false;
  for (const frame of reference.skin) {
    player.selectClip(frame.animation);
    player.seek(frame.time);
    for (const part of frame.parts) {
      const state = player.skinnedMeshes.find((s) => s.source.mesh === part.mesh && s.source.primitive === part.primitive && s.source.node === part.node);
      if (!state) throw new Error(`no skinned mesh for node ${part.node} mesh ${part.mesh} primitive ${part.primitive}`);
      if (!state.layout) throw new Error(`mesh ${part.mesh} has no packed influences`);
      const skeleton = state.mesh.skeleton;
      skeleton.update();
      const size = Math.max(4, Math.ceil(Math.sqrt(skeleton.bones.length * 4) / 4) * 4);
      const bones = new Float32Array(size * size * 4);
      bones.set(skeleton.boneMatrices.subarray(0, skeleton.bones.length * 16));
      const gpu = readBackSkinning(gl, state.mesh, bones, state.layout.influences);
      const cpp = decodeFloat64(part.positions);
      if (cpp.length !== gpu.length) throw new Error(`mesh ${part.mesh}: ${gpu.length / 3} vertices in the page, ${cpp.length / 3} in the reference`);
      for (let i = 0; i < gpu.length; ++i) {
        const d = Math.abs(gpu[i] - cpp[i]);
        if (d > out.max_m) {
          out.max_m = d;
          out.worst = `animation ${frame.animation} t=${frame.time} mesh ${part.mesh} vertex ${Math.floor(i / 3)}: ${gpu[i]} vs ${cpp[i]}`;
        }
      }
      out.vertices += gpu.length / 3;
    }
    ++out.frames;
  }
  player.jigglesEnabled = true;
  return out;
}

// A `both` bake: at the clips' own key times the file's sampled channels (sampled mode) must put the
// skinned joints where the JavaScript runtime does (the bake sampled them through the C++ runtime).
// Joints a jiggle moves are left out: their channels hold the baked jiggle on top.
function sampledAgainstRuntime(player) {
  const modes = player.availableMuscleModes();
  if (!modes.includes('runtime') || !modes.includes('sampled')) return null;
  const jiggling = new Set(player.jiggles.map((j) => j.node));
  const out = { frames: 0, compared: 0, translation_m: 0, linear: 0 };
  for (const clip of player.clips) {
    const times = clip.clip.tracks.length ? clip.clip.tracks[0].times : [];
    for (const q of [0.25, 0.5, 0.75]) {
      if (!times.length) break;
      const time = times[Math.min(times.length - 1, Math.floor(q * (times.length - 1)))];
      player.setMuscleMode('runtime');
      player.selectClip(clip.index);
      player.seek(time);
      const runtime = player.muscles.map((entry) => entry.node.matrixWorld.elements.slice());
      player.setMuscleMode('sampled');
      player.seek(time);
      player.muscles.forEach((entry, m) => {
        if (jiggling.has(entry.node)) return;
        const sampled = entry.node.matrixWorld.elements;
        const size = linearScale(runtime[m]);
        for (let k = 0; k < 16; ++k) {
          const key = k >= 12 ? 'translation_m' : 'linear';
          out[key] = Math.max(out[key], Math.abs(sampled[k] - runtime[m][k]) / (k >= 12 ? 1 : size));
        }
        ++out.compared;
      });
      ++out.frames;
    }
  }
  player.setMuscleMode('runtime');
  return out;
}

// What one frame of the plugin costs: the skeleton's matrices into the WebAssembly runtime, every
// muscle evaluated and its node set, the jiggles stepped by 1/60 s (the pose stays), microseconds per
// frame over 200 frames.
function runtimeCost(player) {
  if (!player.availableMuscleModes().includes('runtime')) return null;
  player.setMuscleMode('runtime');
  const frames = 200;
  const t0 = performance.now();
  for (let f = 0; f < frames; ++f) player.rig.update(1 / 60);
  return { muscles: player.muscles.length, jiggles: player.jiggles.length, us_per_frame: ((performance.now() - t0) * 1000) / frames };
}

// What a rigger uses besides the modes (docs/view.md "On the page"), through the page's own controls on
// the default clip: the scrubber (pauses, poses the clip at the time; with a reference, the muscle joints
// where rigbake's C++ runtime puts them at the reference's times), frame stepping (buttons and , . keys),
// the joint selector and F (the orbit camera's target at the joint), the floor grid, and the panel's width.
function riggerTools(player, reference) {
  const out = { defaultClip: player.clips.length ? player.clips[player.clipIndex].name : null };
  if (!player.clips.length) return out;
  const clip = player.clips[player.clipIndex];
  choose('rb-clip', clip.index);
  const scrub = document.getElementById('rb-scrub');
  const scrubTo = (t) => {
    scrub.value = String(t);
    scrub.dispatchEvent(new Event('input'));
  };
  const objects = [...new Set([...player.muscles.map((m) => m.node), ...player.skinnedMeshes.flatMap((s) => s.mesh.skeleton.bones)])];
  const positions = () => objects.map((o) => new THREE.Vector3().setFromMatrixPosition(o.matrixWorld));
  const farthest = (a, b) => Math.max(...a.map((p, i) => p.distanceTo(b[i])));
  // Scrubbing: pauses, poses, and the same time gives the same pose.
  const t1 = 0.41 * clip.duration;
  player.playing = true;
  scrubTo(t1);
  out.paused_by_scrub = !player.playing && document.getElementById('rb-play').textContent === 'Play';
  out.scrub_time_error = Math.abs(player.time - t1);
  const p1 = positions();
  scrubTo(0);
  out.moved_m = farthest(p1, positions());
  scrubTo(t1);
  out.repeat_m = farthest(p1, positions());
  // Against rigbake's C++ runtime (the agreement pages): the muscle joints' translations at the times.
  const ref = reference && reference.clips.find((c) => c.animation === clip.index);
  out.reference_frames = 0;
  out.reference_m = 0;
  if (ref && player.muscleMode === 'runtime') {
    player.jigglesEnabled = false; // the reference has no jiggles
    ref.times.forEach((time, i) => {
      scrubTo(time);
      player.muscles.forEach((entry, m) => {
        const e = entry.node.matrixWorld.elements;
        for (let k = 12; k < 15; ++k) out.reference_m = Math.max(out.reference_m, Math.abs(e[k] - ref.skinned[i][16 * m + k]));
      });
      ++out.reference_frames;
    });
    // The joint selector's first muscle: the camera's target where the C++ runtime puts that joint.
    const last = ref.times.length - 1;
    scrubTo(ref.times[last]);
    choose('rb-joint', 1);
    const expected = new THREE.Vector3().fromArray(ref.skinned[last], 12);
    out.camera_vs_reference_m = player.selectedJoint === player.muscles[0].node ? player.controls.target.distanceTo(expected) : -1;
    choose('rb-joint', 0);
    player.jigglesEnabled = true;
  }
  // Stepping: one frame forward and back by the buttons and the keys, the pose the scrubber gives there.
  const dt = player.frameStep();
  out.frame_step = dt;
  const start = 10 * dt;
  scrubTo(start);
  const key = (k) => window.dispatchEvent(new KeyboardEvent('keydown', { key: k }));
  click('rb-next');
  out.next_dt = player.time - start;
  const stepped = positions();
  scrubTo(start + dt);
  out.step_pose_m = farthest(stepped, positions());
  click('rb-prev');
  out.prev_dt = player.time - start;
  key('.');
  key('.');
  out.key_dt = player.time - start;
  key(',');
  out.key_back_dt = player.time - start;
  out.paused_by_step = !player.playing;
  // The orbit camera: the target at the chosen joint (a muscle joint, the last skeleton joint), and
  // after a frame's step F puts it at the joint's new place.
  const select = document.getElementById('rb-joint');
  out.joint_options = select.options.length;
  out.camera_target_m = 0;
  out.framed = [];
  // The first muscle, and the joint that moves most between the two times (the page's list of targets).
  const targets = player.jointTargets;
  const worldAt = (t) => {
    scrubTo(t);
    return targets.map((o) => (o ? new THREE.Vector3().setFromMatrixPosition(o.matrixWorld) : null));
  };
  const a = worldAt(start + dt);
  const b = worldAt(0.75 * clip.duration);
  let most = 1;
  targets.forEach((o, i) => {
    if (o && a[i].distanceTo(b[i]) > a[most].distanceTo(b[most])) most = i;
  });
  for (const value of [1, most]) {
    if (value < 1 || value >= select.options.length) continue;
    scrubTo(start + dt);
    choose('rb-joint', value);
    const joint = player.selectedJoint;
    const at = () => player.controls.target.distanceTo(new THREE.Vector3().setFromMatrixPosition(joint.matrixWorld));
    out.camera_target_m = Math.max(out.camera_target_m, at());
    const before = new THREE.Vector3().setFromMatrixPosition(joint.matrixWorld);
    scrubTo(0.75 * clip.duration);
    key('F');
    out.camera_target_m = Math.max(out.camera_target_m, at());
    out.framed.push({ name: select.options[value].text, object: joint.name, reframe_moved_m: before.distanceTo(new THREE.Vector3().setFromMatrixPosition(joint.matrixWorld)) });
  }
  choose('rb-joint', 0);
  // The floor grid against the skinned meshes' bind-pose geometry (their lowest point in the scene).
  out.grid = !!(player.grid instanceof THREE.GridHelper && player.grid.parent === player.scene);
  if (out.grid) {
    const box = new THREE.Box3();
    for (const state of player.skinnedMeshes) {
      const geometry = state.mesh.geometry;
      if (!geometry.boundingBox) geometry.computeBoundingBox();
      box.union(geometry.boundingBox.clone().applyMatrix4(state.mesh.matrixWorld));
    }
    player.grid.geometry.computeBoundingBox();
    out.grid_y = player.grid.position.y;
    out.grid_size = player.grid.geometry.boundingBox.max.x - player.grid.geometry.boundingBox.min.x;
    out.bind_min_y = box.min.y;
    out.character_height = player.characterHeight;
  }
  // The panel, the heatmap group in it, at two page sizes: nothing wider than its box.
  const root = document.getElementById('rigbake-player') || document.getElementById('rb-panel').parentElement;
  const panel = document.getElementById('rb-panel');
  const heat = document.getElementById('rb-heat-group');
  out.panel = [];
  for (const [width, height] of [[1280, 720], [800, 600]]) {
    root.style.width = `${width}px`;
    root.style.height = `${height}px`;
    out.panel.push({
      width,
      height,
      panel: [panel.scrollWidth, panel.clientWidth],
      heatmap: [heat.scrollWidth, heat.clientWidth],
      fits: panel.scrollWidth <= panel.clientWidth && heat.scrollWidth <= heat.clientWidth,
    });
  }
  root.style.width = '';
  root.style.height = '';
  return out;
}

export async function runSelfTest(player, reference, loadError = null) {
  const started = performance.now();
  const result = { done: false, loaded: !!player && !loadError, errors: captured.errors, warnings: captured.warnings, seconds: {} };
  const stage = (name, run) => {
    const t0 = performance.now();
    try {
      result[name] = run();
    } catch (error) {
      captured.errors.push(`${name}: ${error.name}: ${error.message}`);
    }
    result.seconds[name] = (performance.now() - t0) / 1000;
  };
  if (player && !loadError) {
    player.stop();
    player.playing = false;
    // Two frames of the real render loop first: the page plays by itself.
    await new Promise((resolve) => {
      let frames = 0;
      player.playing = true;
      player.onFrame = () => {
        if (++frames === 2) resolve();
      };
      player.start();
    });
    // The page's load time: from the navigation's start (performance's time origin) to the second frame
    // on screen, i.e. the scripts parsed, the base64 GLB decoded and loaded, the shaders compiled.
    result.seconds.load = performance.now() / 1000;
    player.stop();
    player.playing = false;
    result.file = {
      muscles: player.muscles.length,
      jiggles: player.jiggles.length,
      clips: player.clips.length,
      vertices: player.vertexCount,
      packed: player.hasPacked,
      fileInfluences: player.fileInfluences,
      muscleModes: player.availableMuscleModes(),
      influences: player.availableInfluences(),
    };
    stage('rigger', () => riggerTools(player, reference));
    stage('clips', () => playEveryClip(player));
    stage('modes', () => everyMode(player));
    stage('hit', () => hitTest(player));
    stage('runtime', () => runtimeCost(player));
    stage('sampled', () => sampledAgainstRuntime(player));
    if (reference) {
      stage('matrices', () => compareMatrices(player, reference));
      stage('skinning', () => compareSkinning(player, reference));
      if (reference.capi) stage('capi', () => compareCapiFrames(player, reference.capi));
    }
  }
  result.seconds.total = (performance.now() - started) / 1000;
  result.done = true;
  const pre = document.createElement('pre');
  pre.id = 'rigbake-test-result';
  pre.textContent = JSON.stringify(result);
  document.body.appendChild(pre);
  document.title = 'rigbake-test: done';
}
