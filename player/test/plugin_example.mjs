// The plugin's README example as a plain three.js page: ES modules from an import map, the ten lines
// of player/plugin/README.md verbatim, served over http from 127.0.0.1 (module pages need an origin;
// file:// refuses them), opened in headless Chromium by run_page.mjs. The page plays the clip for a
// second of rendered frames and writes what it saw: the rig's counts, how far the muscle joints moved
// from their rest on the carrier, the packed influences the materials skin, and the largest jiggle.
//
// Usage: node plugin_example.mjs CHROMIUM THREE_DIR WASM_DIR BAKED.glb [TIMEOUT_SECONDS]
//   THREE_DIR: the three package (node_modules/three), WASM_DIR: scripts/build-wasm.sh's output.
import { spawn } from 'node:child_process';
import fs from 'node:fs';
import http from 'node:http';
import path from 'node:path';
import { fileURLToPath } from 'node:url';

const [chromium, threeDir, wasmDir, glb, timeout = '120'] = process.argv.slice(2);
const here = path.dirname(fileURLToPath(import.meta.url));
const pluginDir = path.join(here, '..', 'plugin');

// The README's code block, run as written (scene, camera and renderer are the page's own).
const readme = fs.readFileSync(path.join(pluginDir, 'README.md'), 'utf8');
const example = readme.match(/## Ten lines[\s\S]*?```js\n([\s\S]*?)```/)[1].replace("'baked.glb'", "'/baked.glb'");
const lines = example.trim().split('\n');
if (lines.length > 10) throw new Error(`the README example has ${lines.length} lines, not ten`);

// Three scripts: a classic one records errors first; the example module (the README's lines after a
// prelude that makes the scene, camera and renderer, using the THREE the example imports: imports are
// hoisted); a probe module that waits for it, plays a second, and writes the result.
const page = `<!doctype html><html><head><meta charset="utf-8"><title>rigbake-three example</title>
<script type="importmap">{"imports": {"three": "/three/build/three.module.js", "three/addons/": "/three/examples/jsm/",
  "rigbake-three": "/plugin/src/index.js"}}</script>
<script>
window.exampleErrors = [];
window.addEventListener('error', (e) => window.exampleErrors.push(String(e.message)));
window.addEventListener('unhandledrejection', (e) => window.exampleErrors.push(String((e.reason && e.reason.stack) || e.reason)));
</script></head><body>
<script type="module">
const scene = new THREE.Scene();
const camera = new THREE.PerspectiveCamera(35, 4 / 3, 0.01, 100);
camera.position.set(0, 1, 4);
const renderer = new THREE.WebGLRenderer();
renderer.setSize(320, 240);
document.body.appendChild(renderer.domElement);
${example}
window.example = { gltf, renderer, mixer };
</script>
<script type="module">
import { Matrix4 } from 'three';
const started = performance.now();
while (!window.example && !window.exampleErrors.length && performance.now() - started < 60000) await new Promise((r) => setTimeout(r, 50));
let result = { errors: window.exampleErrors };
if (window.example) {
  // A second and a half of the example's own frames, looked at every 50 ms: how far the muscle joints
  // moved from rest (their translation against the carrier's K) and the largest jiggle.
  const { gltf, renderer } = window.example;
  const rig = gltf.userData.rigbake;
  const stored = gltf.parser.json.extensions.RIGBAKE_muscle_rig.muscles;
  let moved = 0;
  let jiggle = 0;
  for (let look = 0; look < 30; ++look) {
    await new Promise((resolve) => setTimeout(resolve, 50));
    rig.muscles.forEach((muscle, m) => {
      const rest = new Matrix4().fromArray(stored[m].skinnedInCarrier).elements;
      for (let k = 12; k < 15; ++k) moved = Math.max(moved, Math.abs(muscle.node.matrix.elements[k] - rest[k]));
    });
    jiggle = Math.max(jiggle, ...rig.jiggles.map((j) => (j.angle * 180) / Math.PI));
  }
  const influences = [];
  gltf.scene.traverse((o) => o.isSkinnedMesh && influences.push(o.userData.rigbakeSkinning.influences));
  result = { lines: ${lines.length}, time: window.example.mixer.time, muscles: rig.muscles.length, jiggles: rig.jiggles.length, moved_m: moved, influences,
    largest_jiggle_deg: jiggle, glError: renderer.getContext().getError(),
    errors: window.exampleErrors };
  renderer.setAnimationLoop(null);
}
const pre = document.createElement('pre');
pre.id = 'rigbake-test-result';
pre.textContent = JSON.stringify(result);
document.body.appendChild(pre);
document.title = 'rigbake-test: done';
</script></body></html>`;

const routes = [
  ['/three/', threeDir],
  ['/plugin/', pluginDir],
];
const types = { '.js': 'text/javascript', '.mjs': 'text/javascript', '.wasm': 'application/wasm', '.glb': 'model/gltf-binary', '.html': 'text/html' };
const server = http.createServer((request, response) => {
  const url = decodeURIComponent(new URL(request.url, 'http://localhost').pathname);
  let file = null;
  if (url === '/' || url === '/index.html') {
    response.writeHead(200, { 'content-type': 'text/html' });
    return response.end(page);
  }
  if (url === '/baked.glb') file = glb;
  else if (url === '/rigbake_runtime.mjs' || url === '/rigbake_runtime.wasm') file = path.join(wasmDir, url.slice(1));
  for (const [prefix, dir] of routes) if (url.startsWith(prefix)) file = path.join(dir, url.slice(prefix.length));
  if (!file || url.includes('..') || !fs.existsSync(file) || !fs.statSync(file).isFile()) {
    response.writeHead(404);
    return response.end();
  }
  response.writeHead(200, { 'content-type': types[path.extname(file)] || 'application/octet-stream' });
  fs.createReadStream(file).pipe(response);
});
server.listen(0, '127.0.0.1', () => {
  const { port } = server.address();
  const runner = spawn(process.execPath, [path.join(here, 'run_page.mjs'), chromium, `http://127.0.0.1:${port}/`, timeout], {
    stdio: ['ignore', 'inherit', 'inherit'],
  });
  runner.on('exit', (code) => {
    server.close();
    process.exit(code ?? 1);
  });
});
