// Radiance RGBE (.hdr): header lines, a blank line, "-Y H +X W", then
// new-style run-length encoded scanlines (or flat RGBE pixels). The file is
// read once; the declared size is checked against the limit and against the
// bytes the file has left before the image is allocated.
#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "core/error.h"
#include "core/file_io.h"
#include "core/image_io.h"
#include "core/size_limits.h"

namespace terrain {
namespace {

// Radiance headers are a few short lines (program, format, exposure).
constexpr std::size_t kMaxHeaderBytes = 64 * 1024;

struct HdrLayout {
    std::int64_t width = 0, height = 0;
    std::size_t dataStart = 0;
};

// The next '\n'-terminated line from pos (advanced past it); IoError when
// the header runs past its bound or the end of the file.
std::string_view nextLine(const std::string& file, std::string_view bytes, std::size_t& pos) {
    const std::size_t end = bytes.find('\n', pos);
    if (end == std::string_view::npos || end > kMaxHeaderBytes)
        throw IoError(file, "HDR header is unterminated or longer than " + std::to_string(kMaxHeaderBytes) + " bytes");
    const std::string_view line = bytes.substr(pos, end - pos);
    pos = end + 1;
    return line;
}

// "-Y H +X W" (blanks between the fields, H and W decimal integers); false
// otherwise.
bool parseResolution(std::string_view line, std::int64_t& width, std::int64_t& height) {
    std::string_view fields[5];
    int count = 0;
    for (std::size_t pos = 0; count < 5;) {
        pos = line.find_first_not_of(" \t\r", pos);
        if (pos == std::string_view::npos) break;
        const std::size_t end = std::min(line.find_first_of(" \t\r", pos), line.size());
        fields[count++] = line.substr(pos, end - pos);
        pos = end;
    }
    auto integer = [](std::string_view text, std::int64_t& out) {
        const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), out);
        return ec == std::errc() && end == text.data() + text.size();
    };
    return count == 4 && fields[0] == "-Y" && fields[2] == "+X" && integer(fields[1], height) &&
           integer(fields[3], width);
}

HdrLayout readHeader(const std::string& file, std::string_view bytes) {
    std::size_t pos = 0;
    if (bytes.substr(0, 2) != "#?") throw IoError(file, "not a Radiance HDR file");
    bool formatOk = false;
    for (std::string_view line = nextLine(file, bytes, pos); !line.empty(); line = nextLine(file, bytes, pos))
        if (line.substr(0, 22) == "FORMAT=32-bit_rle_rgbe") formatOk = true;
    if (!formatOk) throw IoError(file, "unsupported HDR format (need 32-bit_rle_rgbe)");
    HdrLayout layout;
    const std::string_view resolution = nextLine(file, bytes, pos);
    if (!parseResolution(resolution, layout.width, layout.height))
        throw IoError(file, "unsupported resolution line '" + std::string(resolution) + "' (need -Y H +X W)");
    checkDeclaredSize(file, layout.width, layout.height, "pixels");
    layout.dataStart = pos;
    // the shortest scanline: run-length encoded, 4 channels of 2-byte runs of
    // up to 128 pixels, after its 4-byte marker; flat RGBE when too narrow
    const std::int64_t w = layout.width;
    const std::int64_t minRowBytes = (w >= 8 && w < 32768) ? 4 + 8 * ((w + 127) / 128) : 4 * w;
    if (static_cast<std::int64_t>(bytes.size() - pos) < minRowBytes * layout.height)
        throw IoError(file, "truncated HDR: " + std::to_string(bytes.size()) + " bytes cannot hold " +
                                std::to_string(w) + " x " + std::to_string(layout.height) + " pixels");
    return layout;
}

// Decodes one scanline of RGBE quadruples into scan (4 bytes per pixel).
void readScanline(const std::string& file, std::string_view bytes, std::size_t& pos, int w, unsigned char* scan) {
    auto byte = [&]() -> unsigned char {
        if (pos >= bytes.size()) throw IoError(file, "truncated HDR pixel data");
        return static_cast<unsigned char>(bytes[pos++]);
    };
    const unsigned char b0 = byte(), b1 = byte(), b2 = byte(), b3 = byte();
    if (!(w >= 8 && w < 32768 && b0 == 2 && b1 == 2 && ((b2 << 8) | b3) == w)) {
        scan[0] = b0;
        scan[1] = b1;
        scan[2] = b2;
        scan[3] = b3;
        for (int x = 1; x < w; ++x)
            for (int c = 0; c < 4; ++c) scan[static_cast<std::size_t>(x) * 4 + c] = byte();
        return;
    }
    for (int c = 0; c < 4; ++c)
        for (int x = 0; x < w;) {
            int count = byte();
            const bool run = count > 128;
            if (run) count -= 128;
            if (count == 0 || x + count > w) throw IoError(file, "corrupt HDR: bad run length");
            const unsigned char value = run ? byte() : 0;
            for (int k = 0; k < count; ++k) scan[static_cast<std::size_t>(x++) * 4 + c] = run ? value : byte();
        }
}

}  // namespace

std::vector<float> readHdrRgb(const std::string& file, int& width, int& height) {
    const std::string bytes = readFileBytes(file);
    const HdrLayout layout = readHeader(file, bytes);
    const int w = static_cast<int>(layout.width), h = static_cast<int>(layout.height);
    std::vector<float> rgb(static_cast<std::size_t>(w) * h * 3);
    std::vector<unsigned char> scan(static_cast<std::size_t>(w) * 4);
    std::size_t pos = layout.dataStart;
    for (int y = 0; y < h; ++y) {
        readScanline(file, bytes, pos, w, scan.data());
        for (int x = 0; x < w; ++x) {
            const unsigned char* p = &scan[static_cast<std::size_t>(x) * 4];
            const float f = p[3] ? std::ldexp(1.0f, p[3] - 136) : 0.0f;
            float* o = &rgb[(static_cast<std::size_t>(y) * w + x) * 3];
            o[0] = p[0] * f;
            o[1] = p[1] * f;
            o[2] = p[2] * f;
        }
    }
    width = w;
    height = h;
    return rgb;
}

}  // namespace terrain
