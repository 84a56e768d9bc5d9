// Welding by grid cell (llround of each coordinate / tolerance): each vertex joins the lowest vertex of
// its cell. When every axis's cells span fewer than 2^21 values (a character 2 m wide at the bake's
// 1e-6 of body height spans about 1.1e6), the three fit one 63-bit key, and a hash table of the cells
// filled in vertex order finds each cell's first vertex in linear time; otherwise the cells are sorted
// with the vertex index as the last key.
#include "pipeline/weld.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <tuple>


namespace rigbake {

std::vector<int> firstVertexOfCell(const std::vector<Eigen::Vector3d>& positions, double tolerance) {
  const size_t count = positions.size();
  std::vector<int> first_of_vertex(count);
  if (count == 0) return first_of_vertex;
  std::vector<std::array<long long, 3>> cells(count);
  std::array<long long, 3> low, high;
  low.fill(std::numeric_limits<long long>::max());
  high.fill(std::numeric_limits<long long>::min());
  for (size_t v = 0; v < count; ++v) {
    for (int k = 0; k < 3; ++k) {
      cells[v][k] = std::llround(positions[v][k] / tolerance);
      low[k] = std::min(low[k], cells[v][k]);
      high[k] = std::max(high[k], cells[v][k]);
    }
  }
  constexpr long long kAxisSpan = 1LL << 21;
  bool packs = true;
  for (int k = 0; k < 3; ++k) packs = packs && high[k] - low[k] < kAxisSpan;
  if (packs) {
    // Open addressing on the packed cell: the first vertex to reach a cell is its lowest.
    size_t capacity = 1;
    while (capacity < 2 * count) capacity <<= 1;
    constexpr std::uint64_t kEmpty = ~std::uint64_t{0};
    std::vector<std::uint64_t> slot_key(capacity, kEmpty);
    std::vector<int> slot_vertex(capacity, -1);
    for (size_t v = 0; v < count; ++v) {
      const std::uint64_t key = (static_cast<std::uint64_t>(cells[v][0] - low[0]) << 42) |
                                (static_cast<std::uint64_t>(cells[v][1] - low[1]) << 21) |
                                static_cast<std::uint64_t>(cells[v][2] - low[2]);
      // Fibonacci hashing spreads neighbouring cells over the table.
      size_t at = static_cast<size_t>((key * 0x9E3779B97F4A7C15ull) >> 1) & (capacity - 1);
      while (slot_key[at] != kEmpty && slot_key[at] != key) at = (at + 1) & (capacity - 1);
      if (slot_key[at] == kEmpty) {
        slot_key[at] = key;
        slot_vertex[at] = static_cast<int>(v);
      }
      first_of_vertex[v] = slot_vertex[at];
    }
    return first_of_vertex;
  }
  std::vector<std::uint32_t> order(count);
  for (size_t v = 0; v < count; ++v) order[v] = static_cast<std::uint32_t>(v);
  std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
    return std::tie(cells[a][0], cells[a][1], cells[a][2], a) < std::tie(cells[b][0], cells[b][1], cells[b][2], b);
  });
  for (size_t i = 0, group = 0; i < count; ++i) {
    if (i > 0 && cells[order[i]] != cells[order[i - 1]]) group = i;
    first_of_vertex[order[i]] = static_cast<int>(order[group]);
  }
  return first_of_vertex;
}

}  // namespace rigbake
