#include "gi/shading_rows.h"

#include <algorithm>
#include <cstring>

#include "core/error.h"
#include "gi/shading.h"

namespace terrain::gi {

namespace {

// Receiver rows of the tiles dirty in either set.
std::vector<std::uint8_t> dirtyReceiverRows(const ReceiverTiles& env, const ReceiverTiles& keys) {
    std::vector<std::uint8_t> out(static_cast<std::size_t>(env.nyr), 0);
    for (int ty = 0; ty < env.tilesY; ++ty) {
        bool dirty = false;
        for (int tx = 0; tx < env.tilesX && !dirty; ++tx) dirty = env.isDirty(tx, ty) || keys.isDirty(tx, ty);
        if (!dirty) continue;
        const int y0 = ty * env.tileSize, y1 = std::min(env.nyr, y0 + env.tileSize);
        std::fill(out.begin() + y0, out.begin() + y1, std::uint8_t{1});
    }
    return out;
}

}  // namespace

void changedShadingRows(ConstGridView before, ConstGridView after, const ReceiverTiles& env, const ReceiverTiles& keys,
                        int subsample, std::vector<std::uint8_t>& rows) {
    const int nx = after.nx, ny = after.ny;
    if (before.nx != nx || before.ny != ny)
        throw InputError("shading rows: the heights before and after differ in size");
    if (keys.nxr != env.nxr || keys.nyr != env.nyr || keys.tileSize != env.tileSize)
        throw InputError("shading rows: the environment's and the key lights' tiles differ");
    rows.assign(static_cast<std::size_t>(ny), 0);
    for (int y = 0; y < ny; ++y)
        if (std::memcmp(before.row(y), after.row(y), sizeof(float) * static_cast<std::size_t>(nx)) != 0)
            for (int r = std::max(0, y - 1); r <= std::min(ny - 1, y + 1); ++r) rows[static_cast<std::size_t>(r)] = 1;
    const std::vector<std::uint8_t> receivers = dirtyReceiverRows(env, keys);
    for (int y = 0; y < ny; ++y) {
        const ReceiverLerp r = receiverLerp(y, subsample, env.nyr);
        if (receivers[static_cast<std::size_t>(r.i0)] != 0 || receivers[static_cast<std::size_t>(r.i1)] != 0)
            rows[static_cast<std::size_t>(y)] = 1;
    }
}

}  // namespace terrain::gi
