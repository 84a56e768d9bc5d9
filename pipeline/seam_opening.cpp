#include "pipeline/seam_opening.h"

#include <algorithm>
#include <cassert>

#include "pipeline/parallel.h"
#include "pipeline/weld.h"

namespace rigbake {

SeamPlaces findSeamPlaces(const Character& character, const std::vector<MeasuredPart>& parts, double weld_tolerance) {
  std::vector<Eigen::Vector3d> positions;
  std::vector<std::pair<int, int>> owner;
  for (size_t p = 0; p < parts.size(); ++p) {
    const std::vector<Eigen::Vector3d>& own = character.meshes[parts[p].mesh_part].positions;
    for (size_t v = 0; v < own.size(); ++v) {
      positions.push_back(own[v]);
      owner.emplace_back(static_cast<int>(p), static_cast<int>(v));
    }
  }
  const std::vector<int> first = firstVertexOfCell(positions, weld_tolerance);
  // Places numbered in the order of their first vertex; only those with two vertices or more kept.
  std::vector<int> place_of_first(positions.size(), -1);
  std::vector<std::vector<std::pair<int, int>>> all;
  for (size_t i = 0; i < positions.size(); ++i) {
    int& place = place_of_first[static_cast<size_t>(first[i])];
    if (place < 0) {
      place = static_cast<int>(all.size());
      all.emplace_back();
    }
    all[static_cast<size_t>(place)].push_back(owner[i]);
  }
  SeamPlaces places;
  for (auto& members : all)
    if (members.size() >= 2) places.members.push_back(std::move(members));
  return places;
}

namespace {

// A vertex's weights as (joint, weight) pairs, ascending, zero weights left out.
std::vector<std::pair<int, double>> sortedRow(const InfluenceSet& set, int v) {
  std::vector<std::pair<int, double>> row;
  for (int k = 0; k < set.slots_per_vertex; ++k) {
    const double w = set.weights[static_cast<size_t>(v) * set.slots_per_vertex + k];
    if (w != 0.0) row.emplace_back(set.joints[static_cast<size_t>(v) * set.slots_per_vertex + k], w);
  }
  std::sort(row.begin(), row.end());
  return row;
}

// The places whose vertices do not all carry the same weights (joint for joint, to the bit) in the
// input's or the rig's set: the others move as one under either skinning (apart from a turn of their
// bind offsets, at most the weld tolerance) and need not be skinned at every sample.
SeamPlaces placesThatCanOpen(const std::vector<MeasuredPart>& parts, const SeamPlaces& places) {
  SeamPlaces open;
  for (const auto& members : places.members) {
    bool differ = false;
    for (bool rig : {false, true}) {
      const auto& [p0, v0] = members[0];
      const auto first = sortedRow(rig ? parts[p0].rig : parts[p0].input, v0);
      for (size_t i = 1; i < members.size() && !differ; ++i)
        differ = sortedRow(rig ? parts[members[i].first].rig : parts[members[i].first].input, members[i].second) != first;
    }
    if (differ) open.members.push_back(members);
  }
  return open;
}

Eigen::Vector3d skinVertex(const Eigen::Vector3d& p, const InfluenceSet& set, int v, const SkinFrame& frame) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (int k = 0; k < set.slots_per_vertex; ++k) {
    const double w = set.weights[static_cast<size_t>(v) * set.slots_per_vertex + k];
    if (w != 0.0) sum += w * (frame[static_cast<size_t>(set.joints[static_cast<size_t>(v) * set.slots_per_vertex + k])] * p);
  }
  return sum;
}

// The largest amount by which two members of one place move apart, every place, one frame.
double largestOpening(const std::vector<MeasuredPart>& parts, const Character& character, const SeamPlaces& places,
                      const SkinFrame& frame, bool rig) {
  double largest = 0.0;
  std::vector<Eigen::Vector3d> bind, posed;
  for (const auto& members : places.members) {
    bind.clear();
    posed.clear();
    for (const auto& [p, v] : members) {
      const MeasuredPart& part = parts[static_cast<size_t>(p)];
      bind.push_back(character.meshes[part.mesh_part].positions[static_cast<size_t>(v)]);
      posed.push_back(skinVertex(bind.back(), rig ? part.rig : part.input, v, frame));
    }
    // Apart by more than at the bind pose, where a place's vertices may already be up to the weld
    // tolerance apart.
    for (size_t a = 0; a < posed.size(); ++a)
      for (size_t b = a + 1; b < posed.size(); ++b)
        largest = std::max(largest, (posed[a] - posed[b]).norm() - (bind[a] - bind[b]).norm());
  }
  return largest;
}

}  // namespace

std::vector<SeamOpening> measureSeamOpening(const std::vector<MeasuredPart>& parts, const Character& character,
                                            const SeamPlaces& places, const std::vector<MeasuredClip>& clips, int threads) {
  std::vector<SeamOpening> openings(clips.size());
  const SeamPlaces open = placesThatCanOpen(parts, places);
  if (open.members.empty()) return openings;
  for (size_t c = 0; c < clips.size(); ++c) {
    const std::vector<SkinFrame>& frames = *clips[c].frames;
    std::vector<std::pair<double, double>> per_frame(frames.size());  // (input, rig)
    parallelForEach(threads, frames.size(), [&](size_t t) {
      per_frame[t] = {largestOpening(parts, character, open, frames[t], false),
                      largestOpening(parts, character, open, frames[t], true)};
    });
    SeamOpening& opening = openings[c];
    for (size_t t = 0; t < frames.size(); ++t) {
      opening.input = std::max(opening.input, per_frame[t].first);
      if (per_frame[t].second > opening.rig) {
        opening.rig = per_frame[t].second;
        opening.time = clips[c].times[t];
      }
    }
  }
  return openings;
}

void measureSeams(const Character& character, const std::vector<MeasuredPart>& parts, const std::vector<MeasuredClip>& clips,
                  double weld_tolerance, int threads, DeformationQuality* quality) {
  assert(quality->clips.size() == clips.size());
  const SeamPlaces places = findSeamPlaces(character, parts, weld_tolerance);
  quality->seam_places = static_cast<int>(places.members.size());
  const std::vector<SeamOpening> openings = measureSeamOpening(parts, character, places, clips, threads);
  for (size_t c = 0; c < clips.size(); ++c) quality->clips[c].seams = openings[c];
}

}  // namespace rigbake
