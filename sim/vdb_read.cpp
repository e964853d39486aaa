// The OpenVDB file structure (header, grid table, grid metadata, transform)
// parsed from the file's bytes; trees in sim/vdb_tree.cpp.
#include "sim/vdb_read.h"

#include <cstring>
#include <string_view>

#include "core/byte_reader.h"
#include "core/error.h"
#include "core/file_io.h"
#include "sim/vdb_blocks.h"

namespace terrain::vdb {
namespace {

constexpr std::int64_t kMagic = 0x56444220;  // "VDB " as a little-endian int64
// File formats with per-grid compression and node masks (OpenVDB 3) up to
// the one OpenVDB 10 writes.
constexpr std::uint32_t kMinVersion = 222, kMaxVersion = 224;
constexpr std::uint32_t kMaxNameBytes = 1024;  // grid, metadata, type and transform names
constexpr std::int32_t kMaxGrids = 1024;
constexpr char kFloatTree[] = "Tree_float_5_4_3";
constexpr char kHalfFloatTree[] = "Tree_float_5_4_3_HalfFloat";
// OpenVDB appends this and a number to a repeated grid name.
constexpr char kNameSuffixSeparator = '\x1e';

// A name from the file as it may appear in a message.
std::string printable(std::string_view name) { return boundedLine(name, 40); }

// OpenVDB metadata: count, then name, type name and sized value per entry.
template <class OnEntry>
void readMetadata(ByteReader& r, OnEntry onEntry) {
    const auto count = r.read<std::uint32_t>("metadata count");
    if (count > r.remaining() / 12) throw IoError(r.file(), "corrupt OpenVDB file: absurd metadata count");
    for (std::uint32_t i = 0; i < count; ++i) {
        const std::string_view name = r.sizedString(kMaxNameBytes, "metadata name");
        const std::string_view type = r.sizedString(kMaxNameBytes, "metadata type");
        const auto size = r.read<std::uint32_t>("metadata size");
        onEntry(name, type, r.take(size, "metadata value"));
    }
}

void readHeader(ByteReader& r) {
    if (r.size() < 8 || r.read<std::int64_t>("magic number") != kMagic)
        throw IoError(r.file(), "not an OpenVDB file (bad magic number)");
    const auto version = r.read<std::uint32_t>("file format version");
    if (version < kMinVersion || version > kMaxVersion)
        throw IoError(r.file(), "OpenVDB file format " + std::to_string(version) +
                                    " is not supported (the engine reads " + std::to_string(kMinVersion) + " to " +
                                    std::to_string(kMaxVersion) + ")");
    r.skip(8, "library version");
    if (r.read<std::uint8_t>("grid offsets flag") != 1)
        throw IoError(r.file(), "OpenVDB file written as a stream (without grid offsets) is not supported");
    r.skip(36, "file UUID");
    readMetadata(r, [](std::string_view, std::string_view, std::string_view) {});
}

GridEntry readEntry(ByteReader& r) {
    GridEntry e;
    const std::string_view unique = r.sizedString(kMaxNameBytes, "grid name");
    e.name = std::string(unique.substr(0, unique.find(kNameSuffixSeparator)));
    e.type = std::string(r.sizedString(kMaxNameBytes, "grid type"));
    e.instance = !r.sizedString(kMaxNameBytes, "instance parent").empty();
    const auto gridPos = r.read<std::int64_t>("grid offset");
    const auto blockPos = r.read<std::int64_t>("grid data offset");
    const auto endPos = r.read<std::int64_t>("grid end offset");
    if (gridPos == static_cast<std::int64_t>(r.position()) && blockPos >= gridPos && endPos >= blockPos &&
        endPos > static_cast<std::int64_t>(r.size()))
        throw IoError(r.file(), "truncated: grid '" + printable(e.name) + "' ends at byte " + std::to_string(endPos) +
                                    ", the file has " + std::to_string(r.size()) + " bytes");
    if (gridPos != static_cast<std::int64_t>(r.position()) || blockPos < gridPos || endPos < blockPos ||
        endPos > static_cast<std::int64_t>(r.size()))
        throw IoError(r.file(), "corrupt OpenVDB grid table: grid '" + printable(e.name) + "' lies outside the file");
    e.gridPos = static_cast<std::uint64_t>(gridPos);
    e.blockPos = static_cast<std::uint64_t>(blockPos);
    e.endPos = static_cast<std::uint64_t>(endPos);
    return e;
}

// The voxel size of a scale or translation map (the field OpenVDB's
// voxelSize() returns); other transforms are not the engine's layout.
void readTransform(ByteReader& r, FloatGrid& g) {
    const std::string_view type = r.sizedString(kMaxNameBytes, "transform type");
    auto vec3 = [&](double* xyz) {
        for (int i = 0; i < 3; ++i) xyz[i] = r.read<double>("transform");
    };
    double translation[3], scale[3], voxel[3] = {1.0, 1.0, 1.0}, derived[9];
    if (type == "UniformScaleTranslateMap" || type == "ScaleTranslateMap" || type == "TranslationMap")
        vec3(translation);
    if (type == "UniformScaleMap" || type == "ScaleMap" || type == "UniformScaleTranslateMap" ||
        type == "ScaleTranslateMap") {
        vec3(scale);
        vec3(voxel);
        for (int i = 0; i < 3; ++i) vec3(derived + 3 * i);  // inverse scale, its square, half inverse
    } else if (type != "TranslationMap") {
        throw IoError(r.file(), "grid '" + g.name + "' has a " + printable(type) +
                                    " transform; the engine reads scale and translation transforms");
    }
    g.voxelX = voxel[0];
    g.voxelY = voxel[1];
}

void readGridMetadata(ByteReader& r, FloatGrid& g) {
    readMetadata(r, [&](std::string_view name, std::string_view type, std::string_view value) {
        const bool int32 = type == "int32" && value.size() == 4;
        if (int32 && (name == "terrain_nx" || name == "terrain_ny")) {
            std::int32_t v;
            std::memcpy(&v, value.data(), 4);
            (name == "terrain_nx" ? g.declaredNx : g.declaredNy) = v;
        }
        if (name == "class" && type == "string" && value != "unknown")
            throw IoError(r.file(), "grid '" + g.name + "' has class '" + printable(value) +
                                        "'; a height field's grid class is 'unknown'");
    });
}

}  // namespace

FileReader::FileReader(const std::string& file) : file_(file), bytes_(readFileBytes(file)) {
    ByteReader r(file_, bytes_);
    readHeader(r);
    const auto count = r.read<std::int32_t>("grid count");
    if (count < 1) throw IoError(file_, "contains no grids");
    if (count > kMaxGrids)
        throw IoError(file_,
                      "declares " + std::to_string(count) + " grids (at most " + std::to_string(kMaxGrids) + ")");
    for (std::int32_t i = 0; i < count; ++i) {
        grids_.push_back(readEntry(r));
        r.seek(grids_.back().endPos, "grid end offset");
    }
}

const GridEntry* FileReader::find(const std::string& name) const {
    for (const GridEntry& e : grids_)
        if (e.name == name) return &e;
    return nullptr;
}

const GridEntry* FileReader::firstFloatGrid() const {
    for (const GridEntry& e : grids_)
        if (e.type == kFloatTree || e.type == kHalfFloatTree) return &e;
    return nullptr;
}

FloatGrid FileReader::readGrid(const GridEntry& entry) const {
    FloatGrid g;
    g.name = printable(entry.name);
    if (entry.type == kHalfFloatTree)
        throw IoError(file_, "grid '" + g.name + "' is stored as 16-bit floats; the engine reads 32-bit float grids");
    if (entry.type != kFloatTree)
        throw IoError(file_, "grid '" + g.name + "' is a " + printable(entry.type) + " grid, not a float grid");
    if (entry.instance) throw IoError(file_, "grid '" + g.name + "' is an instance of another grid (not supported)");
    ByteReader r(file_, std::string_view(bytes_).substr(0, entry.endPos));
    r.seek(entry.gridPos, "grid offset");
    g.compression = r.read<std::uint32_t>("grid compression");
    if ((g.compression & ~(kCompressZip | kCompressActiveMask | kCompressBlosc)) != 0 ||
        ((g.compression & kCompressZip) && (g.compression & kCompressBlosc)))
        throw IoError(file_, "grid '" + g.name + "' has unknown compression flags " + std::to_string(g.compression));
    readGridMetadata(r, g);
    readTransform(r, g);
    g.topology = readTopology(r, g.compression, g.name);
    if (r.position() != entry.blockPos)
        throw IoError(file_, "corrupt OpenVDB grid '" + g.name + "': its tree does not end where its data begins");
    g.blockPos = entry.blockPos;
    g.endPos = entry.endPos;
    return g;
}

void FileReader::readValues(const FloatGrid& grid, int nx, int ny, Grid& out) const {
    ByteReader r(file_, std::string_view(bytes_).substr(0, grid.endPos));
    r.seek(grid.blockPos, "grid data offset");
    readLayerValues(r, grid.compression, grid.topology, nx, ny, out);
    if (r.position() != grid.endPos)
        throw IoError(file_, "corrupt OpenVDB grid '" + grid.name + "': its data does not end where the grid ends");
}

}  // namespace terrain::vdb
