// The page `rigbake view` writes: the player, its controls, and the GLB it was given. The page loads
// from file:// with no server and no network: the GLB arrives as base64 in a classic script
// (window.RIGBAKE_MODEL, model.js) because Chromium blocks fetch() and module scripts on file://.
// With ?test=1 the page runs its self-test (self_test.js) and writes the result into the DOM.

import { RigbakePlayer, MUSCLE_MODES, INFLUENCE_COUNTS } from './player.js';
import { installErrorCapture, runSelfTest } from './self_test.js';
import { loadRigbakeRuntime } from '../../runtime/js/rigbake_runtime.mjs';
// The WebAssembly runtime's bytes, bundled into the player script (esbuild's binary loader,
// scripts/install-player.sh): a file:// page cannot fetch the .wasm beside it.
import runtimeWasm from 'rigbake-runtime-wasm';

const HEAT_SCALES = [
  [0.005, '5 mm'],
  [0.01, '1 cm'],
  [0.02, '2 cm'],
  [0.05, '5 cm'],
];

function decodeBase64(text) {
  const binary = atob(text);
  const bytes = new Uint8Array(binary.length);
  for (let i = 0; i < binary.length; ++i) bytes[i] = binary.charCodeAt(i);
  return bytes.buffer;
}

function element(tag, attributes = {}, children = []) {
  const node = document.createElement(tag);
  for (const [key, value] of Object.entries(attributes)) {
    if (key === 'text') node.textContent = value;
    else if (value !== false && value !== undefined) node.setAttribute(key, value === true ? '' : value);
  }
  for (const child of children) node.appendChild(child);
  return node;
}

// A row of radio buttons; onPick(value) when one is chosen.
function radioGroup(name, label, values, labels, onPick) {
  const group = element('fieldset', { class: 'group', id: `rb-${name}` }, [element('legend', { text: label })]);
  values.forEach((value, i) => {
    const input = element('input', { type: 'radio', name: `rb-${name}`, value: String(value), id: `rb-${name}-${value}` });
    input.addEventListener('change', () => input.checked && onPick(value));
    group.appendChild(element('label', { for: input.id }, [input, document.createTextNode(` ${labels[i]}`)]));
  });
  return group;
}

function setRadio(name, value, available) {
  for (const input of document.querySelectorAll(`input[name="rb-${name}"]`)) {
    input.checked = input.value === String(value);
    input.disabled = !available.map(String).includes(input.value);
  }
}

function buildControls(panel, player, title) {
  const clipSelect = element('select', { id: 'rb-clip', 'aria-label': 'clip' });
  player.clips.forEach((clip) => clipSelect.appendChild(element('option', { value: String(clip.index), text: `${clip.name} (${clip.duration.toFixed(2)} s)` })));
  if (!player.clips.length) clipSelect.appendChild(element('option', { value: '0', text: 'no clips: the bind pose' }));
  clipSelect.addEventListener('change', () => player.selectClip(Number(clipSelect.value)));
  const play = element('button', { id: 'rb-play', type: 'button', text: 'Pause' });
  const showPlaying = () => (play.textContent = player.playing ? 'Pause' : 'Play');
  play.addEventListener('click', () => {
    player.playing = !player.playing;
    showPlaying();
  });
  const time = element('span', { id: 'rb-time', class: 'time', text: '0.00 s' });
  // The time scrubber: dragging it pauses and poses the clip at that time (jiggles from rest).
  const scrub = element('input', { type: 'range', id: 'rb-scrub', class: 'scrub', min: '0', max: '1', step: 'any', value: '0', 'aria-label': 'time' });
  scrub.addEventListener('input', () => {
    player.playing = false;
    player.seek(Number(scrub.value));
    showPlaying();
  });
  const prev = element('button', { id: 'rb-prev', type: 'button', text: '◀ frame', title: 'one frame back (,)' });
  const next = element('button', { id: 'rb-next', type: 'button', text: 'frame ▶', title: 'one frame on (.)' });
  prev.addEventListener('click', () => player.step(-1));
  next.addEventListener('click', () => player.step(1));
  // The joint the orbit camera frames: the whole character, a muscle joint, or a skeleton joint.
  const targets = [null];
  const jointSelect = element('select', { id: 'rb-joint', 'aria-label': 'frame joint' }, [element('option', { value: '0', text: 'whole character' })]);
  const addTargets = (label, entries) => {
    if (!entries.length) return;
    const group = element('optgroup', { label });
    for (const [name, object] of entries) {
      group.appendChild(element('option', { value: String(targets.length), text: name }));
      targets.push(object);
    }
    jointSelect.appendChild(group);
  };
  addTargets('Muscles', player.muscles.map((m) => [m.name, m.node]));
  const bones = [];
  for (const state of player.skinnedMeshes) for (const bone of state.mesh.skeleton.bones) if (!bones.includes(bone)) bones.push(bone);
  const muscleNodes = new Set(player.muscles.map((m) => m.node));
  addTargets('Joints', bones.filter((b) => !muscleNodes.has(b)).map((b) => [b.name || `joint ${bones.indexOf(b)}`, b]));
  player.jointTargets = targets; // the self-test reads which object each option frames
  jointSelect.addEventListener('change', () => player.frameJoint(targets[Number(jointSelect.value)]));
  const frameButton = element('button', { id: 'rb-frame', type: 'button', text: 'Frame', title: 'frame the selected joint again (F)' });
  frameButton.addEventListener('click', () => player.reframe());
  // Keys: , and . step a frame, F frames the selected joint again. Not while typing in a text field.
  window.addEventListener('keydown', (event) => {
    if (event.ctrlKey || event.metaKey || event.altKey || (event.target && event.target.tagName === 'TEXTAREA')) return;
    if (event.key === ',') player.step(-1);
    else if (event.key === '.') player.step(1);
    else if (event.key === 'f' || event.key === 'F') player.reframe();
    else return;
    showPlaying();
    event.preventDefault();
  });
  const muscles = radioGroup('muscles', 'Muscles', MUSCLE_MODES, ['runtime', 'sampled', 'off'], (mode) => player.setMuscleMode(mode));
  const influences = radioGroup('influences', 'Influences', INFLUENCE_COUNTS, ['4', '7', '10'], (n) => player.setInfluences(n));
  const heat = element('input', { type: 'checkbox', id: 'rb-heatmap' });
  const heatScale = element('select', { id: 'rb-heat-scale', 'aria-label': 'heatmap full scale' });
  HEAT_SCALES.forEach(([value, text]) => heatScale.appendChild(element('option', { value: String(value), text })));
  heatScale.value = String(player.heatScale);
  heat.addEventListener('change', () => player.setHeatmap(heat.checked, Number(heatScale.value)));
  heatScale.addEventListener('change', () => player.setHeatmap(heat.checked, Number(heatScale.value)));
  const legend = element('span', { class: 'legend', id: 'rb-legend' });
  // Short label, the explanation below it: the group must fit the 320 px panel (no sideways scroll).
  const heatGroup = element('fieldset', { class: 'group', id: 'rb-heat-group' }, [
    element('legend', { text: 'Heatmap' }),
    element('label', { for: 'rb-heatmap' }, [heat, document.createTextNode(' on, red at ')]),
    heatScale,
    element('div', { class: 'note', text: 'displacement against plain skinning (muscles at rest)' }),
    legend,
  ]);
  const hit = element('button', { id: 'rb-hit', type: 'button', text: 'Hit' });
  hit.addEventListener('click', () => player.hit());
  const info = element('p', { id: 'rb-info', class: 'info' });
  panel.append(
    element('h1', { text: title }),
    element('div', { class: 'row' }, [clipSelect, play]),
    element('div', { class: 'row' }, [scrub, time]),
    element('div', { class: 'row' }, [prev, next, element('span', { id: 'rb-step', class: 'note' })]),
    element('div', { class: 'row' }, [jointSelect, frameButton]),
    muscles,
    influences,
    heatGroup,
    element('div', { class: 'row' }, [hit, element('span', { id: 'rb-hit-note', class: 'note' })]),
    info,
  );
  const update = () => {
    setRadio('muscles', player.muscleMode, player.availableMuscleModes());
    setRadio('influences', player.influences, player.availableInfluences());
    clipSelect.value = String(player.clipIndex);
    const clip = player.clips[player.clipIndex];
    scrub.max = String(clip ? clip.duration : 0);
    scrub.disabled = prev.disabled = next.disabled = !clip;
    document.getElementById('rb-step').textContent = clip ? `, and . keys: ${(1 / player.frameStep()).toFixed(3).replace(/\.?0+$/, '')} fps` : '';
    showPlaying();
    const liveJiggles = player.jiggles.length;
    hit.disabled = !liveJiggles || player.muscleMode !== 'runtime';
    document.getElementById('rb-hit-note').textContent = !liveJiggles
      ? 'the file has no jiggles (bake with --jiggle)'
      : player.muscleMode !== 'runtime'
        ? 'jiggles run live with muscles: runtime'
        : `kicks ${liveJiggles} jiggle${liveJiggles > 1 ? 's' : ''} at 1.5 m/s, away from the camera`;
    legend.textContent = player.heatmap ? ' blue 0, green half, red full scale' : '';
    info.textContent =
      `${player.muscles.length} muscles (${player.rig ? 'RIGBAKE_muscle_rig' : 'no rig extension'}), ${liveJiggles} jiggles, ` +
      `${player.vertexCount} skinned vertices, ${player.hasPacked ? `${player.fileInfluences} packed influences` : 'no packed influences'}, ` +
      `${player.clips.length} clips. Influences 4 = three.js's own skinning of JOINTS_0/WEIGHTS_0; 7 and 10 = the packed 0.001 weights in rigbake's shader.`;
  };
  player.onChange(update);
  player.onFrame = () => {
    time.textContent = `${player.time.toFixed(2)} s`;
    scrub.value = String(player.time);
  };
  update();
}

// Starts the page: `root` holds the panel and the viewport. options.title names the file.
export async function startPage(root, options = {}) {
  const test = new URLSearchParams(location.search).get('test') === '1';
  if (test) installErrorCapture();
  const panel = element('div', { class: 'panel', id: 'rb-panel' });
  const viewport = element('div', { class: 'viewport', id: 'rb-viewport' });
  const status = element('p', { id: 'rb-status', class: 'status', text: 'loading…' });
  root.append(panel, viewport);
  panel.appendChild(status);
  try {
    if (typeof window.RIGBAKE_MODEL !== 'string') throw new Error('model.js did not load: the page needs the model.js file written beside it');
    const runtime = await loadRigbakeRuntime(runtimeWasm);
    // Draco's decoder files come as a script of their own beside a Draco file's page (rigbake-draco.js).
    const draco = window.RIGBAKE_DRACO ? { wrapper: window.RIGBAKE_DRACO.wrapper, wasm: decodeBase64(window.RIGBAKE_DRACO.wasm) } : null;
    const size = test ? { width: 320, height: 240, preserveDrawingBuffer: true } : {};
    const player = new RigbakePlayer(viewport, { runtime, draco, ...size });
    window.rigbakePlayer = player;
    await player.load(decodeBase64(window.RIGBAKE_MODEL));
    status.remove();
    buildControls(panel, player, options.title || 'rigbake view');
    player.frameCamera();
    if (!test) window.addEventListener('resize', () => player.resize());
    player.start();
    if (test) await runSelfTest(player, window.RIGBAKE_REFERENCE || null);
  } catch (error) {
    status.textContent = `The player could not start: ${error.message}`;
    status.className = 'status error';
    console.error(error);
    if (test) await runSelfTest(null, null, error);
  }
}
