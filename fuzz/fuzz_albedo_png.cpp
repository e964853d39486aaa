// Fuzz target: 8-bit sRGB albedo maps (gi/albedo_io loadAlbedo with a PNG) for
// a 16 x 16 height field, the size of the seed images.
#include "fuzz/fuzz_input.h"
#include "gi/albedo_io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    static terrain::fuzz::InputFile file(".png");
    const std::string& path = file.write(data, size);
    terrain::fuzz::expectSuccessOrError([&] {
        const terrain::gi::AlbedoMap m = terrain::gi::loadAlbedo(path, 16, 16);
        for (const terrain::Grid& c : m.channel) {
            terrain::fuzz::require(c.nx == 16 && c.ny == 16, "each channel has the field's size");
            for (float v : c.v) terrain::fuzz::require(v >= 0.0f && v <= 1.0f, "albedos are in [0, 1]");
        }
    });
    return 0;
}
