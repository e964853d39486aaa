// Fuzz target: 16-bit greyscale PNG heightmaps (core/png_io readPngHeightmap).
#include <cmath>

#include "core/png_io.h"
#include "fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    static terrain::fuzz::InputFile file(".png");
    const std::string& path = file.write(data, size);
    terrain::fuzz::expectSuccessOrError([&] {
        // a mapping with an offset, as the DEMs use: every sample maps to a finite height
        const terrain::Grid g = terrain::readPngHeightmap(path, 0.25f, -100.0f);
        terrain::fuzz::require(g.nx > 0 && g.ny > 0 && g.v.size() == static_cast<std::size_t>(g.nx) * g.ny,
                               "the grid's size matches its samples");
        for (float v : g.v) terrain::fuzz::require(std::isfinite(v), "heights are finite");
    });
    return 0;
}
