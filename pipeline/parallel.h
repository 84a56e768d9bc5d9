// Data-parallel loops for the bake's per-vertex, per-frame and per-pose work, on plain std::threads.
//
// Results never depend on the thread count: [0, count) is cut into chunks that depend only on count
// and grain, each chunk writes its own outputs, and callers combine per-chunk results in chunk order
// (never in completion order). A body that throws stops the loop; the exception of the lowest chunk
// that threw is rethrown, which is the one a serial loop would have thrown.
#pragma once

#include <cstddef>
#include <functional>

namespace rigbake {

// `requested` when positive, else the hardware's concurrency (at least 1): what `--threads 0` or no
// --threads means.
int resolveThreadCount(int requested);

// How many chunks parallelFor() cuts [0, count) into: ceil(count / grain), grain >= 1.
size_t parallelChunkCount(size_t count, size_t grain);

// Calls body(chunk, begin, end) for every chunk [begin, end) = [chunk * grain, min(count, (chunk + 1) *
// grain)) on up to resolveThreadCount(threads) threads, the calling thread one of them. Inside a body,
// parallelFor runs serially (no nested threads), so stages may call each other freely.
void parallelFor(int threads, size_t count, size_t grain,
                 const std::function<void(size_t chunk, size_t begin, size_t end)>& body);

// How many threads parallelFor() and parallelForWorkers() run [0, count) on: at most one per chunk,
// and 1 inside a parallel body.
size_t parallelWorkerCount(int threads, size_t count, size_t grain);

// parallelFor whose body also gets the index of the worker running it (below parallelWorkerCount()),
// so that each worker can keep scratch memory from chunk to chunk instead of allocating per chunk.
// Which worker runs a chunk varies from run to run: what a chunk writes must not depend on it.
void parallelForWorkers(int threads, size_t count, size_t grain,
                        const std::function<void(size_t worker, size_t chunk, size_t begin, size_t end)>& body);

// parallelFor with one item per chunk: body(i) for every i in [0, count).
void parallelForEach(int threads, size_t count, const std::function<void(size_t index)>& body);

}  // namespace rigbake
