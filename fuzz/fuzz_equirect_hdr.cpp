// Fuzz target: .hdr equirectangular environment maps (core/image_io readEquirect).
#include "fuzz/fuzz_equirect.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    static terrain::fuzz::InputFile file(".hdr");
    terrain::fuzz::fuzzEquirect(file, data, size);
    return 0;
}
