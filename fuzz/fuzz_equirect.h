#pragma once
// The body of the two environment-map targets (.exr and .hdr): both go
// through readEquirect, which dispatches on the file's extension.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "core/image_io.h"
#include "fuzz/fuzz_input.h"

namespace terrain::fuzz {

/// Reads the input as an equirectangular map named with `extension`; a map
/// read must hold three floats for each of its pixels.
inline void fuzzEquirect(InputFile& file, const std::uint8_t* data, std::size_t size) {
    const std::string& path = file.write(data, size);
    expectSuccessOrError([&] {
        int width = 0, height = 0;
        const std::vector<float> rgb = readEquirect(path, width, height);
        require(width > 0 && height > 0 && rgb.size() == static_cast<std::size_t>(width) * height * 3,
                "the image's size matches its pixels");
    });
}

}  // namespace terrain::fuzz
