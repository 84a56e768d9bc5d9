#!/usr/bin/env python3
"""Counts issue 29's goals from the `bake --stats` files scripts/skin-goals.sh writes (docs/deformation-quality.md,
"Eight characters and more levers"):
  roughness: clips whose rig roughness rise is within 1.2x plain skinning's (`roughness_ratio`, as validate judges);
  halved:    arm clips whose whole-body volume change under the rig is at most half of plain skinning's;
  creases:   crease samples (clip x crease) where no more vertices pass through the opposing skin under the
             rig than under plain skinning and it comes no more than 0.5 mm closer;
  regions:   characters on which no body region loses more than 1 point of volume beyond plain skinning.
Beneath, the same counts for the yardsticks the issue names, dual quaternions and centres of rotation, each
scored against plain skinning as the rig is (regions: dual quaternions only; the stats carry no
centre-of-rotation region volumes). Below that, where to look: each character's roughest clip's lumpiest vertex and its worst region's
place (the vertex taking most of its loss), as the stats name them (docs/deformation-quality.md).
Usage: skin-goals.py OUT_DIR [--json]"""
import json
import os
import sys

ARM_CLIPS = {"ElbowFlexion", "ArmRaise", "rom_elbow_flexion", "rom_shoulder_abduction", "rom_shoulder_flexion"}
NAMES = ["mannequin", "cyberpunk", "soldier", "male_casual", "female_casual", "cowboy", "cesiumman", "kaykit"]


def crease_no_worse(rig, plain):
    if rig["through_vertices"] > plain["through_vertices"]:
        return False
    if plain["closest_mm"] is None or rig["closest_mm"] is None:
        return True  # no skin faces skin within reach under one of them: nothing closer
    return rig["closest_mm"] >= plain["closest_mm"] - 0.5


METHODS = {"dual quat.": "dual_quaternion", "centres rot.": "centre_of_rotation"}


def method_change(quality, clip, key):
    """Whole-body change (percent) of skinning `key` in `clip`: the body table's, or for centres of rotation
    the surface figures' (the body table has no such column)."""
    if key == "centre_of_rotation":
        return quality["surface"]["per_clip"][clip]["centre_of_rotation_volume"]["change_percent"]
    return quality["body"]["per_clip"][clip][key]["change_percent"]


def score_method(out, key):
    """The four counts for a comparison skinning, judged as the rig is: its roughness rise against plain
    skinning's (floored), its arm clips' change against plain skinning's, its crease samples against plain
    skinning's, its regions' loss beyond plain skinning (None where the stats have no regions for it)."""
    totals = {"roughness": [0, 0], "halved": [0, 0], "creases": [0, 0], "regions": [0, 0] if key == "dual_quaternion" else None}
    for name in NAMES:
        quality = json.load(open(os.path.join(out, name + ".stats.json")))["deformation_quality"]
        for clip, figures in quality["surface"]["per_clip"].items():
            rise = figures["roughness_rise_p95_mm"]
            totals["roughness"][0] += rise[key] <= 1.2 * max(rise["input"], figures["roughness_floor_mm"])
            totals["roughness"][1] += 1
            if clip in ARM_CLIPS:
                plain = quality["body"]["per_clip"][clip]["input"]["change_percent"]
                totals["halved"][0] += abs(method_change(quality, clip, key)) <= 0.5 * abs(plain)
                totals["halved"][1] += 1
        for per in quality["creases"]["per_clip"].values():
            for v in per.values():
                totals["creases"][0] += crease_no_worse(v[key], v["input"])
                totals["creases"][1] += 1
        if totals["regions"] is not None:
            worst = max([max(0.0, min(v["input"]["change_percent"], 0.0) - v[key]["change_percent"])
                         for data in quality["regions"].values() for v in data["per_clip"].values()] + [0.0])
            totals["regions"][0] += worst <= 1.0
            totals["regions"][1] += 1
    return totals


def score(out):
    rows, totals = [], {"roughness": [0, 0], "halved": [0, 0], "creases": [0, 0], "regions": [0, 0]}
    for name in NAMES:
        stats = json.load(open(os.path.join(out, name + ".stats.json")))
        quality = stats["deformation_quality"]
        clips = list(quality["body"]["per_clip"].keys())
        ratios = [v["roughness_ratio"] for v in quality["surface"]["per_clip"].values()]
        row = {"character": name, "clips": len(clips), "roughness": [sum(r <= 1.2 for r in ratios), len(ratios)],
               "roughest": max(ratios)}
        arm = [c for c in clips if c in ARM_CLIPS]
        halved = [c for c in arm
                  if abs(quality["body"]["per_clip"][c]["rig"]["change_percent"])
                  <= 0.5 * abs(quality["body"]["per_clip"][c]["input"]["change_percent"])]
        row["halved"] = [len(halved), len(arm)]
        roughest_clip = max(quality["surface"]["per_clip"], key=lambda c: quality["surface"]["per_clip"][c]["roughness_ratio"])
        row["lumpiest"] = quality["surface"]["per_clip"][roughest_clip].get("lumpiest_at")
        samples = [(c, k, v) for c, per in quality["creases"]["per_clip"].items() for k, v in per.items()]
        row["creases"] = [sum(crease_no_worse(v["rig"], v["input"]) for _, _, v in samples), len(samples)]
        worst = (0.0, None, None)
        for region, data in quality["regions"].items():
            for clip, v in data["per_clip"].items():
                loss = max(0.0, min(v["input"]["change_percent"], 0.0) - v["rig"]["change_percent"])
                if loss > worst[0]:
                    worst = (loss, region, clip)
        row["worst_region"] = {"points": worst[0], "region": worst[1], "clip": worst[2],
                               "place": quality["regions"][worst[1]]["per_clip"][worst[2]]["rig"].get("lost_most_at")
                               if worst[1] else None}
        row["regions"] = [1 if worst[0] <= 1.0 else 0, 1]
        rows.append(row)
        for key in totals:
            totals[key][0] += row[key][0]
            totals[key][1] += row[key][1]
    return rows, totals


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    rows, totals = score(sys.argv[1])
    methods = {name: score_method(sys.argv[1], key) for name, key in METHODS.items()}
    if "--json" in sys.argv:
        print(json.dumps({"characters": rows, "totals": totals, "yardsticks": methods}, indent=2))
        return
    print("%-14s %10s %9s %8s %9s  %s" % ("character", "roughness", "roughest", "halved", "creases",
                                          "worst region loss beyond plain (points)"))
    for r in rows:
        w = r["worst_region"]
        print("%-14s %6d/%-3d %8.2fx %4d/%-3d %5d/%-3d  %.2f %s %s" % (
            r["character"], *r["roughness"], r["roughest"], *r["halved"], *r["creases"], w["points"], w["region"] or "", w["clip"] or ""))
    print("%-14s %6d/%-3d %9s %4d/%-3d %5d/%-3d  %d/%d characters within 1 point" % (
        "total", *totals["roughness"], "", *totals["halved"], *totals["creases"], *totals["regions"]))
    print("the yardsticks, each scored against plain skinning as the rig is:")
    for name, t in methods.items():
        regions = "%d/%d characters within 1 point" % tuple(t["regions"]) if t["regions"] else "(no region figures)"
        print("%-14s %6d/%-3d %9s %4d/%-3d %5d/%-3d  %s" % (name, *t["roughness"], "", *t["halved"], *t["creases"], regions))
    print("\nwhere to look (mesh 'name' vertex, bind position):")
    for r in rows:
        lump, place = r["lumpiest"], r["worst_region"]["place"]
        if lump:
            print("%-14s lumpiest: %s vertex %d at (%.3f %.3f %.3f), %.2f mm beyond plain skinning" % (
                r["character"], repr(lump["mesh"]), lump["vertex"], *lump["bind_position"],
                lump["rig_rise_mm"] - lump["input_rise_mm"]))
        if place:
            print("%-14s region:   %s vertex %d at (%.3f %.3f %.3f), %.2f of its %.2f points" % (
                r["character"], repr(place["mesh"]), place["vertex"], *place["bind_position"], place["points"],
                r["worst_region"]["points"]))


if __name__ == "__main__":
    main()
