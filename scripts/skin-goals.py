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
centre-of-rotation region volumes). Then, beside the goals, the rig's figures no count above takes, so
that a change is weighed on them too (docs/deformation-quality.md, "Weighing a change"): joint regions (the
skin about each joint, uncapped) losing more than 1 point beyond plain skinning, of every joint region and
clip, and the largest; the volume kept, the median over clips of the rig's whole-body change over plain
skinning's (clips where plain skinning changes the body by more than 0.05 %); and the seams' largest
opening under the rig on the clips plain skinning keeps closed (at most 0.05 mm; where the input's own
weights open a place, rounding scales that opening, docs/deformation-quality.md "Seams"). Last, where to
look: each character's roughest clip's lumpiest vertex and its worst region's place (the vertex taking most
of its loss), as the stats name them (docs/deformation-quality.md).
Usage: skin-goals.py OUT_DIR [--json]"""
import json
import os
import statistics
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


def character_counts(quality, key):
    """One character's four counts for skinning `key` ("rig", "dual_quaternion", "centre_of_rotation"), each
    [passed, of], judged against plain skinning: its roughness rise against plain skinning's floored at the
    stats' floor (the rig's by its `roughness_ratio`, as validate judges), its arm clips' whole-body change
    against half of plain skinning's, its crease samples (crease_no_worse), and its worst region loss beyond
    plain skinning as (points, region, clip) with the regions count, or None where the stats have no regions
    for `key` (centres of rotation)."""
    counts = {"roughness": [0, 0], "halved": [0, 0], "creases": [0, 0], "regions": None, "worst_region": None}
    for clip, figures in quality["surface"]["per_clip"].items():
        rise = figures["roughness_rise_p95_mm"]
        floored = max(rise["input"], figures["roughness_floor_mm"])
        ratio = figures["roughness_ratio"] if key == "rig" else rise[key] / floored
        counts["roughness"][0] += ratio <= 1.2
        counts["roughness"][1] += 1
    for clip in quality["body"]["per_clip"]:
        if clip in ARM_CLIPS:
            plain = quality["body"]["per_clip"][clip]["input"]["change_percent"]
            counts["halved"][0] += abs(method_change(quality, clip, key)) <= 0.5 * abs(plain)
            counts["halved"][1] += 1
    for per in quality["creases"]["per_clip"].values():
        for v in per.values():
            counts["creases"][0] += crease_no_worse(v[key], v["input"])
            counts["creases"][1] += 1
    if key != "centre_of_rotation":
        worst = (0.0, None, None)
        for region, data in quality["regions"].items():
            for clip, v in data["per_clip"].items():
                loss = max(0.0, min(v["input"]["change_percent"], 0.0) - v[key]["change_percent"])
                if loss > worst[0]:
                    worst = (loss, region, clip)
        counts["worst_region"] = worst
        counts["regions"] = [1 if worst[0] <= 1.0 else 0, 1]
    return counts


def beside_goals(quality):
    """The rig's figures beside the goal counts: joint-region clips losing over 1 point beyond plain skinning
    [count, of] and the largest loss, the median of |rig| / |plain| whole-body change over the clips where
    plain skinning changes the body by more than 0.05 %, and the largest seam opening under the rig on the
    clips plain skinning keeps closed (within 0.05 mm; mm) with [how many clips that is, of]."""
    losses = [v["loss_beyond_input_points"] for per in quality["joint_regions"]["per_clip"].values() for v in per.values()]
    ratios = [abs(b["rig"]["change_percent"]) / abs(b["input"]["change_percent"])
              for b in quality["body"]["per_clip"].values() if abs(b["input"]["change_percent"]) > 0.05]
    kept = statistics.median(ratios) if ratios else None
    closed = [v["rig_mm"] for v in quality["seams"]["per_clip"].values() if v["input_mm"] <= 0.05]
    return {"joint_regions_over_1": [sum(x > 1.0 for x in losses), len(losses)],
            "joint_region_worst": max(losses, default=0.0), "kept_median": kept,
            "seam_on_closed_clips_mm": max(closed, default=0.0),
            "clips_plain_keeps_closed": [len(closed), len(quality["seams"]["per_clip"])]}


def score_method(out, key):
    """The four counts for a comparison skinning over every character, judged as the rig is (regions None
    where the stats have none for it)."""
    totals = {"roughness": [0, 0], "halved": [0, 0], "creases": [0, 0],
              "regions": None if key == "centre_of_rotation" else [0, 0]}
    for name in NAMES:
        counts = character_counts(json.load(open(os.path.join(out, name + ".stats.json")))["deformation_quality"], key)
        for item, total in totals.items():
            if total is not None:
                total[0] += counts[item][0]
                total[1] += counts[item][1]
    return totals


def score(out):
    rows, totals = [], {"roughness": [0, 0], "halved": [0, 0], "creases": [0, 0], "regions": [0, 0]}
    for name in NAMES:
        quality = json.load(open(os.path.join(out, name + ".stats.json")))["deformation_quality"]
        counts = character_counts(quality, "rig")
        per_clip = quality["surface"]["per_clip"]
        roughest_clip = max(per_clip, key=lambda c: per_clip[c]["roughness_ratio"])
        worst = counts["worst_region"]
        row = {"character": name, "clips": len(quality["body"]["per_clip"]), "roughness": counts["roughness"],
               "roughest": per_clip[roughest_clip]["roughness_ratio"], "halved": counts["halved"],
               "lumpiest": per_clip[roughest_clip].get("lumpiest_at"), "creases": counts["creases"],
               "worst_region": {"points": worst[0], "region": worst[1], "clip": worst[2],
                                "place": quality["regions"][worst[1]]["per_clip"][worst[2]]["rig"].get("lost_most_at")
                                if worst[1] else None},
               "regions": counts["regions"], "beside": beside_goals(quality)}
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
    print("\nbeside the goals (the rig): joint regions over 1 point beyond plain, the largest; volume kept"
          " (median of rig / plain change); seams")
    for r in rows:
        b = r["beside"]
        kept = "%.2f" % b["kept_median"] if b["kept_median"] is not None else "-"
        print("%-14s %5d/%-5d %6.2f  kept %s  seams %.3f mm on the %d/%d clips plain skinning keeps closed" % (
            r["character"], *b["joint_regions_over_1"], b["joint_region_worst"], kept, b["seam_on_closed_clips_mm"],
            *b["clips_plain_keeps_closed"]))
    over = [sum(r["beside"]["joint_regions_over_1"][i] for r in rows) for i in (0, 1)]
    print("%-14s %5d/%-5d" % ("total", *over))
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
