#!/usr/bin/env python3
"""Remakes the derived seeds of the fuzz corpus (tests/fuzz/, docs: tests/fuzz/README.md).

Usage: tests/fuzz/make_seeds.py RIGBAKE_BINARY

The character seeds are the sample mannequin (`rigbake sample`, 2,000 vertices) simplified by gltfpack
to about 80 triangles and 2 keys per second, so that each is about 10 KB and a fuzzer iteration stays
fast: as GLB with float attributes, quantized (KHR_mesh_quantization), meshopt-compressed, as .gltf
with its buffer embedded, and as VRM 0.x and 1.0 (gltfpack drops the VRM extension; it is copied back
with its node indices mapped by name). The muscle seeds are `rigbake place` on the mannequin, with and
without the rigbake block. Deterministic: the same tools give the same bytes.
"""
import base64
import json
import os
import struct
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))


def read_glb(path):
    data = open(path, "rb").read()
    json_length = struct.unpack_from("<I", data, 12)[0]
    document = json.loads(data[20:20 + json_length])
    binary = b""
    if len(data) > 20 + json_length:
        bin_length = struct.unpack_from("<I", data, 20 + json_length)[0]
        binary = data[28 + json_length:28 + json_length + bin_length]
    return document, binary


def write_glb(path, document, binary):
    text = json.dumps(document, separators=(",", ":"), sort_keys=True).encode()
    text += b" " * (-len(text) % 4)
    binary += b"\0" * (-len(binary) % 4)
    body = struct.pack("<I", len(text)) + b"JSON" + text + struct.pack("<I", len(binary)) + b"BIN\0" + binary
    with open(path, "wb") as out:
        out.write(b"glTF" + struct.pack("<II", 2, 12 + len(body)) + body)


def gltfpack(source, target, *flags):
    subprocess.run(["gltfpack", "-i", source, "-o", target, "-si", "0.02", "-sa", "-af", "2", "-kn", *flags],
                   check=True, stdout=subprocess.DEVNULL)


def with_vrm(packed, original, target):
    """`packed` (gltfpack's output) with `original`'s VRM extension, its node indices mapped by name."""
    document, binary = read_glb(packed)
    source, _ = read_glb(original)
    index_of = {node.get("name"): i for i, node in enumerate(document["nodes"])}
    name_of = [node.get("name") for node in source["nodes"]]

    def remap(value, key=None):
        if isinstance(value, dict):
            return {k: remap(v, k) for k, v in value.items()}
        if isinstance(value, list):
            return [remap(v, key) for v in value]
        if key in ("node",) and isinstance(value, int):
            return index_of[name_of[value]]
        return value

    for name in source.get("extensionsUsed", []):
        document.setdefault("extensions", {})[name] = remap(source["extensions"][name])
        document.setdefault("extensionsUsed", []).append(name)
    write_glb(target, document, binary)


def with_springs(source, target):
    """`source` (a VRM 0.x) with a secondaryAnimation of UniVRM's shape (as tests/vrm_convert_test.cpp
    adds): spring chains from the toes and the branching left shoulder, sphere colliders on the head and
    hands, for the VRM 0.x -> 1.0 conversion."""
    document, binary = read_glb(source)
    vrm = document["extensions"]["VRM"]
    bone = {entry["bone"]: entry["node"] for entry in vrm["humanoid"]["humanBones"]}

    def sphere(x, y, z, radius):
        return {"offset": {"x": x, "y": y, "z": z}, "radius": radius}

    vrm["secondaryAnimation"] = {
        "colliderGroups": [
            {"node": bone["head"], "colliders": [sphere(0, 0.08, 0.01, 0.1)]},
            {"node": bone["leftHand"], "colliders": [sphere(0, 0, 0, 0.05), sphere(-0.05, 0, 0, 0.04)]},
            {"node": bone["rightHand"], "colliders": [sphere(0.05, 0.01, 0.02, 0.04)]}],
        "boneGroups": [
            {"comment": "toes", "stiffiness": 1.5, "gravityPower": 0.5, "gravityDir": {"x": 0.3, "y": -1, "z": 0.2},
             "dragForce": 0.4, "center": -1, "hitRadius": 0.02, "bones": [bone["leftToes"], bone["rightToes"]],
             "colliderGroups": [0]},
            {"comment": "left shoulder", "stiffiness": 2.0, "gravityPower": 0, "gravityDir": {"x": 0, "y": -1, "z": 0},
             "dragForce": 0.7, "center": bone["hips"], "hitRadius": 0.03, "bones": [bone["leftShoulder"]],
             "colliderGroups": [0, 2]}]}
    write_glb(target, document, binary)


def main():
    rigbake = os.path.abspath(sys.argv[1])
    characters = os.path.join(HERE, "character")
    muscles = os.path.join(HERE, "muscles")
    os.makedirs(characters, exist_ok=True)
    os.makedirs(muscles, exist_ok=True)
    with tempfile.TemporaryDirectory() as work:
        def run(*args):
            subprocess.run([rigbake, *args], check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)

        sample = os.path.join(work, "sample.glb")
        run("sample", "--vertices", "2000", "-o", sample)
        gltfpack(sample, os.path.join(characters, "mannequin.glb"), "-noq")
        gltfpack(sample, os.path.join(characters, "quantized.glb"))
        gltfpack(sample, os.path.join(characters, "meshopt.glb"), "-c")
        document, binary = read_glb(os.path.join(characters, "mannequin.glb"))
        document["buffers"][0]["uri"] = "data:application/octet-stream;base64," + base64.b64encode(binary).decode()
        with open(os.path.join(characters, "embedded.gltf"), "w") as out:
            json.dump(document, out, separators=(",", ":"), sort_keys=True)
        for version in ("0", "1"):
            vrm = os.path.join(work, "sample" + version + ".vrm")
            packed = os.path.join(work, "packed" + version + ".glb")
            run("sample", "--vertices", "2000", "--vrm", version, "-o", vrm)
            as_glb = os.path.join(work, "sample" + version + ".glb")  # gltfpack goes by the extension
            os.link(vrm, as_glb)
            gltfpack(as_glb, packed, "-noq")
            with_vrm(packed, vrm, os.path.join(characters, "vrm" + version + ".vrm"))
        with_springs(os.path.join(characters, "vrm0.vrm"), os.path.join(characters, "vrm0_springs.vrm"))
        # The whole file is 35 KB; the arms' parts (both sides) keep every kind of field at a tenth of it.
        placed = os.path.join(work, "placed.json")
        run("place", os.path.join(characters, "mannequin.glb"), "-o", placed)
        whole = json.load(open(placed))
        arms = {"Arms": whole["Arms"], "rigbake": dict(whole["rigbake"])}
        arms["rigbake"]["muscles"] = {name: part for name, part in whole["rigbake"]["muscles"].items()
                                      if part["group"] == "Arms"}
        with open(os.path.join(muscles, "arms.json"), "w") as out:
            json.dump(arms, out, separators=(",", ":"), sort_keys=True)
        talk_only = {group: value for group, value in whole.items() if group != "rigbake"}
        with open(os.path.join(muscles, "positions_only.json"), "w") as out:
            json.dump(talk_only, out, separators=(",", ":"), sort_keys=True)

if __name__ == "__main__":
    main()
