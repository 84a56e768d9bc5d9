// One rounding per place on the skin. The motion-aware rounding (pipeline/quantize_for_motion.h) holds
// every part to the character's worst vertex, but two vertices of different mesh parts at one place
// whose weights agree only to 1e-9 (sums in another order) can still break a near tie apart, and the
// border between the meshes would open by up to a rounding's error (0.15-0.7 mm). Here every such
// vertex takes the rounding of the first vertex at its place: a valid rounding of its own weights.
#pragma once

#include <utility>
#include <vector>

#include "pipeline/influences.h"

namespace rigbake {

// Pruned rows this close, slot by slot (same joints), count as the same weights: rows built from the
// same input weights in another slot order differ in the last bits of their sums.
constexpr double kSameWeightTolerance = 1e-9;

// `weld_of_vertex` numbers the places of every part's vertices, parts one after another (part p's
// vertices from first_vertex[p]; first_vertex has one entry past the last part). Per place, its first
// (part, vertex) in that order.
std::vector<std::pair<int, int>> firstVertexAtEachPlace(const std::vector<int>& weld_of_vertex, const std::vector<int>& first_vertex);

// The places as above; pruned[p] and (*quantized)[p] are part p's rows, with the same slot
// count in every part. A vertex whose pruned row equals, within kSameWeightTolerance, that of the first
// vertex at its place gets that vertex's quantized row.
void shareSeamRoundings(const std::vector<int>& weld_of_vertex, const std::vector<int>& first_vertex,
                        const std::vector<InfluenceSet>& pruned, std::vector<QuantizedInfluences>* quantized);

}  // namespace rigbake
