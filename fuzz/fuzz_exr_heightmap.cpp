// Fuzz target: float EXR heightmaps and frames (sim/heightmap_io readHeightmap
// for .exr: the `height` channel or the only one), and every channel of a
// frame (core/image_io readExrChannels).
#include <cmath>

#include "core/image_io.h"
#include "fuzz/fuzz_input.h"
#include "sim/heightmap_io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    static terrain::fuzz::InputFile file(".exr");
    const std::string& path = file.write(data, size);
    terrain::fuzz::expectSuccessOrError([&] {
        float cell = 0.0f;
        const terrain::Grid g = terrain::readHeightmap(path, 1.0f, 0.0f, &cell);
        terrain::fuzz::require(g.nx >= 2 && g.ny >= 2 && g.v.size() == static_cast<std::size_t>(g.nx) * g.ny,
                               "the grid's size matches its samples");
        for (float v : g.v) terrain::fuzz::require(std::isfinite(v), "heights are finite");
    });
    terrain::fuzz::expectSuccessOrError([&] {
        const terrain::ExrChannels exr = terrain::readExrChannels(path);
        terrain::fuzz::require(exr.grids.size() == exr.names.size() && exr.names.size() == exr.available.size(),
                               "every channel is read");
        for (const terrain::Grid& g : exr.grids)
            terrain::fuzz::require(g.nx > 0 && g.ny > 0 && g.v.size() == static_cast<std::size_t>(g.nx) * g.ny,
                                   "each channel has one value per pixel");
    });
    return 0;
}
