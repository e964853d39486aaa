// Fuzz target: 16-bit Phong exponent maps (gi/albedo_io loadPhongExponentMap)
// for a 16 x 16 height field, the size of the seed images, over the default range.
#include "fuzz/fuzz_input.h"
#include "gi/albedo_io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    static terrain::fuzz::InputFile file(".png");
    const std::string& path = file.write(data, size);
    terrain::fuzz::expectSuccessOrError([&] {
        terrain::gi::AlbedoMap m;
        terrain::gi::loadPhongExponentMap(path, 16, 16, 1.0f, 1000.0f, m);
        terrain::fuzz::require(m.phongExponent.nx == 16 && m.phongExponent.ny == 16, "the map has the field's size");
        for (float v : m.phongExponent.v) terrain::fuzz::require(v >= 1.0f && v <= 1000.0f, "exponents are in range");
    });
    return 0;
}
