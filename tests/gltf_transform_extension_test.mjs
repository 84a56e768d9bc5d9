// gltf-transform/rigbake-muscle-rig.mjs through glTF-Transform's own API (docs/pipelines.md), on a
// bake of the mannequin with helper joints and jiggles:
// - every node reference of RIGBAKE_muscle_rig is an edge to the joint it names, and a written file names
//   the same joints after transforms that renumber nodes;
// - a transform that removes a joint the rig names makes the write fail, naming the muscle;
// - another extension version is refused when read;
// - quantize() stores WEIGHTS_n in 8 bits, and holdSkinInfluences()/restoreSkinInfluences() around it
//   give back every JOINTS_n/WEIGHTS_n exactly as read, and the packed attributes too after dedup()
//   made them one accessor with the JOINTS_n quantize re-sorts in place.
// Usage: node gltf_transform_extension_test.mjs SOURCE_DIR RIGBAKE_BINARY. Exit 77 (ctest: skipped) when
// glTF-Transform is not installed, 1 instead under CI=true.
import assert from 'node:assert/strict';
import { execFileSync } from 'node:child_process';
import { existsSync, mkdtempSync, rmSync, symlinkSync, writeFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { pathToFileURL } from 'node:url';

const [sourceDir, rigbake] = process.argv.slice(2);
const modules = process.env.RIGBAKE_GLTF_TRANSFORM_MODULES || join(sourceDir, '.tools/gltf-transform/node_modules');
if (!existsSync(join(modules, '@gltf-transform/core'))) {
  console.error(`glTF-Transform is not installed in ${modules} (run scripts/install-gltf-transform.sh)`);
  process.exit(process.env.CI === 'true' ? 1 : 77);
}

const work = mkdtempSync(join(tmpdir(), 'rigbake-gltf-transform-'));
try {
  // Import glTF-Transform as an installed package would be: from a module beside its node_modules.
  symlinkSync(modules, join(work, 'node_modules'));
  writeFileSync(
    join(work, 'packages.mjs'),
    "export * as core from '@gltf-transform/core';\n" +
      "export { ALL_EXTENSIONS } from '@gltf-transform/extensions';\n" +
      "export * as functions from '@gltf-transform/functions';\n",
  );
  const { core, ALL_EXTENSIONS, functions } = await import(pathToFileURL(join(work, 'packages.mjs')).href);
  const rig = await import(pathToFileURL(join(sourceDir, 'gltf-transform/rigbake-muscle-rig.mjs')).href);
  const { RigbakeMuscleRig } = rig.defineRigbakeMuscleRig(core);
  const io = new core.NodeIO().registerExtensions([...ALL_EXTENSIONS, RigbakeMuscleRig]);

  const sample = join(work, 'sample.glb');
  const baked = join(work, 'baked.glb');
  execFileSync(rigbake, ['sample', '-o', sample], { stdio: 'pipe' });
  execFileSync(rigbake, ['bake', sample, '--influences', '10', '--helper-joints', '--jiggle', 'biceps', '-o', baked], {
    stdio: 'pipe',
  });

  // Node names of every reference, by place, from a written file's JSON.
  const referencedNames = (json) => {
    const def = json.extensions[rig.RIGBAKE_MUSCLE_RIG];
    const name = (index) => (index < 0 ? '-1' : json.nodes[index].name);
    const names = [];
    for (const m of def.muscles) {
      names.push(...['skinnedNode', 'originNode', 'insertionNode', 'carrierNode'].map((f) => name(m[f])));
      names.push(...(m.helperNodes || []).map(name));
    }
    for (const j of def.jiggles || []) names.push(name(j.node), name(j.parentNode), name(j.rootNode));
    return names;
  };
  const bakedJson = (await io.readAsJSON(baked)).json;
  const expected = referencedNames(bakedJson);
  const muscles = bakedJson.extensions[rig.RIGBAKE_MUSCLE_RIG].muscles.length;
  const jiggles = bakedJson.extensions[rig.RIGBAKE_MUSCLE_RIG].jiggles.length;
  assert.equal(muscles, 38);
  assert.equal(jiggles, 2);

  // Edges: 4 joints and 3 helpers per muscle, node and root per jiggle (parentNode too unless -1).
  let document = await io.read(baked);
  const muscleRig = document.getRoot().getExtension(rig.RIGBAKE_MUSCLE_RIG);
  const rootParents = bakedJson.extensions[rig.RIGBAKE_MUSCLE_RIG].jiggles.filter((j) => j.parentNode < 0).length;
  assert.equal(muscleRig.listNodeKeys().length, 7 * muscles + 3 * jiggles - rootParents);

  // Renumbering: removing the first node the rig does not name moves every later index down by one;
  // the written rig still names the same joints.
  const referenced = new Set(muscleRig.listNodeKeys().map((key) => muscleRig.getNode(key)));
  const victim = document.getRoot().listNodes().find((node) => !referenced.has(node));
  const victimIndex = document.getRoot().listNodes().indexOf(victim);
  victim.dispose();
  const shifted = await io.writeJSON(document);
  const firstSkinned = bakedJson.extensions[rig.RIGBAKE_MUSCLE_RIG].muscles[0].skinnedNode;
  assert.ok(firstSkinned > victimIndex, 'the removed node comes after the references: nothing moved');
  assert.equal(shifted.json.extensions[rig.RIGBAKE_MUSCLE_RIG].muscles[0].skinnedNode, firstSkinned - 1);
  assert.deepEqual(referencedNames(shifted.json), expected);

  // Held influences survive quantize (which alone stores WEIGHTS_n in 8 bits).
  const weightTypes = (doc) =>
    doc.getRoot().listMeshes()[0].listPrimitives()[0].listSemantics()
      .filter((s) => /^(JOINTS|WEIGHTS)_\d$/.test(s) || s.startsWith('_RIGBAKE_HELD_'))
      .map((s) => `${s}:${doc.getRoot().listMeshes()[0].listPrimitives()[0].getAttribute(s).getComponentType()}`)
      .sort();
  const arrays = (doc) =>
    doc.getRoot().listMeshes()[0].listPrimitives()[0].listSemantics()
      .filter((s) => /^((JOINTS|WEIGHTS)_\d|_RIGBAKE_PACKED_\w+)$/.test(s))
      .sort()
      .map((s) => [s, Array.from(doc.getRoot().listMeshes()[0].listPrimitives()[0].getAttribute(s).getArray())]);
  document = await io.read(baked);
  const before = arrays(document);
  await document.transform(functions.quantize());
  assert.ok(weightTypes(document).includes('WEIGHTS_0:5121'), 'quantize alone keeps 16-bit weights: the hold is pointless');
  document = rig.holdSkinInfluences(await io.read(baked));
  // (No weld here: it reorders vertices; tests/rig_pipelines_test.cpp runs the whole optimize.)
  // dedup first, as optimize does: _RIGBAKE_PACKED_JOINTS_0 holds JOINTS_0's values, so the two become
  // one accessor, which quantize re-sorts where its 8-bit weights tie.
  await document.transform(functions.dedup(), functions.quantize(), functions.prune());
  const shared = document.getRoot().listMeshes()[0].listPrimitives()[0];
  assert.equal(shared.getAttribute('_RIGBAKE_PACKED_JOINTS_0'), shared.getAttribute('JOINTS_0'), 'dedup no longer shares them');
  assert.equal(rig.restoreSkinInfluences(document), 1);
  const reread = await io.readBinary(await io.writeBinary(document));
  assert.deepEqual(weightTypes(reread), ['JOINTS_0:5121', 'JOINTS_1:5121', 'JOINTS_2:5121', 'WEIGHTS_0:5123', 'WEIGHTS_1:5123', 'WEIGHTS_2:5123']);
  assert.deepEqual(arrays(reread), before);
  assert.deepEqual(referencedNames((await io.writeJSON(reread)).json), expected);

  // A removed joint the rig names: the write fails and says which muscle.
  document = await io.read(baked);
  document.getRoot().listNodes().find((n) => n.getName() === 'LeftBicep_muscleSkinned').dispose();
  await assert.rejects(io.writeBinary(document), /LeftBicep\) skinnedNode: its node was removed/);

  // Another layout version is refused, not carried with references it cannot find.
  const jsonDoc = await io.readAsJSON(baked);
  jsonDoc.json.extensions[rig.RIGBAKE_MUSCLE_RIG].version = 2;
  await assert.rejects(io.readJSON(jsonDoc), /version 2 is not 1/);

  console.log(`glTF-Transform extension: ${muscleRig.listNodeKeys().length} node references of ${muscles} muscles and ` +
    `${jiggles} jiggles carried; influences restored after quantize; removed joint and version 2 refused`);
} finally {
  rmSync(work, { recursive: true, force: true });
}
