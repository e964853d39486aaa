// NumPy .npy writing, and environment maps by extension (core/exr_io.cpp,
// core/hdr_io.cpp).
#include "core/image_io.h"

#include <cctype>
#include <cstdint>
#include <cstring>

#include "core/error.h"
#include "core/file_io.h"

namespace terrain {

namespace {

std::string lowerExtension(const std::string& file) {
    const auto dot = file.find_last_of('.');
    std::string e = dot == std::string::npos ? "" : file.substr(dot);
    for (char& c : e) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return e;
}

}  // namespace

void writeNpyArray(const std::string& file, const std::vector<std::size_t>& shape, const float* data) {
    std::string dims;
    std::size_t count = 1;
    for (std::size_t d : shape) {
        dims += std::to_string(d) + ", ";
        count *= d;
    }
    if (shape.size() > 1)
        dims.erase(dims.size() - 2);  // "(ny, nx)"; a 1-tuple keeps its comma: "(n,)"
    else if (!dims.empty())
        dims.erase(dims.size() - 1);
    std::string header = "{'descr': '<f4', 'fortran_order': False, 'shape': (" + dims + "), }";
    // magic (6) + version (2) + header length (2) + header, padded to 64 bytes, ending in '\n'
    const std::size_t total = 10 + header.size() + 1;
    header.append((64 - total % 64) % 64, ' ');
    header.push_back('\n');
    std::string bytes = "\x93NUMPY";
    bytes.push_back('\x01');
    bytes.push_back('\x00');
    const std::uint16_t len = static_cast<std::uint16_t>(header.size());
    bytes.push_back(static_cast<char>(len & 0xff));
    bytes.push_back(static_cast<char>(len >> 8));
    bytes += header;
    const std::size_t off = bytes.size();
    bytes.resize(off + count * 4);
    if (count) std::memcpy(&bytes[off], data, count * 4);  // x86-64 is little-endian
    writeFileAtomic(file, bytes);
}

void writeNpy(const std::string& file, const Grid& g) {
    writeNpyArray(file, {static_cast<std::size_t>(g.ny), static_cast<std::size_t>(g.nx)}, g.data());
}

void writeNpyRgb(const std::string& file, const std::array<Grid, 3>& rgb) {
    const Grid& g0 = rgb[0];
    std::vector<float> interleaved(g0.size() * 3);
    for (std::size_t i = 0; i < g0.size(); ++i)
        for (std::size_t c = 0; c < 3; ++c) interleaved[3 * i + c] = rgb[c].v[i];
    writeNpyArray(file, {static_cast<std::size_t>(g0.ny), static_cast<std::size_t>(g0.nx), 3}, interleaved.data());
}

std::vector<float> readEquirect(const std::string& file, int& width, int& height) {
    const std::string ext = lowerExtension(file);
    if (ext == ".exr") return readExrRgb(file, width, height);
    if (ext == ".hdr") return readHdrRgb(file, width, height);
    throw IoError(file, "environment map must be .exr or .hdr");
}

}  // namespace terrain
