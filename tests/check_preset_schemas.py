#!/usr/bin/python3
"""Every shipped preset passes its JSON Schema, and the schemas reject a broken preset.

Usage: check_preset_schemas.py REPO_DIR [RIGBAKE_CLI]. With the CLI, it also bakes the sample character
(muscles, helper joints, jiggles: every part of the extension) and checks the baked file's
RIGBAKE_muscle_rig extension against presets/schemas/RIGBAKE_muscle_rig.schema.json. Uses Debian's
python3-jsonschema (Draft 2020-12)."""
import copy
import json
import pathlib
import struct
import subprocess
import sys
import tempfile

import jsonschema

def baked_extension(cli: str) -> dict:
    """The RIGBAKE_muscle_rig extension of the sample character baked by the CLI (a GLB's JSON chunk)."""
    with tempfile.TemporaryDirectory() as work:
        sample, baked = f"{work}/sample.glb", f"{work}/baked.glb"
        subprocess.run([cli, "sample", "-o", sample], check=True, capture_output=True)
        subprocess.run([cli, "bake", sample, "--helper-joints", "--jiggle", "biceps", "-o", baked], check=True,
                       capture_output=True)
        data = pathlib.Path(baked).read_bytes()
    length, kind = struct.unpack_from("<II", data, 12)
    assert kind == 0x4E4F534A, "the first GLB chunk is not JSON"
    return json.loads(data[20:20 + length])["extensions"]["RIGBAKE_muscle_rig"]

def main(repo: pathlib.Path, cli: str = "") -> int:
    schemas_dir = repo / "presets" / "schemas"
    schemas = {p.name: json.loads(p.read_text()) for p in schemas_dir.glob("*.schema.json")}
    def validator(name):
        # Debian 12 ships jsonschema 4.10: references resolve through a RefResolver store keyed by $id.
        resolver = jsonschema.RefResolver(base_uri=name, referrer=schemas[name], store=schemas)
        return jsonschema.Draft202012Validator(schemas[name], resolver=resolver)
    checks = [("naming_map.schema.json", p) for p in sorted((repo / "presets" / "skeletons").glob("*.json"))]
    checks += [("landmark_rules.schema.json", repo / "presets" / "landmarks.json")]
    checks += [("muscle_preset.schema.json", p) for p in sorted((repo / "presets" / "muscles").glob("*.json"))]
    checks += [("jiggle_preset.schema.json", p) for p in sorted((repo / "presets" / "jiggle").glob("*.json"))]
    checks += [("body_regions.schema.json", p) for p in sorted((repo / "presets" / "regions").glob("*.json"))]
    checks += [("rom_preset.schema.json", p) for p in sorted((repo / "presets" / "rom").glob("*.json"))]
    checks += [("build_manifest.schema.json", repo / "examples" / "build_manifest.json")]
    failures = 0
    for schema, path in checks:
        errors = list(validator(schema).iter_errors(json.loads(path.read_text())))
        for error in errors:
            print(f"{path.relative_to(repo)}#/{'/'.join(map(str, error.absolute_path))}: {error.message}")
        failures += bool(errors)
        print(f"{'FAIL' if errors else 'ok  '} {path.relative_to(repo)} against {schema}")
    # The schemas must be able to fail: a typo'd key and an unknown landmark are both rejected.
    preset = json.loads((repo / "presets" / "muscles" / "gow_biped.json").read_text())
    broken_key = copy.deepcopy(preset)
    broken_key["muscles"][0]["compresion"] = 0.5
    broken_landmark = copy.deepcopy(preset)
    broken_landmark["muscles"][0]["origin_attach"] = "shoulderblade"
    jiggle = json.loads((repo / "presets" / "jiggle" / "gow_examples.json").read_text())
    broken_jiggle = copy.deepcopy(jiggle)
    broken_jiggle["jiggles"][0]["stifness"] = 0.5
    rom = json.loads((repo / "presets" / "rom" / "default.json").read_text())
    broken_rom = copy.deepcopy(rom)
    broken_rom["clips"][0]["to_degs"] = 130
    sided_rom = copy.deepcopy(rom)
    sided_rom["clips"][0]["joints"][0]["landmark"] = "forearm_l"
    corrective = next(m for m in preset["muscles"] if m.get("kind") == "corrective")
    carrierless = copy.deepcopy(preset)
    next(m for m in carrierless["muscles"] if m.get("kind") == "corrective").pop("carriers")
    carrying_muscle = copy.deepcopy(preset)
    carrying_muscle["muscles"][0]["carriers"] = list(corrective["carriers"])
    manifest = json.loads((repo / "examples" / "build_manifest.json").read_text())
    broken_manifest = copy.deepcopy(manifest)
    broken_manifest["characters"][1]["muscles"] = "tuned.json"
    negatives = [("build_manifest.schema.json", "character with both muscles and muscles_from", broken_manifest),("muscle_preset.schema.json", "typo'd key", broken_key),
                 ("muscle_preset.schema.json", "unknown landmark", broken_landmark),
                 ("muscle_preset.schema.json", "corrective without carriers", carrierless),
                 ("muscle_preset.schema.json", "muscle naming carriers", carrying_muscle),
                 ("jiggle_preset.schema.json", "typo'd jiggle key", broken_jiggle),
                 ("rom_preset.schema.json", "typo'd ROM clip key", broken_rom),
                 ("rom_preset.schema.json", "ROM joint with a side suffix", sided_rom)]
    if cli:
        extension = baked_extension(cli)
        errors = list(validator("RIGBAKE_muscle_rig.schema.json").iter_errors(extension))
        for error in errors:
            print(f"baked sample#/extensions/RIGBAKE_muscle_rig/{'/'.join(map(str, error.absolute_path))}: {error.message}")
        covered = bool(extension.get("jiggles")) and all("helperNodes" in m for m in extension["muscles"])
        print(f"{'FAIL' if errors or not covered else 'ok  '} the baked sample's RIGBAKE_muscle_rig "
              f"({len(extension['muscles'])} muscles, {len(extension.get('jiggles', []))} jiggles) against RIGBAKE_muscle_rig.schema.json")
        checks.append(("RIGBAKE_muscle_rig.schema.json", "baked sample"))
        failures += bool(errors) or not covered
        broken_rig = copy.deepcopy(extension)
        broken_rig["muscles"][0]["restLenght"] = broken_rig["muscles"][0].pop("restLength")
        negative_rig = copy.deepcopy(extension)
        negative_rig["muscles"][0]["compression"] = 1.5
        negatives += [("RIGBAKE_muscle_rig.schema.json", "muscle with a typo'd key", broken_rig),
                      ("RIGBAKE_muscle_rig.schema.json", "muscle whose compression is above 1", negative_rig)]
    else:
        print("note: no RIGBAKE_CLI argument, the baked extension is not checked")
    for schema, label, document in negatives:
        rejected = not validator(schema).is_valid(document)
        print(f"{'ok  ' if rejected else 'FAIL'} schema rejects a {label}")
        failures += not rejected
    print(f"{len(checks) + len(negatives) - failures} passed, {failures} failed")
    return 1 if failures else 0

if __name__ == "__main__":
    sys.exit(main(pathlib.Path(sys.argv[1]), sys.argv[2] if len(sys.argv) > 2 else ""))
