#pragma once
// The only place that includes TBB. Parallel loops hand the body a chunk
// [begin, end) (pbrt style). Reductions are deterministic: the range is cut
// into fixed chunks that do not depend on the thread count, each chunk is
// reduced serially, and the partial results are combined in chunk order, so
// the result is bit-identical for any number of threads.
#include <algorithm>
#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/task_arena.h>

#include "core/grid.h"

namespace terrain {

/// Calls fn(begin, end) over chunks of [begin, end), in parallel.
/// Bodies must write only data owned by their indices (gather, never scatter).
template <class Fn>
void parallelFor(int begin, int end, int grain, Fn&& fn) {
    if (end <= begin) return;
    grain = std::max(grain, 1);
    if (end - begin <= grain) {
        fn(begin, end);
        return;
    }
    tbb::parallel_for(tbb::blocked_range<int>(begin, end, grain),
                      [&](const tbb::blocked_range<int>& r) { fn(r.begin(), r.end()); });
}

/// a() and b() side by side: two independent passes whose own loops are
/// parallel but short (a local change's plans), so that neither thread waits
/// at the end of one for the other's last chunk. They must write disjoint data.
template <class A, class B>
void parallelInvoke(A&& a, B&& b) {
    tbb::parallel_invoke(std::forward<A>(a), std::forward<B>(b));
}

/// fn(item) for each of `items` in parallel, each item a chunk of its own
/// at most: for a loop over fixed blocks of which a few have work (a local
/// change's tiles), given only those, so that the threads share them
/// instead of one thread finding them all in its part of the range.
template <class Fn>
void parallelForEach(const std::vector<int>& items, Fn&& fn) {
    parallelFor(0, static_cast<int>(items.size()), 1, [&](int i0, int i1) {
        for (int i = i0; i < i1; ++i) fn(items[static_cast<std::size_t>(i)]);
    });
}

/// The blocks of [0, nBlocks) holding a row for which hasRow(y) is true,
/// block b being the rows rowsOf(b) (a RowSpan), in order, into out: the
/// items a pass over fixed row blocks hands to parallelForEach.
template <class RowsOf, class HasRow>
void blocksWithRows(int nBlocks, RowsOf&& rowsOf, HasRow&& hasRow, std::vector<int>& out) {
    out.clear();
    for (int b = 0; b < nBlocks; ++b) {
        const RowSpan r = rowsOf(b);
        for (int y = r.y0; y < r.y1; ++y)
            if (hasRow(y)) {
                out.push_back(b);
                break;
            }
    }
}

/// Rows [rows.y0, rows.y1) (cut to the grid already) in parallel, with a
/// grain that keeps chunks around 16k cells; fn(y0, y1) gets row numbers.
template <class Fn>
void parallelForRows(RowSpan rows, int nx, Fn&& fn) {
    const int grain = std::max(1, 16384 / std::max(nx, 1));
    parallelFor(rows.y0, rows.y1, grain, std::forward<Fn>(fn));
}

/// Rows [0, ny) in parallel (parallelForRows above).
template <class Fn>
void parallelForRows(int ny, int nx, Fn&& fn) {
    parallelForRows(RowSpan{0, ny}, nx, std::forward<Fn>(fn));
}

/// How many threads may run a parallel loop's bodies at once here, and the
/// calling thread's slot among them, in [0, workerSlots()): loop bodies that
/// need scratch take it per slot instead of per chunk (a body never runs
/// inside another body of the same thread unless it starts a parallel loop
/// itself). Results must not depend on which slot's scratch a body gets.
inline int workerSlots() { return std::max(1, tbb::this_task_arena::max_concurrency()); }
inline int workerSlot() { return std::max(0, tbb::this_task_arena::current_thread_index()); }

/// Runs fn() so that, while it waits for the parallel loops it starts, the
/// calling thread runs only their bodies (tbb::this_task_arena::isolate). A
/// loop body that takes per-slot scratch (workerSlot) and starts nested
/// loops runs them in here: otherwise another body of the outer loop could
/// start on its thread meanwhile and take the same scratch.
template <class Fn>
void isolated(Fn&& fn) {
    tbb::this_task_arena::isolate(std::forward<Fn>(fn));
}

/// Deterministic reduction over [begin, end) with chunks of fixed size.
/// map(b, e) -> T reduces one chunk serially; combine(T, T) -> T folds the
/// partial results in chunk order.
template <class T, class Map, class Combine>
T deterministicReduce(int begin, int end, int chunk, T init, Map&& map, Combine&& combine) {
    if (end <= begin) return init;
    chunk = std::max(chunk, 1);
    const int nChunks = (end - begin + chunk - 1) / chunk;
    std::vector<T> partial(static_cast<std::size_t>(nChunks), init);
    tbb::parallel_for(tbb::blocked_range<int>(0, nChunks, 1), [&](const tbb::blocked_range<int>& r) {
        for (int c = r.begin(); c < r.end(); ++c) {
            const int b = begin + c * chunk;
            const int e = std::min(end, b + chunk);
            partial[static_cast<std::size_t>(c)] = map(b, e);
        }
    });
    T acc = init;
    for (const T& p : partial) acc = combine(acc, p);
    return acc;
}

/// Runs fn with exactly `threads` worker threads (0 = all hardware threads).
/// Only mains, tests and benchmarks call this: libraries never fix the
/// thread count of their caller.
template <class Fn>
auto withThreads(int threads, Fn&& fn) -> decltype(fn()) {
    if (threads <= 0) return fn();
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(threads));
    tbb::task_arena arena(threads);
    return arena.execute([&] { return fn(); });
}

}  // namespace terrain
