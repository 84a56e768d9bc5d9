// rigbake's config for the glTF-Transform CLI (docs/pipelines.md):
//
//   gltf-transform optimize baked.glb out.glb --config path/to/rigbake.config.mjs
//
// keeps the RIGBAKE_muscle_rig extension (rigbake-muscle-rig.mjs) and every skin influence exactly as
// read (JOINTS_n/WEIGHTS_n of all sets; the _RIGBAKE_PACKED_* attributes glTF-Transform keeps by
// itself). The CLI replaces its extension list with the config's, so the list is the CLI's own
// ALL_EXTENSIONS (meshopt, Draco, ...) plus RIGBAKE_muscle_rig.
//
// The classes must extend the glTF-Transform that runs this file, not another copy of it: the config
// imports @gltf-transform/core and @gltf-transform/extensions from the installation of the CLI that
// loaded it (process.argv[1] is its bin script), so it works wherever this folder lies. Run from
// anything else (a script importing this file), it imports them the ordinary way.
import { readFileSync, realpathSync } from 'node:fs';
import { createRequire } from 'node:module';
import { dirname, join } from 'node:path';
import { pathToFileURL } from 'node:url';

import { defineRigbakeMuscleRig, holdSkinInfluences, restoreSkinInfluences } from './rigbake-muscle-rig.mjs';

// The directory of package `name` as the module at `fromFile` resolves it, or null.
function packageDirectory(name, fromFile) {
  let resolved;
  try {
    resolved = createRequire(fromFile).resolve(name);
  } catch {
    return null;
  }
  for (let dir = dirname(resolved); dir !== dirname(dir); dir = dirname(dir)) {
    try {
      if (JSON.parse(readFileSync(join(dir, 'package.json'), 'utf8')).name === name) return dir;
    } catch {
      // no package.json here: keep climbing
    }
  }
  return null;
}

// The ES module entry of `name` (its exports' "import"/"default" condition, as the CLI's own
// `import` resolves it), from the CLI that runs this config, else an ordinary import.
async function importBesideCli(name) {
  let cli = null;
  try {
    cli = process.argv[1] ? realpathSync(process.argv[1]) : null;
  } catch {
    cli = null;
  }
  const dir = cli && cli.includes(`${join('@gltf-transform', 'cli')}`) ? packageDirectory(name, cli) : null;
  if (!dir) return import(name);
  const pkg = JSON.parse(readFileSync(join(dir, 'package.json'), 'utf8'));
  const exported = typeof pkg.exports === 'object' ? pkg.exports.import || pkg.exports.default : pkg.exports;
  const entry = typeof exported === 'string' ? exported : pkg.module || pkg.main;
  return import(pathToFileURL(join(dir, entry)).href);
}

const core = await importBesideCli('@gltf-transform/core');
const { ALL_EXTENSIONS } = await importBesideCli('@gltf-transform/extensions');
const { RigbakeMuscleRig } = defineRigbakeMuscleRig(core);

export { RigbakeMuscleRig };

export default {
  extensions: [...ALL_EXTENSIONS, RigbakeMuscleRig],
  // Every CLI command reads through io.read and writes through io.write (its Session): the influences
  // are held right after reading and put back right before writing, whatever the command did between.
  onProgramReady: async ({ io }) => {
    const read = io.read.bind(io);
    const write = io.write.bind(io);
    io.read = async (...args) => holdSkinInfluences(await read(...args));
    io.write = async (uri, document, ...rest) => {
      restoreSkinInfluences(document);
      return write(uri, document, ...rest);
    };
  },
};
