// RIGBAKE_muscle_rig for glTF-Transform (https://gltf-transform.dev, "Custom extensions"): reads the
// extension of docs/extensions/RIGBAKE_muscle_rig.md into the document's property graph and writes it
// back, so that glTF-Transform's transforms and its CLI (`--config rigbake.config.mjs`) keep the rig.
//
// The extension is one object on the glTF root. Its node references (every muscle's skinnedNode,
// originNode, insertionNode, carrierNode and helperNodes; every jiggle's node, rootNode and parentNode
// unless -1) become edges to the document's Node properties, so that prune, flatten, dedup and the
// writer's reordering carry them: a written file names the nodes by their new indices. Every other
// property is kept as read. A transform that removes a node the rig names makes the write fail with the
// muscle's name rather than write a rig that points elsewhere.
//
// Skin influences: glTF-Transform's `quantize` (run by `optimize` and `meshopt`) stores WEIGHTS_n in 8
// bits and re-sorts the slots, which cuts 0.001 weights to 1/255 steps and empties the smallest ones:
// the packed buffers (docs/packed-influences.md) and the glTF weights then disagree by up to 1.5 mm.
// holdSkinInfluences() copies every JOINTS_n/WEIGHTS_n into a private vertex attribute that every
// transform carries like any other (weld, simplify, join and reorder move its vertices with the rest,
// quantize at its default level leaves attributes starting with "_" alone), and restoreSkinInfluences()
// puts the copies back, exactly as read, before the file is written.
//
// The module imports nothing: defineRigbakeMuscleRig() takes the @gltf-transform/core module to build
// on, so the classes extend the very Extension class of the glTF-Transform that runs them (the CLI's
// own copy when the config loads it; docs/pipelines.md).

export const RIGBAKE_MUSCLE_RIG = 'RIGBAKE_muscle_rig';
export const RIGBAKE_MUSCLE_RIG_VERSION = 1;

const MUSCLE_NODE_FIELDS = ['skinnedNode', 'originNode', 'insertionNode', 'carrierNode'];
const JIGGLE_NODE_FIELDS = ['node', 'parentNode', 'rootNode'];
const HELD_PREFIX = '_RIGBAKE_HELD_';
const INFLUENCE_SEMANTIC = /^(JOINTS|WEIGHTS)_\d+$/;
const ROOT_PROPERTY_TYPE = 'Root';  // core's PropertyType.ROOT
const FLOAT = 5126;  // core's Accessor.ComponentType.FLOAT

// Calls visit(owner, field, key) for every place of the extension object that can hold a node index.
// key names the place ("muscles/3/helperNodes/1"), which stays the same when indices change.
function forEachNodeField(rigDef, visit) {
  (rigDef.muscles || []).forEach((muscle, m) => {
    for (const field of MUSCLE_NODE_FIELDS) visit(muscle, field, `muscles/${m}/${field}`);
    if (Array.isArray(muscle.helperNodes)) {
      muscle.helperNodes.forEach((_, h) => visit(muscle.helperNodes, h, `muscles/${m}/helperNodes/${h}`));
    }
  });
  (rigDef.jiggles || []).forEach((jiggle, j) => {
    for (const field of JIGGLE_NODE_FIELDS) visit(jiggle, field, `jiggles/${j}/${field}`);
  });
}

// The muscle (or jiggle) a node place belongs to, for messages: "muscles/3 (LeftBicep)".
function describePlace(rigDef, key) {
  const [list, index] = key.split('/');
  const item = (rigDef[list] || [])[Number(index)];
  return `${list}/${index}${item && item.name ? ` (${item.name})` : ''}`;
}

export function defineRigbakeMuscleRig(core) {
  const { Extension, ExtensionProperty, PropertyType, RefMap } = core;

  // The rig: the extension object as read, with null where it named a node, and one edge per node.
  class MuscleRig extends ExtensionProperty {
    init() {
      this.extensionName = RIGBAKE_MUSCLE_RIG;
      this.propertyType = 'RigbakeMuscleRig';
      this.parentTypes = [PropertyType.ROOT];
    }

    getDefaults() {
      return Object.assign(super.getDefaults(), { definition: {}, nodes: new RefMap() });
    }

    // The extension object without its node indices (null in their places).
    getDefinition() {
      return structuredClone(this.get('definition'));
    }

    setDefinition(definition) {
      return this.set('definition', structuredClone(definition));
    }

    getNode(key) {
      return this.getRefMap('nodes', key);
    }

    setNode(key, node) {
      return this.setRefMap('nodes', key, node);
    }

    listNodeKeys() {
      return this.listRefMapKeys('nodes');
    }
  }

  class RigbakeMuscleRig extends Extension {
    static EXTENSION_NAME = RIGBAKE_MUSCLE_RIG;
    extensionName = RIGBAKE_MUSCLE_RIG;

    createMuscleRig() {
      return new MuscleRig(this.document.getGraph());
    }

    read(context) {
      const rigDef = context.jsonDoc.json.extensions?.[RIGBAKE_MUSCLE_RIG];
      if (!rigDef) return this;
      if (rigDef.version !== RIGBAKE_MUSCLE_RIG_VERSION) {
        throw new Error(
          `${RIGBAKE_MUSCLE_RIG}: version ${rigDef.version} is not ${RIGBAKE_MUSCLE_RIG_VERSION}, the layout this ` +
            'extension knows; refusing to carry node references it cannot find',
        );
      }
      const definition = structuredClone(rigDef);
      const rig = this.createMuscleRig();
      forEachNodeField(definition, (owner, field, key) => {
        const index = owner[field];
        if (index === undefined || index === -1) return;  // absent, or a root jiggle's parentNode
        const node = Number.isInteger(index) ? context.nodes[index] : undefined;
        if (!node) throw new Error(`${RIGBAKE_MUSCLE_RIG}: ${key} is ${JSON.stringify(index)}, not a node of the file`);
        rig.setNode(key, node);
        owner[field] = null;
      });
      rig.setDefinition(definition);
      this.document.getRoot().setExtension(RIGBAKE_MUSCLE_RIG, rig);
      return this;
    }

    write(context) {
      const rig = this.document.getRoot().getExtension(RIGBAKE_MUSCLE_RIG);
      if (!rig) return this;
      const rigDef = rig.getDefinition();
      forEachNodeField(rigDef, (owner, field, key) => {
        if (owner[field] !== null) return;
        const node = rig.getNode(key);
        const index = node ? context.nodeIndexMap.get(node) : undefined;
        if (index === undefined) {
          throw new Error(
            `${RIGBAKE_MUSCLE_RIG}: ${describePlace(rigDef, key)} ${key.split('/').slice(2).join('/')}: its node ` +
              'was removed by a transform; the rig would name the wrong joint, so nothing is written',
          );
        }
        owner[field] = index;
      });
      const { json } = context.jsonDoc;
      json.extensions = json.extensions || {};
      json.extensions[RIGBAKE_MUSCLE_RIG] = rigDef;
      return this;
    }
  }

  return { RigbakeMuscleRig, MuscleRig };
}

// Copies every JOINTS_n/WEIGHTS_n of every primitive into _RIGBAKE_HELD_JOINTS_n/_RIGBAKE_HELD_WEIGHTS_n
// (raw integers, not normalized, so that no quantizer reads them as [0, 1] values). Call it after
// reading, before any transform.
export function holdSkinInfluences(document) {
  for (const mesh of document.getRoot().listMeshes()) {
    for (const prim of mesh.listPrimitives()) {
      for (const semantic of prim.listSemantics()) {
        if (!INFLUENCE_SEMANTIC.test(semantic) || prim.getAttribute(HELD_PREFIX + semantic)) continue;
        const source = prim.getAttribute(semantic);
        prim.setAttribute(HELD_PREFIX + semantic, source.clone().setNormalized(false).setSparse(false));
      }
    }
  }
  return document;
}

// Puts the held JOINTS_n/WEIGHTS_n back in place of whatever the transforms left there and removes the
// copies. Call it after the last transform, before writing. Returns the number of primitives restored.
export function restoreSkinInfluences(document) {
  let restored = 0;
  for (const mesh of document.getRoot().listMeshes()) {
    for (const prim of mesh.listPrimitives()) {
      const held = prim.listSemantics().filter((semantic) => semantic.startsWith(HELD_PREFIX));
      if (held.length === 0) continue;
      const replaced = [];
      for (const semantic of prim.listSemantics()) {
        if (!INFLUENCE_SEMANTIC.test(semantic)) continue;
        replaced.push(prim.getAttribute(semantic));
        prim.setAttribute(semantic, null);
      }
      for (const semantic of held) {
        const accessor = prim.getAttribute(semantic);
        const original = semantic.slice(HELD_PREFIX.length);
        prim.setAttribute(semantic, null);
        // glTF 2.0 3.7.3.3: integer WEIGHTS_n are normalized, JOINTS_n never are.
        const normalized = original.startsWith('WEIGHTS_') && accessor.getComponentType() !== FLOAT;
        // Not sparse: glTF-Transform 4.3.0 writes the values of a sparse normalized accessor as the
        // integer part of its [0, 1] values, i.e. 0 (optimize's `sparse` step marks mostly-zero WEIGHTS_1).
        prim.setAttribute(original, accessor.setNormalized(normalized).setSparse(false));
      }
      for (const accessor of replaced) {
        if (accessor.listParents().every((parent) => parent.propertyType === ROOT_PROPERTY_TYPE)) accessor.dispose();
      }
      restored++;
    }
  }
  return restored;
}
