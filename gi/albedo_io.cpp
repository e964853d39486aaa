#include "gi/albedo_io.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <sstream>
#include <vector>

#include <png.h>

#include "core/error.h"
#include "core/parse.h"
#include "core/png_io.h"

namespace terrain::gi {

namespace {
float srgbToLinear(std::uint8_t v) {
    const float c = static_cast<float>(v) / 255.0f;
    return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f);
}
}  // namespace

AlbedoMap loadAlbedo(const std::string& spec, int nx, int ny) {
    AlbedoMap m;
    const bool looksNumeric = !spec.empty() && spec.find(',') != std::string::npos &&
                              spec.find_first_not_of("0123456789.,eE+- ") == std::string::npos;
    if (looksNumeric) {
        const std::vector<float> v = parseNumberList(spec, "--albedo");
        if (v.size() != 3) throw InputError("--albedo '" + spec + "': expected R,G,B or a PNG file");
        for (float a : v)
            if (!(a >= 0.0f && a <= 1.0f)) throw InputError("--albedo '" + spec + "': each value must be in [0, 1]");
        for (int c = 0; c < 3; ++c)
            m.channel[static_cast<std::size_t>(c)].resize(nx, ny, v[static_cast<std::size_t>(c)]);
        return m;
    }
    // the header first: the size must match before anything is allocated
    const PngHeader header = peekPngHeader(spec);
    if (header.width != nx || header.height != ny)
        throw InputError("--albedo " + spec + ": " + std::to_string(header.width) + " x " +
                         std::to_string(header.height) + " pixels, the height field has " + std::to_string(nx) + " x " +
                         std::to_string(ny));
    png_image img;
    std::memset(&img, 0, sizeof img);
    img.version = PNG_IMAGE_VERSION;
    if (!png_image_begin_read_from_file(&img, spec.c_str()))
        throw IoError(spec, std::string("cannot read PNG: ") + img.message);
    img.format = PNG_FORMAT_RGB;
    if (static_cast<int>(img.width) != nx || static_cast<int>(img.height) != ny) {
        png_image_free(&img);
        throw IoError(spec, "the PNG changed while it was being read");
    }
    std::vector<std::uint8_t> px(PNG_IMAGE_SIZE(img));
    if (!png_image_finish_read(&img, nullptr, px.data(), 0, nullptr))
        throw IoError(spec, std::string("cannot decode PNG: ") + img.message);
    for (int c = 0; c < 3; ++c) m.channel[static_cast<std::size_t>(c)].resize(nx, ny);
    for (std::size_t i = 0; i < static_cast<std::size_t>(nx) * ny; ++i)
        for (int c = 0; c < 3; ++c)
            m.channel[static_cast<std::size_t>(c)].v[i] = srgbToLinear(px[3 * i + static_cast<std::size_t>(c)]);
    return m;
}

void loadPhongExponentMap(const std::string& file, int nx, int ny, float lo, float hi, AlbedoMap& map) {
    if (!(lo >= kMinPhongExponent && hi <= kMaxPhongExponent && lo <= hi))
        throw InputError("--phong-exponent-range: need " + std::to_string(kMinPhongExponent) +
                         " <= MIN <= MAX <= " + std::to_string(kMaxPhongExponent));
    const PngHeader header = peekPngHeader(file);  // the size must match before the image is decoded
    if (header.width != nx || header.height != ny)
        throw InputError("--phong-exponent " + file + ": " + std::to_string(header.width) + " x " +
                         std::to_string(header.height) + " pixels, the height field has " + std::to_string(nx) + " x " +
                         std::to_string(ny));
    const Grid raw = readPngHeightmap(file, 1.0f, 0.0f);
    if (raw.nx != nx || raw.ny != ny) throw IoError(file, "the PNG changed while it was being read");
    Grid s(nx, ny);
    const double ratio = static_cast<double>(hi) / lo;
    for (std::size_t i = 0; i < s.v.size(); ++i) {
        const double e = lo * std::pow(ratio, raw.v[i] / 65535.0);
        s.v[i] = static_cast<float>(std::clamp(e, static_cast<double>(lo), static_cast<double>(hi)));
    }
    setPhongExponentMap(map, s);
}

}  // namespace terrain::gi
