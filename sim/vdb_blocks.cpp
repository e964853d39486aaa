// OpenVDB node value blocks: mask compression (which inactive values were
// left out) and the raw, zlib or Blosc data that follows.
#include "sim/vdb_blocks.h"

#include <bit>
#include <cstring>
#include <limits>
#include <string>

#include <blosc.h>
#include <zlib.h>

#include "core/error.h"

namespace terrain::vdb {
namespace {

// What a node saved besides its active values (OpenVDB's io:: node metadata).
enum NodeMetadata : std::uint8_t {
    kNoMaskOrInactiveVals = 0,     // inactive values are all the background
    kNoMaskAndMinusBg = 1,         // ... all minus the background
    kNoMaskAndOneInactiveVal = 2,  // ... all one stored value
    kMaskAndNoInactiveVals = 3,    // a mask selects background or minus background
    kMaskAndOneInactiveVal = 4,    // a mask selects background or one stored value
    kMaskAndTwoInactiveVals = 5,   // a mask selects one of two stored values
    kNoMaskAndAllVals = 6,         // every value is stored
};

std::size_t countOn(const unsigned char* mask, std::size_t bits) {
    std::size_t n = 0;
    for (std::size_t i = 0; i < bits / 64; ++i) {
        std::uint64_t word;
        std::memcpy(&word, mask + 8 * i, 8);
        n += static_cast<std::size_t>(std::popcount(word));
    }
    return n;
}

[[noreturn]] void corrupt(const ByteReader& r, const std::string& what) {
    throw IoError(r.file(), "corrupt OpenVDB data at byte " + std::to_string(r.position()) + ": " + what);
}

void readRaw(ByteReader& r, std::size_t bytes, char* out, const char* what) {
    const std::string_view raw = r.take(bytes, what);
    if (bytes > 0) std::memcpy(out, raw.data(), bytes);  // out may be null when there is nothing to copy
}

// A compressed block: int64 size, then that many bytes (a size <= 0 means
// -size raw bytes follow). It must hold exactly `bytes` bytes of values
// (none for a node without active values: Blosc still writes its header).
void readPackedBlock(ByteReader& r, bool blosc, std::size_t bytes, char* values) {
    const auto stored = r.read<std::int64_t>("compressed block size");
    if (stored <= 0) {
        if (stored != -static_cast<std::int64_t>(bytes)) corrupt(r, "raw block of the wrong size");
        readRaw(r, bytes, values, "raw block");
        return;
    }
    char nothing = 0;
    char* out = bytes > 0 ? values : &nothing;  // the decompressors want a real pointer
    const std::string_view packed = r.take(static_cast<std::uint64_t>(stored), "compressed block");
    if (blosc) {
        std::size_t unpacked = 0;
        if (blosc_cbuffer_validate(packed.data(), packed.size(), &unpacked) != 0 || unpacked != bytes)
            corrupt(r, "invalid Blosc block");
        if (blosc_decompress_ctx(packed.data(), out, bytes, 1) != static_cast<int>(bytes))
            corrupt(r, "Blosc block does not decompress");
        return;
    }
    uLongf unpacked = static_cast<uLongf>(bytes);
    if (packed.size() > std::numeric_limits<uLong>::max() ||
        uncompress(reinterpret_cast<Bytef*>(out), &unpacked, reinterpret_cast<const Bytef*>(packed.data()),
                   static_cast<uLong>(packed.size())) != Z_OK ||
        unpacked != bytes)
        corrupt(r, "zlib block does not decompress to its node's size");
}

void readData(ByteReader& r, std::uint32_t compression, float* out, std::size_t count) {
    const std::size_t bytes = count * sizeof(float);
    if (compression & (kCompressBlosc | kCompressZip))
        readPackedBlock(r, (compression & kCompressBlosc) != 0, bytes, reinterpret_cast<char*>(out));
    else
        readRaw(r, bytes, reinterpret_cast<char*>(out), "raw node values");
}

}  // namespace

void readNodeValues(ByteReader& r, std::uint32_t compression, const unsigned char* valueMask, std::size_t count,
                    float background, float* out, std::vector<float>& scratch) {
    const auto metadata = r.read<std::uint8_t>("node metadata");
    if (metadata > kNoMaskAndAllVals) corrupt(r, "unknown node metadata " + std::to_string(metadata));
    float inactive1 = background;
    float inactive0 = metadata == kNoMaskOrInactiveVals ? background : -background;
    if (metadata == kNoMaskAndOneInactiveVal || metadata == kMaskAndOneInactiveVal ||
        metadata == kMaskAndTwoInactiveVals) {
        inactive0 = r.read<float>("inactive value");
        if (metadata == kMaskAndTwoInactiveVals) inactive1 = r.read<float>("inactive value");
    }
    const unsigned char* selection = nullptr;
    if (metadata == kMaskAndNoInactiveVals || metadata == kMaskAndOneInactiveVal || metadata == kMaskAndTwoInactiveVals)
        selection = reinterpret_cast<const unsigned char*>(r.take(count / 8, "selection mask").data());
    const bool activeOnly = (compression & kCompressActiveMask) && metadata != kNoMaskAndAllVals;
    const std::size_t stored = activeOnly ? countOn(valueMask, count) : count;
    if (stored == count) {
        readData(r, compression, out, count);
        return;
    }
    scratch.resize(stored);
    readData(r, compression, scratch.data(), stored);
    for (std::size_t i = 0, next = 0; i < count; ++i) {
        if (maskBit(valueMask, i))
            out[i] = scratch[next++];
        else
            out[i] = selection && maskBit(selection, i) ? inactive1 : inactive0;
    }
}

}  // namespace terrain::vdb
