#include "gi/shading_tiles.h"

#include "core/error.h"

namespace terrain::gi {

namespace {

void checkSizes(ConstGridView before, ConstGridView after, const ReceiverTiles& env, const ReceiverTiles& keys) {
    if (before.nx != after.nx || before.ny != after.ny)
        throw InputError("shading tiles: the heights before and after differ in size");
    if (keys.nxr != env.nxr || keys.nyr != env.nyr || keys.tileSize != env.tileSize)
        throw InputError("shading tiles: the environment's and the key lights' tiles differ");
}

}  // namespace

void changedDirectTexels(ConstGridView before, ConstGridView after, const ReceiverTiles& env, const ReceiverTiles& keys,
                         int subsample, std::vector<TexelRect>& rects, TexelRuns& ambient, TexelRuns& shading,
                         CellBox differing) {
    checkSizes(before, after, env, keys);
    rects.clear();
    appendTexelsToRedo(env, &before, after, subsample, shadingReach(subsample), rects, nullptr, differing);
    texelRunsOfRects(rects, after.nx, after.ny, ambient);
    if (keys.dirtyCount() == 0) {
        shading = ambient;
        return;
    }
    appendTexelsToRedo(keys, nullptr, after, subsample, 0, rects);  // the heights are counted already
    texelRunsOfRects(rects, after.nx, after.ny, shading);
}

}  // namespace terrain::gi
