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
// holdSkinInfluences() copies every JOINTS_n/WEIGHTS_n and packed attribute into a private vertex
// attribute that every transform carries like any other (weld, simplify, join and reorder move its
// vertices with the rest; its values are kept where no quantizer or in-place sort reaches them), and
// restoreSkinInfluences() puts the copies back, exactly as read, before the file is written.
//
// The module imports nothing: defineRigbakeMuscleRig() takes the @gltf-transform/core module to build
// on, so the classes extend the very Extension class of the glTF-Transform that runs them (the CLI's
// own copy when the config loads it; docs/pipelines.md).

export const RIGBAKE_MUSCLE_RIG = 'RIGBAKE_muscle_rig';
export const RIGBAKE_MUSCLE_RIG_VERSION = 1;

const MUSCLE_NODE_FIELDS = ['skinnedNode', 'originNode', 'insertionNode', 'carrierNode'];
const JIGGLE_NODE_FIELDS = ['node', 'parentNode', 'rootNode'];
const HELD_PREFIX = '_RIGBAKE_HELD_';
// The attributes held across transforms: the glTF influences and the packed ones (docs/packed-influences.md).
const HELD_SEMANTIC = /^((JOINTS|WEIGHTS)_\d+|_RIGBAKE_PACKED_\w+)$/;
const HELD_NAME = /^_RIGBAKE_HELD_(\d+)(N?)_(.+)$/;
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

// Copies every JOINTS_n/WEIGHTS_n and _RIGBAKE_PACKED_* attribute of every primitive into a private
// one, _RIGBAKE_HELD_<component type>[N]_<semantic> (N: the source was normalized). Call it after
// reading, before any transform.
//
// An integer attribute is held as FLOAT values + 0.5: exact (at most 16 bits), outside [-1, 1] so that
// no quantizer touches it (an all-zero one that is quantized still rounds back to 0), and equal to no
// live attribute. The last matters: `dedup` merges accessors of equal content, and `quantize` re-sorts
// JOINTS_n in place (sortPrimitiveWeights, after storing the weights in 8 bits, where two weights
// 1/65535 apart tie and its comparator swaps them). A copy of equal content would be that same
// accessor, re-sorted with it, and so would _RIGBAKE_PACKED_JOINTS_0, whose content is JOINTS_0's:
// measured on CesiumMan through `optimize`, 12 mm between the packed and the glTF weights. A float
// attribute (float weights) is held as a plain copy: quantize replaces float weights with a new
// accessor before it sorts, so no transform writes into the old one.
export function holdSkinInfluences(document) {
  for (const mesh of document.getRoot().listMeshes()) {
    for (const prim of mesh.listPrimitives()) {
      for (const semantic of prim.listSemantics()) {
        if (!HELD_SEMANTIC.test(semantic) || prim.listSemantics().some((s) => (HELD_NAME.exec(s) || [])[3] === semantic)) continue;
        const source = prim.getAttribute(semantic);
        const type = source.getComponentType();
        let held;
        if (type === FLOAT) {
          held = source.clone().setNormalized(false).setSparse(false);
        } else {
          held = document.createAccessor()
            .setType(source.getType())
            .setArray(Float32Array.from(source.getArray(), (value) => value + 0.5))
            .setBuffer(source.getBuffer());
        }
        prim.setAttribute(`${HELD_PREFIX}${type}${source.getNormalized() ? 'N' : ''}_${semantic}`, held);
      }
    }
  }
  return document;
}

const INTEGER_ARRAYS = { 5120: Int8Array, 5121: Uint8Array, 5122: Int16Array, 5123: Uint16Array, 5125: Uint32Array };

// Disposes `accessor` when nothing but the document root holds it any more.
function disposeIfUnused(accessor) {
  if (accessor.listParents().every((parent) => parent.propertyType === ROOT_PROPERTY_TYPE)) accessor.dispose();
}

// Puts the held attributes back in place of whatever the transforms left there, in their own component
// type, and removes the copies. Call it after the last transform, before writing. Returns the number
// of primitives restored.
export function restoreSkinInfluences(document) {
  let restored = 0;
  for (const mesh of document.getRoot().listMeshes()) {
    for (const prim of mesh.listPrimitives()) {
      const held = prim.listSemantics().filter((semantic) => semantic.startsWith(HELD_PREFIX));
      if (held.length === 0) continue;
      const replaced = [];
      for (const semantic of prim.listSemantics()) {
        if (!HELD_SEMANTIC.test(semantic)) continue;
        replaced.push(prim.getAttribute(semantic));
        prim.setAttribute(semantic, null);
      }
      for (const semantic of held) {
        const [, typeText, normalizedMark, original] = HELD_NAME.exec(semantic);
        const type = Number(typeText);
        const accessor = prim.getAttribute(semantic);
        prim.setAttribute(semantic, null);
        let restoredAccessor = accessor;
        if (type !== FLOAT) {
          // getElement() reads a quantized (normalized) copy as its values, so an all-zero attribute
          // that quantize stored in 12 bits rounds back to 0 like any other.
          const count = accessor.getCount();
          const size = accessor.getElementSize();
          const values = new INTEGER_ARRAYS[type](count * size);
          const element = [];
          for (let i = 0; i < count; i++) {
            accessor.getElement(i, element);
            for (let k = 0; k < size; k++) values[i * size + k] = Math.round(element[k] - 0.5);
          }
          restoredAccessor = document.createAccessor(accessor.getName())
            .setType(accessor.getType())
            .setArray(values)
            .setBuffer(accessor.getBuffer());
          disposeIfUnused(accessor);
        }
        // Not sparse: glTF-Transform 4.3.0 writes the values of a sparse normalized accessor as the
        // integer part of its [0, 1] values, i.e. 0 (optimize's `sparse` step marks mostly-zero WEIGHTS_1).
        prim.setAttribute(original, restoredAccessor.setNormalized(normalizedMark === 'N').setSparse(false));
      }
      for (const accessor of replaced) disposeIfUnused(accessor);
      restored++;
    }
  }
  return restored;
}
