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

void changedShadingTiles(ConstGridView before, ConstGridView after, const ReceiverTiles& env, const ReceiverTiles& keys,
                         int subsample, ReceiverTiles& out) {
    checkSizes(before, after, env, keys);
    const ReceiverTiles* recomputed[] = {&env, &keys};
    texelTilesToRedo(recomputed, &before, after, subsample, shadingReach(subsample), out);
}

void changedDirectTiles(ConstGridView before, ConstGridView after, const ReceiverTiles& env, const ReceiverTiles& keys,
                        int subsample, ReceiverTiles& ambient, ReceiverTiles& shading) {
    checkSizes(before, after, env, keys);
    const int reach = shadingReach(subsample);
    const ReceiverTiles* envOnly[] = {&env};
    texelTilesToRedo(envOnly, &before, after, subsample, reach, ambient);
    if (keys.dirtyCount() == 0) {
        shading = ambient;
        return;
    }
    // the texels that read a recomputed key tile, the heights already counted in `ambient`
    const ReceiverTiles* keysOnly[] = {&keys};
    texelTilesToRedo(keysOnly, nullptr, after, subsample, reach, shading);
    for (std::size_t i = 0; i < shading.dirty.size(); ++i) shading.dirty[i] |= ambient.dirty[i];
}

}  // namespace terrain::gi
