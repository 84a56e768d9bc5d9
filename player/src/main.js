// The bundle's entry: esbuild turns this module and three.js into one classic script
// (.tools/player/rigbake-player.js, scripts/install-player.sh) that a page loads from file://.
import { startPage } from './page.js';
import { RigbakePlayer } from './player.js';
import * as rig from './muscle_rig.js';
import * as jiggle from './jiggle.js';

window.RigbakePlayer = { startPage, RigbakePlayer, rig, jiggle };
