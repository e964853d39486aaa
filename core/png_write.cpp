// PNG writing through libpng into a checked atomic file (core/file_io.h).
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/file_io.h"
#include "core/png_error.h"
#include "core/png_io.h"

namespace terrain {
namespace {

using png_detail::PngErrorText;

struct PngImage {
    int width, height, channels, bitDepth;
    const unsigned char* data;
};

// Encodes the image into f. setjmp-safe: plain C types only (libpng's
// structures are destroyed here on both ways out).
bool encodePng(std::FILE* f, const PngImage* image, PngErrorText* error) {
    png_structp png =
        png_create_write_struct(PNG_LIBPNG_VER_STRING, error, png_detail::onPngError, png_detail::onPngWarning);
    if (!png) return false;
    png_infop info = png_create_info_struct(png);
    if (!info) {
        png_destroy_write_struct(&png, nullptr);
        return false;
    }
    if (setjmp(png_jmpbuf(png))) {
        png_destroy_write_struct(&png, &info);
        return false;
    }
    static const int kTypes[] = {PNG_COLOR_TYPE_GRAY, PNG_COLOR_TYPE_GRAY_ALPHA, PNG_COLOR_TYPE_RGB,
                                 PNG_COLOR_TYPE_RGB_ALPHA};
    png_init_io(png, f);
    png_set_compression_level(png, 6);
    png_set_IHDR(png, info, static_cast<png_uint_32>(image->width), static_cast<png_uint_32>(image->height),
                 image->bitDepth, kTypes[image->channels - 1], PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT,
                 PNG_FILTER_TYPE_DEFAULT);
    png_write_info(png, info);
    if (image->bitDepth == 16) png_set_swap(png);
    const std::size_t rowBytes = static_cast<std::size_t>(image->width) * image->channels * (image->bitDepth / 8);
    for (int y = 0; y < image->height; ++y) png_write_row(png, image->data + rowBytes * y);
    png_write_end(png, nullptr);
    png_destroy_write_struct(&png, &info);
    return true;
}

}  // namespace

void writePng(const std::string& file, int width, int height, int channels, int bitDepth, const void* pixels) {
    if (width < 1 || height < 1 || channels < 1 || channels > 4 || (bitDepth != 8 && bitDepth != 16))
        throw InputError("cannot write " + file + ": bad image shape");
    AtomicFile out(file);
    const PngImage image{width, height, channels, bitDepth, static_cast<const unsigned char*>(pixels)};
    PngErrorText error;
    errno = 0;
    if (!encodePng(out.stream(), &image, &error)) {
        const int why = errno;  // libpng's "Write Error" hides the cause a failed fwrite left here
        throw IoError(
            file, std::string("PNG write failed: ") + error.text + (why ? std::string(": ") + std::strerror(why) : ""));
    }
    out.commit();
}

void writePngRgb(const std::string& file, int width, int height, const std::vector<std::uint8_t>& pixels,
                 int channels) {
    if (pixels.size() != static_cast<std::size_t>(width) * height * channels)
        throw InputError("cannot write " + file + ": pixel buffer size does not match the image");
    writePng(file, width, height, channels, 8, pixels.data());
}

void pngRangeFor(const Grid& height, float& zScale, float& zOffset) {
    float lo = height.v.empty() ? 0.0f : height.v[0], hi = lo;
    for (float v : height.v) {
        lo = std::min(lo, v);
        hi = std::max(hi, v);
    }
    zOffset = lo;
    zScale = hi > lo ? (hi - lo) / 65535.0f : 1.0f;
}

void writePngHeightmap(const std::string& file, const Grid& height, float zScale, float zOffset) {
    if (!(zScale > 0.0f) || !std::isfinite(zScale) || !std::isfinite(zOffset))
        throw InputError("cannot write " + file + ": z-scale must be positive and finite");
    std::vector<std::uint16_t> samples(height.size());
    for (std::size_t i = 0; i < samples.size(); ++i) {
        const float h = height.v[i];
        if (!std::isfinite(h)) throw InputError("cannot write " + file + ": heights contain NaN or Inf");
        const double q = std::nearbyint((static_cast<double>(h) - zOffset) / zScale);
        samples[i] = static_cast<std::uint16_t>(std::clamp(q, 0.0, 65535.0));
    }
    writePng(file, height.nx, height.ny, 1, 16, samples.data());
}

}  // namespace terrain
