// rigbake-three: plays rigbake bakes in any three.js app. Register the plugin with GLTFLoader and every
// loaded file gets its RIGBAKE_muscle_rig muscles and jiggles evaluated each frame by the WebAssembly
// runtime (gltf.userData.rigbake.update(dt) after the mixer), and its 7 or 10 packed influences
// (docs/packed-influences.md) skinned in the mesh's own shader. README.md has the ten-line example.

import { RigbakeRig } from './rig.js';
import { prepareSkinning } from './skinning.js';

export { RigbakeRig, nodeObjects, MAX_JIGGLE_STEPS } from './rig.js';
export { prepareSkinning, applySkinningState, readBackSkinning, makeBoneTexture, packedLayout } from './skinning.js';

export const EXTENSION_NAME = 'RIGBAKE_muscle_rig';

export class RigbakeMuscleRigPlugin {
  // parser: GLTFLoader's; runtime: what loadRigbakeRuntime() (rigbake_runtime.mjs) resolved to, one per
  // page, shared by every file. options.skinning = false leaves the materials alone.
  constructor(parser, runtime, options = {}) {
    if (!runtime || typeof runtime.createRig !== 'function')
      throw new Error('RigbakeMuscleRigPlugin needs the rigbake runtime: await loadRigbakeRuntime() from rigbake_runtime.mjs');
    this.name = EXTENSION_NAME;
    this.parser = parser;
    this.runtime = runtime;
    this.options = options;
  }

  // After the scene is built: packed skinning on every skinned mesh that carries it, and the rig as
  // gltf.userData.rigbake (null when the file has no RIGBAKE_muscle_rig).
  afterRoot(gltf) {
    if (this.options.skinning !== false) {
      gltf.scene.traverse((object) => {
        if (object.isSkinnedMesh) {
          object.frustumCulled = false; // muscles move the skin beyond the bind pose's bounds
          prepareSkinning(object);
        }
      });
    }
    const extension = (this.parser.json.extensions || {})[EXTENSION_NAME];
    gltf.userData.rigbake = extension ? new RigbakeRig(gltf, this.runtime, extension) : null;
    return null;
  }
}
