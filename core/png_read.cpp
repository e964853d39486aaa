// PNG reading through libpng: the header checked before anything is
// allocated, then the rows (core/png_error.h: setjmp-safe).
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/png_error.h"
#include "core/png_io.h"
#include "core/size_limits.h"

namespace terrain {
namespace {

using png_detail::PngErrorText;

struct FileCloser {
    void operator()(std::FILE* f) const { std::fclose(f); }
};
using FilePtr = std::unique_ptr<std::FILE, FileCloser>;

// Signature, IHDR chunk (length, type, 13 bytes of data, CRC), and the
// smallest IDAT and IEND chunks around a deflate stream.
constexpr long kSignatureAndHeaderBytes = 8 + 8 + 13 + 4;
constexpr long kMinChunkBytesAfterHeader = 12 + 12;
// Deflate codes a 258-byte match in as little as 2 bits, so a stream
// expands at most 1032 times: a file shorter than its pixels / 1032 is
// truncated, whatever it declares.
constexpr std::uint64_t kDeflateMaxRatio = 1032;

std::uint32_t bigEndian32(const unsigned char* p) {
    return (std::uint32_t{p[0]} << 24) | (std::uint32_t{p[1]} << 16) | (std::uint32_t{p[2]} << 8) | p[3];
}

int channelsOf(int colorType) {
    switch (colorType) {
        case PNG_COLOR_TYPE_GRAY:
            return 1;
        case PNG_COLOR_TYPE_GRAY_ALPHA:
            return 2;
        case PNG_COLOR_TYPE_RGB:
            return 3;
        case PNG_COLOR_TYPE_RGB_ALPHA:
            return 4;
        case PNG_COLOR_TYPE_PALETTE:
            return 1;
        default:
            return 0;
    }
}

// Reads the signature and IHDR from the start of f and checks them against
// the size limit and the file's length; leaves f rewound.
PngHeader peekHeader(std::FILE* f, const std::string& file) {
    unsigned char b[kSignatureAndHeaderBytes] = {};
    const std::size_t got = std::fread(b, 1, sizeof b, f);
    if (got < 8 || png_sig_cmp(b, 0, 8) != 0) throw IoError(file, "not a PNG file (bad signature)");
    if (got < sizeof b || bigEndian32(b + 8) != 13 || std::memcmp(b + 12, "IHDR", 4) != 0)
        throw IoError(file, "truncated or corrupt PNG: no valid IHDR header chunk");
    const std::uint32_t width = bigEndian32(b + 16), height = bigEndian32(b + 20);
    PngHeader h;
    h.bitDepth = b[24];
    h.colorType = b[25];
    const int channels = channelsOf(h.colorType);
    if (channels == 0 || (h.bitDepth != 1 && h.bitDepth != 2 && h.bitDepth != 4 && h.bitDepth != 8 && h.bitDepth != 16))
        throw IoError(file, "corrupt PNG: invalid bit depth " + std::to_string(h.bitDepth) + " or colour type " +
                                std::to_string(h.colorType));
    checkDeclaredSize(file, width, height, "pixels");
    h.width = static_cast<int>(width);
    h.height = static_cast<int>(height);
    if (std::fseek(f, 0, SEEK_END) != 0) throw IoError(file, "cannot read: not a seekable file");
    const long length = std::ftell(f);
    std::rewind(f);
    const std::uint64_t rowBytes = (std::uint64_t{width} * channels * h.bitDepth + 7) / 8;
    const std::uint64_t pixelBytes = std::uint64_t{height} * (rowBytes + 1);  // + 1 filter byte per row
    const std::uint64_t needed = kSignatureAndHeaderBytes + kMinChunkBytesAfterHeader + pixelBytes / kDeflateMaxRatio;
    if (length < 0 || static_cast<std::uint64_t>(length) < needed)
        throw IoError(file, "truncated PNG: " + std::to_string(length) + " bytes cannot hold " + std::to_string(width) +
                                " x " + std::to_string(height) + " pixels (at least " + std::to_string(needed) +
                                " bytes)");
    return h;
}

// Reads the info chunks and sets up the decoding of a greyscale image to
// 8-bit or host-order 16-bit samples. setjmp-safe: plain C types only.
bool readGreyInfo(png_structp png, png_infop info, std::FILE* f, std::size_t* rowBytes) {
    if (setjmp(png_jmpbuf(png))) return false;
    png_init_io(png, f);
    png_set_user_limits(png, kMaxGridSide, kMaxGridSide);
    png_read_info(png, info);
    const int colorType = png_get_color_type(png, info);
    const int bitDepth = png_get_bit_depth(png, info);
    if (colorType == PNG_COLOR_TYPE_GRAY_ALPHA) png_set_strip_alpha(png);
    if (bitDepth < 8) png_set_expand_gray_1_2_4_to_8(png);
    if (bitDepth == 16) png_set_swap(png);  // PNG stores big-endian; we want host order
    png_set_interlace_handling(png);
    png_read_update_info(png, info);
    *rowBytes = png_get_rowbytes(png, info);
    return true;
}

// Decodes every row into rows[]. setjmp-safe: plain C types only.
bool readRows(png_structp png, png_bytepp rows) {
    if (setjmp(png_jmpbuf(png))) return false;
    png_read_image(png, rows);
    png_read_end(png, nullptr);
    return true;
}

// Owns libpng's read structures: destroyed on every way out of the caller.
struct PngReadStructs {
    png_structp png = nullptr;
    png_infop info = nullptr;
    explicit PngReadStructs(PngErrorText* error) {
        png = png_create_read_struct(PNG_LIBPNG_VER_STRING, error, png_detail::onPngError, png_detail::onPngWarning);
        if (png) info = png_create_info_struct(png);
    }
    ~PngReadStructs() {
        if (png) png_destroy_read_struct(&png, info ? &info : nullptr, nullptr);
    }
};

// The decoded samples of a greyscale PNG: 8 or 16 bits, rowBytes per row.
struct GreySamples {
    std::vector<unsigned char> bytes;
    std::size_t rowBytes = 0;
};

GreySamples decodeGrey(std::FILE* f, const std::string& file, const PngHeader& header) {
    PngErrorText error;
    PngReadStructs s(&error);
    if (!s.png || !s.info) throw IoError(file, "out of memory creating the PNG reader");
    GreySamples out;
    if (!readGreyInfo(s.png, s.info, f, &out.rowBytes)) throw IoError(file, std::string("corrupt PNG: ") + error.text);
    const std::size_t expected = static_cast<std::size_t>(header.width) * (header.bitDepth == 16 ? 2 : 1);
    if (out.rowBytes != expected) throw IoError(file, "corrupt PNG: unexpected decoded row size");
    out.bytes.resize(out.rowBytes * static_cast<std::size_t>(header.height));
    std::vector<png_bytep> rows(static_cast<std::size_t>(header.height));
    for (std::size_t y = 0; y < rows.size(); ++y) rows[y] = out.bytes.data() + y * out.rowBytes;
    if (!readRows(s.png, rows.data())) throw IoError(file, std::string("corrupt or truncated PNG: ") + error.text);
    return out;
}

// A number for a message: "%g", not std::to_string's 40 digits of 1e38.
std::string shortNumber(float v) {
    char text[32];
    std::snprintf(text, sizeof text, "%g", static_cast<double>(v));
    return text;
}

const char* colourTypeName(int colorType) {
    switch (colorType) {
        case PNG_COLOR_TYPE_RGB:
            return "RGB";
        case PNG_COLOR_TYPE_RGB_ALPHA:
            return "RGBA";
        case PNG_COLOR_TYPE_PALETTE:
            return "palette";
        default:
            return "colour";
    }
}

}  // namespace

PngHeader peekPngHeader(const std::string& file) {
    FilePtr f(std::fopen(file.c_str(), "rb"));
    if (!f) throw IoError(file, std::string("cannot open: ") + std::strerror(errno));
    return peekHeader(f.get(), file);
}

Grid readPngHeightmap(const std::string& file, float zScale, float zOffset, int* sourceBitDepth) {
    if (!std::isfinite(zScale) || !std::isfinite(zOffset))
        throw InputError("height mapping for " + file + " is not finite (z-scale " + std::to_string(zScale) +
                         ", z-offset " + std::to_string(zOffset) + ")");
    FilePtr f(std::fopen(file.c_str(), "rb"));
    if (!f) throw IoError(file, std::string("cannot open: ") + std::strerror(errno));
    const PngHeader header = peekHeader(f.get(), file);
    if (header.colorType != PNG_COLOR_TYPE_GRAY && header.colorType != PNG_COLOR_TYPE_GRAY_ALPHA)
        throw IoError(file, std::string("is a colour PNG (") + colourTypeName(header.colorType) +
                                "); a heightmap must be a greyscale PNG (16-bit for full precision)");
    const GreySamples samples = decodeGrey(f.get(), file, header);
    Grid g(header.width, header.height);
    for (std::size_t i = 0; i < g.v.size(); ++i) {
        std::uint16_t value = 0;
        if (header.bitDepth == 16)
            std::memcpy(&value, samples.bytes.data() + 2 * i, 2);
        else
            value = static_cast<std::uint16_t>(samples.bytes[i] * 257u);  // 0..255 onto 0..65535
        g.v[i] = zOffset + zScale * static_cast<float>(value);
        if (!std::isfinite(g.v[i]))
            throw IoError(file, "pixel (" + std::to_string(i % header.width) + ", " + std::to_string(i / header.width) +
                                    ") maps to a non-finite height (z-scale " + shortNumber(zScale) + ", z-offset " +
                                    shortNumber(zOffset) + ")");
    }
    if (sourceBitDepth) *sourceBitDepth = header.bitDepth;
    return g;
}

}  // namespace terrain
