#pragma once
// The value block of one OpenVDB tree node, as OpenVDB 10 lays it out in a
// file (file format 222 to 224): a byte saying which values were left out,
// the inactive values and selection mask it calls for, then the values
// themselves, raw, zlib- or Blosc-compressed. Decoded here from a bounded
// cursor: every size the file states is checked against what the file holds
// and what the node can hold before anything is decompressed.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/byte_reader.h"

namespace terrain::vdb {

/// Per-grid compression flags (OpenVDB's io::COMPRESS_*).
inline constexpr std::uint32_t kCompressZip = 0x1;
inline constexpr std::uint32_t kCompressActiveMask = 0x2;
inline constexpr std::uint32_t kCompressBlosc = 0x4;

/// Bit n of a node mask stored as little-endian 64-bit words.
inline bool maskBit(const unsigned char* mask, std::size_t n) { return (mask[n >> 3] >> (n & 7)) & 1u; }

/// Reads the value block of a node with `count` values (512 for a leaf)
/// into out[0..count), as OpenVDB's io::readCompressedValues does:
/// valueMask is the node's active mask (count bits), background the tree's.
/// scratch is reused between calls. IoError on anything malformed.
void readNodeValues(ByteReader& r, std::uint32_t compression, const unsigned char* valueMask, std::size_t count,
                    float background, float* out, std::vector<float>& scratch);

}  // namespace terrain::vdb
