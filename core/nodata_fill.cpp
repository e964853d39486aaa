// Nodata holes take the nearest valid height: a breadth-first search from
// every valid cell at once, so each hole cell is reached first from its
// nearest valid cell (in 4-connected steps).
#include "core/nodata_fill.h"

#include "core/error.h"

namespace terrain {

std::int64_t fillNodata(Grid& g, const std::vector<std::uint8_t>& masked) {
    const std::size_t n = g.v.size();
    std::vector<std::uint8_t> done(n, 0);
    std::vector<std::size_t> queue;
    queue.reserve(n);
    for (std::size_t i = 0; i < n; ++i)
        if (!masked[i]) {
            done[i] = 1;
            queue.push_back(i);
        }
    if (queue.empty()) throw InputError("every cell is nodata");
    const std::int64_t filled = static_cast<std::int64_t>(n - queue.size());
    for (std::size_t head = 0; head < queue.size(); ++head) {
        const std::size_t i = queue[head];
        const int x = static_cast<int>(i % g.nx), y = static_cast<int>(i / g.nx);
        auto visit = [&](int nx, int ny) {
            if (nx < 0 || ny < 0 || nx >= g.nx || ny >= g.ny) return;
            const std::size_t j = static_cast<std::size_t>(ny) * g.nx + nx;
            if (done[j]) return;
            done[j] = 1;
            g.v[j] = g.v[i];
            queue.push_back(j);
        };
        visit(x - 1, y);
        visit(x + 1, y);
        visit(x, y - 1);
        visit(x, y + 1);
    }
    return filled;
}

}  // namespace terrain
