// Fuzz target: .hdr equirectangular environment maps (core/image_io readEquirect).
#include "core/image_io.h"
#include "fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    static terrain::fuzz::InputFile file(".hdr");
    const std::string& path = file.write(data, size);
    terrain::fuzz::expectSuccessOrError([&] {
        int width = 0, height = 0;
        const std::vector<float> rgb = terrain::readEquirect(path, width, height);
        terrain::fuzz::require(width > 0 && height > 0 && rgb.size() == static_cast<std::size_t>(width) * height * 3,
                               "the image's size matches its pixels");
    });
    return 0;
}
