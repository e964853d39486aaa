#pragma once
// Asking for a row's cells before a pass reads them.
//
// An incremental GI frame redoes small boxes of large fields (a local
// change's texels, a few dozen a side), each field last read a frame
// earlier: its lines are in memory, not in cache. Read row after row, each
// row's few lines are too short a stream for the hardware's prefetchers,
// so the pass waits on one row's lines after another. Asking for the lines
// of every row of its box first lets the memory system fetch them together.
// A prefetch reads nothing into the program's values: no result changes.

namespace terrain {

/// Asks for the cache lines that hold row[x0 .. x1) (x0 <= x1, inside the row).
inline void prefetchRow(const float* row, int x0, int x1) {
    constexpr int kLineFloats = 16;  // a 64-byte line
    for (int x = x0; x < x1; x += kLineFloats) __builtin_prefetch(row + x);
}

}  // namespace terrain
