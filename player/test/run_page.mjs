// Opens a page in headless Chromium through the DevTools protocol on a pipe (no port, no network),
// waits until the page's title says its self-test is done, and prints one JSON object on stdout:
//   {"result": <the page's <pre id="rigbake-test-result"> parsed>, "console": [...], "exceptions": [...],
//    "log": [...], "title": "...", "seconds": N}
// `console` holds every console message of level error or warning, `exceptions` uncaught exceptions,
// `log` the browser's own error/warning entries (failed loads, blocked requests).
//
// Why not `chromium --dump-dom`: it dumps at the load event, or with --virtual-time-budget when the
// virtual clock runs out, and that clock runs on while a texture decodes on another thread, so a page
// whose glTF has a JPEG (CesiumMan) was dumped before it had loaded. Here the wait is in real time.
//
// Usage: node run_page.mjs CHROMIUM URL [TIMEOUT_SECONDS]
import { spawn } from 'node:child_process';
import { mkdtempSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';

const [chromium, url, timeoutArgument] = process.argv.slice(2);
if (!chromium || !url) {
  console.error('usage: node run_page.mjs CHROMIUM URL [TIMEOUT_SECONDS]');
  process.exit(2);
}
const timeout = Number(timeoutArgument || 120) * 1000;
const profile = mkdtempSync(join(tmpdir(), 'rigbake-chromium-'));
const flags = [
  '--headless', '--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run', '--disable-background-networking',
  '--disable-component-update', '--disable-sync', '--disable-dev-shm-usage', '--enable-unsafe-swiftshader',
  '--remote-debugging-pipe', `--user-data-dir=${profile}`, 'about:blank',
];
const browser = spawn(chromium, flags, { stdio: ['ignore', 'ignore', 'pipe', 'pipe', 'pipe'] });
let stderr = '';
browser.stdio[2].on('data', (chunk) => (stderr = (stderr + chunk).slice(-4000)));
const toBrowser = browser.stdio[3];
const fromBrowser = browser.stdio[4];

let nextId = 1;
const pending = new Map();
const events = [];
let buffer = '';
fromBrowser.on('data', (chunk) => {
  buffer += chunk.toString('utf8');
  let end;
  while ((end = buffer.indexOf('\0')) >= 0) {
    const message = JSON.parse(buffer.slice(0, end));
    buffer = buffer.slice(end + 1);
    if (message.id && pending.has(message.id)) {
      const { resolve, reject } = pending.get(message.id);
      pending.delete(message.id);
      if (message.error) reject(new Error(`${message.error.message} (${message.error.code})`));
      else resolve(message.result);
    } else if (message.method) {
      events.push(message);
    }
  }
});
function send(method, params = {}, sessionId = undefined) {
  const id = nextId++;
  const message = { id, method, params };
  if (sessionId) message.sessionId = sessionId;
  toBrowser.write(`${JSON.stringify(message)}\0`);
  return new Promise((resolve, reject) => pending.set(id, { resolve, reject }));
}
const sleep = (ms) => new Promise((resolve) => setTimeout(resolve, ms));

function describe(args) {
  return (args || []).map((a) => (a.value !== undefined ? String(a.value) : a.description || a.type)).join(' ');
}

async function main() {
  const started = Date.now();
  const { targetId } = await send('Target.createTarget', { url: 'about:blank' });
  const { sessionId } = await send('Target.attachToTarget', { targetId, flatten: true });
  await send('Runtime.enable', {}, sessionId);
  await send('Log.enable', {}, sessionId);
  await send('Page.enable', {}, sessionId);
  await send('Page.navigate', { url }, sessionId);
  let title = '';
  while (Date.now() - started < timeout) {
    await sleep(200);
    const evaluation = await send('Runtime.evaluate', { expression: 'document.title', returnByValue: true }, sessionId);
    title = evaluation.result.value || '';
    if (title.startsWith('rigbake-test: done')) break;
  }
  const text = await send(
    'Runtime.evaluate',
    { expression: "(document.getElementById('rigbake-test-result') || {}).textContent || ''", returnByValue: true },
    sessionId,
  );
  const mine = events.filter((e) => !e.sessionId || e.sessionId === sessionId);
  const output = {
    title,
    seconds: (Date.now() - started) / 1000,
    timedOut: !title.startsWith('rigbake-test: done'),
    result: text.result.value ? JSON.parse(text.result.value) : null,
    console: mine
      .filter((e) => e.method === 'Runtime.consoleAPICalled' && ['error', 'warning', 'assert'].includes(e.params.type))
      .map((e) => `${e.params.type}: ${describe(e.params.args)}`),
    exceptions: mine
      .filter((e) => e.method === 'Runtime.exceptionThrown')
      .map((e) => (e.params.exceptionDetails.exception || {}).description || e.params.exceptionDetails.text),
    log: mine
      .filter((e) => e.method === 'Log.entryAdded' && ['error', 'warning'].includes(e.params.entry.level))
      .map((e) => `${e.params.entry.level} ${e.params.entry.source}: ${e.params.entry.text} ${e.params.entry.url || ''}`.trim()),
  };
  process.stdout.write(`${JSON.stringify(output)}\n`);
  await send('Browser.close').catch(() => {});
}

const killer = setTimeout(() => {
  process.stdout.write(`${JSON.stringify({ timedOut: true, error: 'chromium did not answer', stderr })}\n`);
  browser.kill('SIGKILL');
  process.exit(1);
}, timeout + 30000);
main()
  .catch((error) => {
    process.stdout.write(`${JSON.stringify({ error: error.message, stderr })}\n`);
    process.exitCode = 1;
  })
  .finally(() => {
    clearTimeout(killer);
    setTimeout(() => {
      if (browser.exitCode === null) browser.kill('SIGKILL');
      rmSync(profile, { recursive: true, force: true });
    }, 2000).unref();
  });
browser.on('exit', () => {
  rmSync(profile, { recursive: true, force: true });
});
