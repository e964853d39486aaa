// PNG reading and writing through libpng.
#include "core/png_io.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>

#include <png.h>

#include "core/error.h"
#include "core/file_io.h"

namespace terrain {

// ---------------------------------------------------------------------------
// PNG reading
// ---------------------------------------------------------------------------
namespace {

struct PngReadContext {
    std::string file;
    std::string message;
};

[[noreturn]] void pngError(png_structp png, png_const_charp msg) {
    auto* ctx = static_cast<PngReadContext*>(png_get_error_ptr(png));
    if (ctx) ctx->message = msg;
    png_longjmp(png, 1);
}
void pngWarning(png_structp, png_const_charp) {}

struct FileCloser {
    void operator()(std::FILE* f) const {
        if (f) std::fclose(f);
    }
};
using FilePtr = std::unique_ptr<std::FILE, FileCloser>;

// Reads a greyscale PNG into 16-bit samples. Returns false and sets ctx.message
// on a libpng error (setjmp-based, so no C++ objects with destructors live
// across the setjmp in this function other than the plain vector data).
bool readGrey16(std::FILE* f, PngReadContext& ctx, int& width, int& height, std::vector<std::uint16_t>& out,
                int& colorTypeOut) {
    png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &ctx, pngError, pngWarning);
    if (!png) {
        ctx.message = "out of memory";
        return false;
    }
    png_infop info = png_create_info_struct(png);
    if (!info) {
        png_destroy_read_struct(&png, nullptr, nullptr);
        ctx.message = "out of memory";
        return false;
    }
    std::vector<png_bytep>* rows = new std::vector<png_bytep>();
    if (setjmp(png_jmpbuf(png))) {
        png_destroy_read_struct(&png, &info, nullptr);
        delete rows;
        return false;
    }
    png_init_io(png, f);
    png_set_user_limits(png, 65536, 65536);
    png_read_info(png, info);
    const png_uint_32 w = png_get_image_width(png, info);
    const png_uint_32 h = png_get_image_height(png, info);
    const int bitDepth = png_get_bit_depth(png, info);
    const int colorType = png_get_color_type(png, info);
    colorTypeOut = colorType;
    if (colorType != PNG_COLOR_TYPE_GRAY && colorType != PNG_COLOR_TYPE_GRAY_ALPHA) {
        png_destroy_read_struct(&png, &info, nullptr);
        delete rows;
        ctx.message = "not a greyscale PNG (a heightmap must have one channel)";
        return false;
    }
    if (colorType == PNG_COLOR_TYPE_GRAY_ALPHA) png_set_strip_alpha(png);
    if (bitDepth < 8) png_set_expand_gray_1_2_4_to_8(png);
    if (bitDepth == 16) png_set_swap(png);  // PNG stores big-endian; we want host order
    png_read_update_info(png, info);
    const std::size_t rowBytes = png_get_rowbytes(png, info);
    width = static_cast<int>(w);
    height = static_cast<int>(h);
    std::vector<unsigned char> buffer(rowBytes * h);
    rows->resize(h);
    for (png_uint_32 y = 0; y < h; ++y) (*rows)[y] = buffer.data() + y * rowBytes;
    png_read_image(png, rows->data());
    png_read_end(png, nullptr);
    png_destroy_read_struct(&png, &info, nullptr);
    delete rows;
    out.resize(static_cast<std::size_t>(w) * h);
    if (bitDepth == 16) {
        for (std::size_t i = 0; i < out.size(); ++i) std::memcpy(&out[i], buffer.data() + 2 * i, 2);
    } else {
        // 8-bit (or expanded lower depths): scale to the 16-bit range (v * 257)
        for (std::size_t i = 0; i < out.size(); ++i) out[i] = static_cast<std::uint16_t>(buffer[i] * 257u);
    }
    return true;
}

}  // namespace

Grid readPngHeightmap(const std::string& file, float zScale, float zOffset) {
    if (!std::isfinite(zScale) || !std::isfinite(zOffset))
        throw InputError("height mapping for " + file + " is not finite (z-scale " + std::to_string(zScale) +
                         ", z-offset " + std::to_string(zOffset) + ")");
    FilePtr f(std::fopen(file.c_str(), "rb"));
    if (!f) throw IoError(file, std::string("cannot open: ") + std::strerror(errno));
    unsigned char sig[8] = {};
    if (std::fread(sig, 1, 8, f.get()) != 8 || png_sig_cmp(sig, 0, 8) != 0)
        throw IoError(file, "not a PNG file (bad signature)");
    std::rewind(f.get());
    PngReadContext ctx{file, {}};
    int w = 0, h = 0, colorType = 0;
    std::vector<std::uint16_t> samples;
    if (!readGrey16(f.get(), ctx, w, h, samples, colorType))
        throw IoError(file, "corrupt or truncated PNG: " + ctx.message);
    Grid g(w, h);
    for (std::size_t i = 0; i < samples.size(); ++i) g.v[i] = zOffset + zScale * static_cast<float>(samples[i]);
    for (float v : g.v)
        if (!std::isfinite(v)) throw IoError(file, "height mapping produces non-finite heights");
    return g;
}

// ---------------------------------------------------------------------------
// PNG writing
// ---------------------------------------------------------------------------
namespace {
bool writePngRaw(std::FILE* f, int width, int height, int channels, int bitDepth, const unsigned char* data,
                 std::string& message) {
    PngReadContext ctx{"", {}};
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &ctx, pngError, pngWarning);
    if (!png) return false;
    png_infop info = png_create_info_struct(png);
    if (!info) {
        png_destroy_write_struct(&png, nullptr);
        return false;
    }
    if (setjmp(png_jmpbuf(png))) {
        message = ctx.message;
        png_destroy_write_struct(&png, &info);
        return false;
    }
    static const int kTypes[] = {PNG_COLOR_TYPE_GRAY, PNG_COLOR_TYPE_GRAY_ALPHA, PNG_COLOR_TYPE_RGB,
                                 PNG_COLOR_TYPE_RGB_ALPHA};
    png_init_io(png, f);
    png_set_compression_level(png, 6);
    png_set_IHDR(png, info, static_cast<png_uint_32>(width), static_cast<png_uint_32>(height), bitDepth,
                 kTypes[channels - 1], PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    png_write_info(png, info);
    if (bitDepth == 16) png_set_swap(png);
    const std::size_t rowBytes = static_cast<std::size_t>(width) * channels * (bitDepth / 8);
    for (int y = 0; y < height; ++y) png_write_row(png, const_cast<png_bytep>(data + rowBytes * y));
    png_write_end(png, nullptr);
    png_destroy_write_struct(&png, &info);
    return true;
}
}  // namespace

void writePng(const std::string& file, int width, int height, int channels, int bitDepth, const void* pixels) {
    if (width < 1 || height < 1 || channels < 1 || channels > 4 || (bitDepth != 8 && bitDepth != 16))
        throw InputError("cannot write " + file + ": bad image shape");
    const std::string tmp = temporaryNameFor(file);
    std::FILE* f = std::fopen(tmp.c_str(), "wb");
    if (!f) throw IoError(file, std::string("cannot open for writing: ") + std::strerror(errno));
    std::string message;
    const bool ok =
        writePngRaw(f, width, height, channels, bitDepth, static_cast<const unsigned char*>(pixels), message);
    const bool closed = std::fclose(f) == 0;
    if (!ok || !closed) {
        std::remove(tmp.c_str());
        throw IoError(file, "PNG write failed" + (message.empty() ? std::string() : ": " + message));
    }
    commitTemporary(tmp, file);
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
