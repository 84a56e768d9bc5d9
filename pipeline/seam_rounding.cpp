#include "pipeline/seam_rounding.h"

#include <cassert>
#include <cmath>
#include <utility>

namespace rigbake {

std::vector<std::pair<int, int>> firstVertexAtEachPlace(const std::vector<int>& weld_of_vertex, const std::vector<int>& first_vertex) {
  std::vector<std::pair<int, int>> first_at(weld_of_vertex.size(), {-1, -1});
  for (size_t p = 0; p + 1 < first_vertex.size(); ++p) {
    for (int v = 0; v < first_vertex[p + 1] - first_vertex[p]; ++v) {
      auto& first = first_at[static_cast<size_t>(weld_of_vertex[first_vertex[p] + v])];
      if (first.first < 0) first = {static_cast<int>(p), v};
    }
  }
  return first_at;
}

void shareSeamRoundings(const std::vector<int>& weld_of_vertex, const std::vector<int>& first_vertex,
                        const std::vector<InfluenceSet>& pruned, std::vector<QuantizedInfluences>* quantized) {
  assert(pruned.size() == quantized->size() && first_vertex.size() == pruned.size() + 1);
  if (pruned.size() < 2) return;  // within one part, equal weights at one place already round alike
  const int slots = pruned[0].slots_per_vertex;
  const std::vector<std::pair<int, int>> first_at = firstVertexAtEachPlace(weld_of_vertex, first_vertex);
  for (size_t p = 0; p < pruned.size(); ++p) {
    assert(pruned[p].slots_per_vertex == slots && (*quantized)[p].slots_per_vertex == slots);
    const int count = first_vertex[p + 1] - first_vertex[p];
    for (int v = 0; v < count; ++v) {
      const auto& first = first_at[static_cast<size_t>(weld_of_vertex[first_vertex[p] + v])];
      if (first.first == static_cast<int>(p)) continue;  // itself, or a vertex of its own part
      const InfluenceSet& mine = pruned[p];
      const InfluenceSet& theirs = pruned[first.first];
      bool same = true;
      for (int k = 0; k < slots && same; ++k) {
        const size_t a = static_cast<size_t>(v) * slots + k, b = static_cast<size_t>(first.second) * slots + k;
        same = std::abs(mine.weights[a] - theirs.weights[b]) <= kSameWeightTolerance &&
               (mine.weights[a] == 0.0 || mine.joints[a] == theirs.joints[b]);
      }
      if (!same) continue;
      QuantizedInfluences& to = (*quantized)[p];
      const QuantizedInfluences& from = (*quantized)[first.first];
      for (int k = 0; k < slots; ++k) {
        to.joints[static_cast<size_t>(v) * slots + k] = from.joints[static_cast<size_t>(first.second) * slots + k];
        to.weights[static_cast<size_t>(v) * slots + k] = from.weights[static_cast<size_t>(first.second) * slots + k];
      }
    }
  }
}

}  // namespace rigbake
