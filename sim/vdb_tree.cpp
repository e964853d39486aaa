// An OpenVDB FloatGrid's tree, read from the file's bytes: the topology
// (root table, two levels of internal nodes, leaf masks), then the leaves'
// values of the z = 0 layer.
#include "sim/vdb_tree.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cstring>
#include <string>
#include <tuple>

#include "core/error.h"
#include "sim/vdb_blocks.h"

namespace terrain::vdb {
namespace {

constexpr std::int32_t kRootChildSide = 4096;  // voxels per side of a root child
constexpr std::size_t kLeafValues = 512;
constexpr std::size_t kLeafMaskBytes = kLeafValues / 8;
// In each 64-bit word of a leaf mask (one x column of 8 x 8 y, z voxels),
// the bits of the voxels at z = 0.
constexpr std::uint64_t kLeafZeroLayerBits = 0x0101010101010101ull;

std::uint32_t floatBits(float v) { return std::bit_cast<std::uint32_t>(v); }

std::uint64_t word(const unsigned char* mask, std::size_t i) {
    std::uint64_t w;
    std::memcpy(&w, mask + 8 * i, 8);
    return w;
}

class TopologyReader {
public:
    TopologyReader(ByteReader& r, std::uint32_t compression, const std::string& grid, Topology& t)
        : r_(r), compression_(compression), grid_(grid), t_(t) {}

    void readRoot();

private:
    void readRootTiles(std::uint32_t count, std::vector<std::array<std::int32_t, 3>>& keys);
    void readInternal(std::int32_t ox, std::int32_t oy, std::int32_t oz, int log2Dim, int childLog2Side);
    void recordInactiveTiles(const unsigned char* childMask, std::int32_t ox, std::int32_t oy, int log2Dim,
                             int childLog2Side);
    void readLeaf(std::int32_t ox, std::int32_t oy, std::int32_t oz);
    std::array<std::int32_t, 3> readAlignedOrigin(const char* what);
    [[noreturn]] void corrupt(const std::string& why) const {
        throw IoError(r_.file(), "corrupt OpenVDB grid '" + grid_ + "': " + why);
    }
    [[noreturn]] void notHeightField(const std::string& why) const {
        throw IoError(r_.file(), "grid '" + grid_ + "' " + why + "; a height field is one layer of voxels at z = 0");
    }

    ByteReader& r_;
    std::uint32_t compression_;
    const std::string& grid_;
    Topology& t_;
    std::vector<float> values_, scratch_;
};

std::array<std::int32_t, 3> TopologyReader::readAlignedOrigin(const char* what) {
    std::array<std::int32_t, 3> c{};
    for (auto& v : c) v = r_.read<std::int32_t>(what);
    for (auto v : c)
        if (v % kRootChildSide != 0) corrupt(std::string(what) + " is not on the root's 4096-voxel grid");
    return c;
}

void TopologyReader::readRoot() {
    const auto buffers = r_.read<std::int32_t>("tree buffer count");
    if (buffers != 1) corrupt("the tree declares " + std::to_string(buffers) + " buffers (OpenVDB writes 1)");
    t_.background = r_.read<float>("background value");
    const auto tiles = r_.read<std::uint32_t>("root tile count");
    const auto children = r_.read<std::uint32_t>("root child count");
    // a root tile takes 17 bytes, a child at least its origin and two masks
    if (tiles > r_.remaining() / 17 || children > r_.remaining() / (12 + 2 * 4096))
        corrupt(std::to_string(tiles) + " root tiles and " + std::to_string(children) +
                " children cannot fit in the file");
    std::vector<std::array<std::int32_t, 3>> keys;
    readRootTiles(tiles, keys);
    for (std::uint32_t i = 0; i < children; ++i) {
        const auto c = readAlignedOrigin("root child origin");
        // OpenVDB writes the root's children sorted and reads their value
        // blocks in that order; any other order would pair the wrong blocks
        if (i > 0 && !(keys.back() < c)) corrupt("root children are not in ascending order");
        keys.push_back(c);
        readInternal(c[0], c[1], c[2], 5, 7);
    }
    std::sort(keys.begin(), keys.end());
    if (std::adjacent_find(keys.begin(), keys.end()) != keys.end()) corrupt("two root entries at one origin");
}

void TopologyReader::readRootTiles(std::uint32_t count, std::vector<std::array<std::int32_t, 3>>& keys) {
    for (std::uint32_t i = 0; i < count; ++i) {
        const auto c = readAlignedOrigin("root tile origin");
        const auto value = r_.read<float>("root tile value");
        if (r_.read<std::uint8_t>("root tile state") != 0) notHeightField("has an active 4096-voxel tile");
        if (c[2] == 0 && floatBits(value) != floatBits(t_.background))
            t_.tiles.push_back({c[0], c[1], kRootChildSide, value});
        keys.push_back(c);
    }
}

void TopologyReader::readInternal(std::int32_t ox, std::int32_t oy, std::int32_t oz, int log2Dim, int childLog2Side) {
    const std::size_t count = std::size_t{1} << (3 * log2Dim);
    const auto* childMask = reinterpret_cast<const unsigned char*>(r_.take(count / 8, "child mask").data());
    const auto* valueMask = reinterpret_cast<const unsigned char*>(r_.take(count / 8, "value mask").data());
    bool activeTile = false;
    for (std::size_t i = 0; i < count / 64; ++i) {
        if (word(childMask, i) & word(valueMask, i)) corrupt("a node has a child and a tile at one position");
        activeTile = activeTile || word(valueMask, i) != 0;
    }
    if (activeTile) notHeightField("has an active tile");
    values_.resize(count);
    readNodeValues(r_, compression_, valueMask, count, t_.background, values_.data(), scratch_);
    if (oz == 0) recordInactiveTiles(childMask, ox, oy, log2Dim, childLog2Side);
    const int dim = 1 << log2Dim;
    for (std::size_t w = 0; w < count / 64; ++w)
        for (std::uint64_t bits = word(childMask, w); bits != 0; bits &= bits - 1) {
            const std::size_t i = 64 * w + static_cast<std::size_t>(std::countr_zero(bits));
            const auto cx = static_cast<std::int32_t>(ox + ((i >> (2 * log2Dim)) << childLog2Side));
            const auto cy = static_cast<std::int32_t>(oy + (((i >> log2Dim) & (dim - 1)) << childLog2Side));
            const auto cz = static_cast<std::int32_t>(oz + ((i & (dim - 1)) << childLog2Side));
            if (childLog2Side == 3)
                readLeaf(cx, cy, cz);
            else
                readInternal(cx, cy, cz, 4, 3);
        }
}

// The node's tiles in its z = 0 layer (values_ holds the node's values).
void TopologyReader::recordInactiveTiles(const unsigned char* childMask, std::int32_t ox, std::int32_t oy, int log2Dim,
                                         int childLog2Side) {
    const int dim = 1 << log2Dim;
    for (int xi = 0; xi < dim; ++xi)
        for (int yi = 0; yi < dim; ++yi) {
            const std::size_t i =
                (static_cast<std::size_t>(xi) << (2 * log2Dim)) | (static_cast<std::size_t>(yi) << log2Dim);
            if (maskBit(childMask, i) || floatBits(values_[i]) == floatBits(t_.background)) continue;
            t_.tiles.push_back(
                {ox + (xi << childLog2Side), oy + (yi << childLog2Side), 1 << childLog2Side, values_[i]});
        }
}

void TopologyReader::readLeaf(std::int32_t ox, std::int32_t oy, std::int32_t oz) {
    const auto* mask = reinterpret_cast<const unsigned char*>(r_.take(kLeafMaskBytes, "leaf mask").data());
    ActiveVoxels& a = t_.active;
    for (int xi = 0; xi < 8; ++xi) {
        const std::uint64_t w = word(mask, static_cast<std::size_t>(xi));
        if (w == 0) continue;
        if (oz != 0 || (w & ~kLeafZeroLayerBits) != 0) notHeightField("has active voxels off z = 0");
        const std::int64_t x = std::int64_t{ox} + xi;
        const std::int64_t y0 = std::int64_t{oy} + (std::countr_zero(w) >> 3);
        const std::int64_t y1 = std::int64_t{oy} + ((63 - std::countl_zero(w)) >> 3);
        if (a.count == 0) {
            a.minX = a.maxX = x;
            a.minY = y0;
            a.maxY = y1;
        }
        a.minX = std::min(a.minX, x);
        a.maxX = std::max(a.maxX, x);
        a.minY = std::min(a.minY, y0);
        a.maxY = std::max(a.maxY, y1);
        a.count += std::popcount(w);
    }
    t_.leaves.push_back({ox, oy, oz, mask});
}

void fillTile(const Tile& tile, Grid& out) {
    const std::int64_t x0 = std::max<std::int64_t>(tile.x, 0), y0 = std::max<std::int64_t>(tile.y, 0);
    const std::int64_t x1 = std::min<std::int64_t>(std::int64_t{tile.x} + tile.side, out.nx);
    const std::int64_t y1 = std::min<std::int64_t>(std::int64_t{tile.y} + tile.side, out.ny);
    for (std::int64_t y = y0; y < y1; ++y)
        for (std::int64_t x = x0; x < x1; ++x) out(static_cast<int>(x), static_cast<int>(y)) = tile.value;
}

// The z = 0 values of a leaf (values[(x << 6) | (y << 3)]) inside out.
void copyLeafLayer(const Leaf& leaf, const float* values, Grid& out) {
    for (int xi = 0; xi < 8; ++xi) {
        const std::int64_t x = std::int64_t{leaf.x} + xi;
        if (x < 0 || x >= out.nx) continue;
        for (int yi = 0; yi < 8; ++yi) {
            const std::int64_t y = std::int64_t{leaf.y} + yi;
            if (y >= 0 && y < out.ny) out(static_cast<int>(x), static_cast<int>(y)) = values[(xi << 6) | (yi << 3)];
        }
    }
}

}  // namespace

Topology readTopology(ByteReader& r, std::uint32_t compression, const std::string& grid) {
    Topology t;
    TopologyReader(r, compression, grid, t).readRoot();
    return t;
}

void readLayerValues(ByteReader& r, std::uint32_t compression, const Topology& t, int nx, int ny, Grid& out) {
    out.resize(nx, ny, t.background);
    for (const Tile& tile : t.tiles) fillTile(tile, out);
    std::array<float, kLeafValues> values{};
    std::vector<float> scratch;
    for (const Leaf& leaf : t.leaves) {
        r.skip(kLeafMaskBytes, "leaf mask");  // a repeat of the topology's, which OpenVDB uses too
        readNodeValues(r, compression, leaf.activeMask, kLeafValues, t.background, values.data(), scratch);
        if (leaf.z == 0) copyLeafLayer(leaf, values.data(), out);
    }
}

}  // namespace terrain::vdb
