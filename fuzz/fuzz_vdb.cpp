// Fuzz target: OpenVDB terrain frames (sim/vdb_io readVdb), with every
// optional layer the reader may fill.
#include <cmath>

#include "fuzz/fuzz_input.h"
#include "sim/vdb_io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    static terrain::fuzz::InputFile file(".vdb");
    const std::string& path = file.write(data, size);
    terrain::fuzz::expectSuccessOrError([&] {
        terrain::TerrainState s;
        terrain::LayerSet layers;
        layers.water = true;
        layers.sediment = true;
        terrain::readVdb(path, s, layers);
        terrain::fuzz::require(s.nx > 0 && s.ny > 0 && s.bedrock.nx == s.nx && s.bedrock.ny == s.ny,
                               "the state's size matches its bedrock");
        for (float v : s.bedrock.v) terrain::fuzz::require(std::isfinite(v), "heights are finite");
    });
    return 0;
}
