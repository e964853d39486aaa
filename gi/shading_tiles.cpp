#include "gi/shading_tiles.h"

#include "core/error.h"

namespace terrain::gi {

void changedShadingTiles(ConstGridView before, ConstGridView after, const ReceiverTiles& env, const ReceiverTiles& keys,
                         int subsample, ReceiverTiles& out) {
    const int nx = after.nx, ny = after.ny;
    if (before.nx != nx || before.ny != ny)
        throw InputError("shading tiles: the heights before and after differ in size");
    if (keys.nxr != env.nxr || keys.nyr != env.nyr || keys.tileSize != env.tileSize)
        throw InputError("shading tiles: the environment's and the key lights' tiles differ");
    const int reach = shadingReach(subsample);
    out.reset(env.nxr, env.nyr, env.tileSize, false);
    for (int ty = 0; ty < out.tilesY; ++ty)
        for (int tx = 0; tx < out.tilesX; ++tx) {
            const bool dirty = readsDirtyReceivers(env, tx, ty) || readsDirtyReceivers(keys, tx, ty) ||
                               cellsDiffer(before, after, texelCellsOfTile(env, tx, ty, nx, ny, subsample, reach));
            out.setDirty(tx, ty, dirty);
        }
}

}  // namespace terrain::gi
