// The bundle's entry: esbuild turns this module, the rigbake-three plugin (player/plugin/), the
// WebAssembly runtime (its ES module and its .wasm bytes) and three.js into one classic script
// (.tools/player/rigbake-player.js, scripts/install-player.sh) that a page loads from file://.
import { startPage } from './page.js';
import { RigbakePlayer } from './player.js';
import * as plugin from '../plugin/src/index.js';

window.RigbakePlayer = { startPage, RigbakePlayer, plugin };
