#include "gi/shading_tiles.h"

#include "core/error.h"

namespace terrain::gi {

void changedShadingTiles(ConstGridView before, ConstGridView after, const ReceiverTiles& env, const ReceiverTiles& keys,
                         int subsample, ReceiverTiles& out) {
    if (before.nx != after.nx || before.ny != after.ny)
        throw InputError("shading tiles: the heights before and after differ in size");
    if (keys.nxr != env.nxr || keys.nyr != env.nyr || keys.tileSize != env.tileSize)
        throw InputError("shading tiles: the environment's and the key lights' tiles differ");
    const ReceiverTiles* recomputed[] = {&env, &keys};
    texelTilesToRedo(recomputed, &before, after, subsample, shadingReach(subsample), out);
}

}  // namespace terrain::gi
