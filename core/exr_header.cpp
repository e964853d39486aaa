// OpenEXR header checks (magic, version flags, attributes, data window,
// channel count, offset table size) on the file's bytes.
#include "core/exr_header.h"

#include <cstdint>
#include <optional>
#include <string_view>

#include "core/byte_reader.h"
#include "core/error.h"
#include "core/size_limits.h"

namespace terrain {
namespace {

constexpr std::uint32_t kExrMagic = 20000630;
constexpr std::uint32_t kTiledFlag = 0x200, kLongNamesFlag = 0x400, kDeepFlag = 0x800, kMultiPartFlag = 0x1000;
// An environment map needs R, G, B (and maybe A); a file with many more
// channels makes OpenEXR size a line buffer per channel for nothing.
constexpr int kMaxChannels = 32;
// Data window corners beyond this are absurd and make OpenEXR's own
// arithmetic on them overflow.
constexpr std::int64_t kMaxCorner = std::int64_t{1} << 30;

// Scanlines per chunk for each compression (OpenEXR's compression enum).
int linesPerChunk(int compression) {
    constexpr int lines[] = {1, 1, 1, 16, 32, 16, 32, 32, 32, 256};
    return compression >= 0 && compression < 10 ? lines[compression] : 0;
}

int countChannels(ByteReader& r, std::size_t end, std::size_t maxName) {
    int count = 0;
    while (r.position() < end) {
        if (r.cString(maxName, "channel name").empty()) {
            // OpenEXR reads the list up to its terminator, whatever the
            // attribute's size: a list that ends elsewhere would make it
            // read the rest of the header out of step with this check
            if (r.position() != end)
                throw IoError(r.file(), "corrupt EXR: the channel list does not fill its attribute");
            return count;
        }
        r.skip(16, "channel description");  // pixel type, pLinear + reserved, x and y sampling
        if (++count > kMaxChannels)
            throw IoError(r.file(), "EXR has more than " + std::to_string(kMaxChannels) + " channels");
    }
    throw IoError(r.file(), "corrupt EXR: unterminated channel list");
}

struct ExrAttributes {
    std::optional<ExrDataWindow> window;
    int compression = -1;
    std::uint32_t tileWidth = 0, tileHeight = 0;
};

// Bytes of the value of each fixed-size attribute type OpenEXR reads by its
// layout rather than by the size the file declares (0: not such a type).
std::size_t fixedValueSize(std::string_view type) {
    struct Fixed {
        std::string_view type;
        std::size_t bytes;
    };
    static constexpr Fixed kFixed[] = {
        {"box2i", 16},
        {"box2f", 16},
        {"chromaticities", 32},
        {"compression", 1},
        {"deepImageState", 1},
        {"double", 8},
        {"envmap", 1},
        {"float", 4},
        {"int", 4},
        {"keycode", 28},
        {"lineOrder", 1},
        {"m33f", 36},
        {"m33d", 72},
        {"m44f", 64},
        {"m44d", 128},
        {"rational", 8},
        {"tiledesc", 9},
        {"timecode", 8},
        {"v2i", 8},
        {"v2f", 8},
        {"v2d", 16},
        {"v3i", 12},
        {"v3f", 12},
        {"v3d", 24},
    };
    for (const Fixed& f : kFixed)
        if (f.type == type) return f.bytes;
    return 0;
}

// The types whose value holds sizes of its own, checked against the
// attribute's size before OpenEXR allocates what they declare: a preview
// image (width x height RGBA bytes) and a vector of strings (a length before
// each).
void checkSizedValue(ByteReader& r, std::string_view type, std::size_t end) {
    if (type == "preview") {
        if (end - r.position() < 8) throw IoError(r.file(), "corrupt EXR: a preview image without its size");
        const auto w = r.read<std::uint32_t>("preview width"), h = r.read<std::uint32_t>("preview height");
        if (std::uint64_t{w} * h * 4 != end - r.position())
            throw IoError(r.file(), "corrupt EXR: the preview image does not fill its attribute");
    } else if (type == "stringvector") {
        while (r.position() < end) {
            const auto n = r.read<std::int32_t>("string length");
            if (n < 0 || static_cast<std::size_t>(n) > end - r.position())
                throw IoError(r.file(), "corrupt EXR: a string runs past its attribute");
            r.skip(static_cast<std::size_t>(n), "string");
        }
    }
}

ExrAttributes readAttributes(ByteReader& r, std::size_t maxName) {
    ExrAttributes a;
    for (;;) {
        const std::string_view name = r.cString(maxName, "attribute name");
        if (name.empty()) return a;
        const std::string_view type = r.cString(maxName, "attribute type");
        const auto size = r.read<std::int32_t>("attribute size");
        if (size < 0 || static_cast<std::size_t>(size) > r.remaining())
            throw IoError(r.file(), "corrupt EXR: attribute '" + std::string(name) + "' declares " +
                                        std::to_string(size) + " bytes, " + std::to_string(r.remaining()) + " left");
        const std::size_t end = r.position() + static_cast<std::size_t>(size);
        const std::size_t fixed = fixedValueSize(type);
        if (fixed != 0 && fixed != static_cast<std::size_t>(size))
            throw IoError(r.file(), "corrupt EXR: attribute '" + std::string(name) + "' of type " + std::string(type) +
                                        " declares " + std::to_string(size) + " bytes, not " + std::to_string(fixed));
        checkSizedValue(r, type, end);
        if (name == "dataWindow" && type == "box2i" && size == 16) {
            ExrDataWindow w;
            w.x0 = r.read<std::int32_t>("data window");
            w.y0 = r.read<std::int32_t>("data window");
            w.x1 = r.read<std::int32_t>("data window");
            w.y1 = r.read<std::int32_t>("data window");
            a.window = w;
        } else if (name == "compression" && type == "compression" && size == 1) {
            a.compression = r.read<std::uint8_t>("compression");
        } else if (name == "tiles" && type == "tiledesc" && size == 9) {
            a.tileWidth = r.read<std::uint32_t>("tile width");
            a.tileHeight = r.read<std::uint32_t>("tile height");
        } else if (type == "chlist") {
            // every channel list, whatever its name: OpenEXR reads each by its layout
            countChannels(r, end, maxName);
        }
        r.seek(end, "attribute");
    }
}

// Offset table entries (8 bytes each) the level-0 image needs.
std::uint64_t chunkCount(const ExrAttributes& a, std::int64_t width, std::int64_t height, bool tiled) {
    if (tiled) {
        if (a.tileWidth < 1 || a.tileHeight < 1) return 0;
        return static_cast<std::uint64_t>((width + a.tileWidth - 1) / a.tileWidth) *
               static_cast<std::uint64_t>((height + a.tileHeight - 1) / a.tileHeight);
    }
    const int lines = linesPerChunk(a.compression);
    return lines > 0 ? static_cast<std::uint64_t>((height + lines - 1) / lines) : 0;
}

}  // namespace

ExrDataWindow checkExrHeader(const std::string& file, std::string_view bytes) {
    ByteReader r(file, bytes);
    if (bytes.size() < 8 || r.read<std::uint32_t>("magic") != kExrMagic) throw IoError(file, "not an OpenEXR file");
    const auto version = r.read<std::uint32_t>("version");
    if ((version & 0xff) != 2) throw IoError(file, "unsupported OpenEXR version " + std::to_string(version & 0xff));
    if (version & (kDeepFlag | kMultiPartFlag)) throw IoError(file, "multi-part and deep EXR files are not supported");
    const bool tiled = (version & kTiledFlag) != 0;
    const ExrAttributes a = readAttributes(r, (version & kLongNamesFlag) ? 255 : 31);
    if (!a.window) throw IoError(file, "corrupt EXR: no data window");
    const ExrDataWindow w = *a.window;
    for (const std::int64_t corner : {w.x0, w.y0, w.x1, w.y1})
        if (corner < -kMaxCorner || corner > kMaxCorner) throw IoError(file, "corrupt EXR: absurd data window");
    const std::int64_t width = std::int64_t{w.x1} - w.x0 + 1, height = std::int64_t{w.y1} - w.y0 + 1;
    checkDeclaredSize(file, width, height, "pixels");
    const std::uint64_t chunks = chunkCount(a, width, height, tiled);
    if (chunks == 0) throw IoError(file, "corrupt EXR: unknown compression or tile size");
    if (chunks * 8 > r.remaining())
        throw IoError(file, "truncated EXR: " + std::to_string(bytes.size()) + " bytes cannot hold " +
                                std::to_string(width) + " x " + std::to_string(height) + " pixels");
    return w;
}

}  // namespace terrain
