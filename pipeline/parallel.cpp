// std::thread rather than a task library (oneTBB, OpenMP): the bake has a handful of coarse loops
// (frames, poses, blocks of vertices) that run for milliseconds each, so starting the threads per loop
// costs nothing measurable, there is no dependency to install, and determinism is plain to see: chunks
// are fixed by count and grain, claimed in index order from one atomic counter, and write only their
// own slots.
#include "pipeline/parallel.h"

#include <algorithm>
#include <atomic>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

namespace rigbake {
namespace {

// True on a thread that is running a parallelFor body: a nested loop then runs serially, so that two
// stages that are each parallel do not start threads squared.
thread_local bool inside_parallel_body = false;

}  // namespace

int resolveThreadCount(int requested) {
  if (requested > 0) return requested;
  return static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
}

size_t parallelChunkCount(size_t count, size_t grain) {
  grain = std::max<size_t>(grain, 1);
  return (count + grain - 1) / grain;
}

size_t parallelWorkerCount(int threads, size_t count, size_t grain) {
  const size_t chunks = parallelChunkCount(count, grain);
  if (chunks == 0) return 0;
  return inside_parallel_body ? 1 : std::min<size_t>(static_cast<size_t>(resolveThreadCount(threads)), chunks);
}

void parallelForWorkers(int threads, size_t count, size_t grain,
                        const std::function<void(size_t worker, size_t chunk, size_t begin, size_t end)>& body) {
  grain = std::max<size_t>(grain, 1);
  const size_t chunks = parallelChunkCount(count, grain);
  if (chunks == 0) return;
  const size_t workers = parallelWorkerCount(threads, count, grain);
  if (workers <= 1) {
    for (size_t c = 0; c < chunks; ++c) body(0, c, c * grain, std::min(count, (c + 1) * grain));
    return;
  }
  std::atomic<size_t> next{0};
  std::atomic<size_t> lowest_error{chunks};  // chunks above it need not run
  std::mutex error_mutex;
  std::exception_ptr error;
  auto work = [&](size_t worker) {
    inside_parallel_body = true;
    // Chunks are claimed in index order and every chunk below the lowest that threw still runs, so the
    // exception kept is the one a serial loop would have stopped at.
    for (size_t c = next++; c < chunks; c = next++) {
      if (c > lowest_error) continue;
      try {
        body(worker, c, c * grain, std::min(count, (c + 1) * grain));
      } catch (...) {
        std::lock_guard<std::mutex> lock(error_mutex);
        if (c < lowest_error) {
          lowest_error = c;
          error = std::current_exception();
        }
      }
    }
    inside_parallel_body = false;
  };
  std::vector<std::thread> pool;
  pool.reserve(workers - 1);
  for (size_t t = 1; t < workers; ++t) pool.emplace_back(work, t);
  work(0);
  for (std::thread& thread : pool) thread.join();
  if (error) std::rethrow_exception(error);
}

void parallelFor(int threads, size_t count, size_t grain,
                 const std::function<void(size_t chunk, size_t begin, size_t end)>& body) {
  parallelForWorkers(threads, count, grain, [&](size_t, size_t chunk, size_t begin, size_t end) { body(chunk, begin, end); });
}

void parallelForEach(int threads, size_t count, const std::function<void(size_t index)>& body) {
  parallelFor(threads, count, 1, [&](size_t, size_t begin, size_t) { body(begin); });
}

}  // namespace rigbake
