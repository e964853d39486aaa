#pragma once
// Checks an OpenEXR file's header before OpenEXR reads it: OpenEXR sizes its
// buffers and offset tables from the header, so a small hostile file could
// otherwise make it allocate gigabytes.
#include <string>
#include <string_view>

namespace terrain {

/// The data window an EXR header declares (inclusive corners).
struct ExrDataWindow {
    int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
    int width() const { return x1 - x0 + 1; }
    int height() const { return y1 - y0 + 1; }
};

/// Parses the header of a single-part, flat (not deep) EXR held in bytes and
/// throws IoError naming `file` unless every attribute fits in the file, the
/// data window is 1 to kMaxGridSide per side, the channels are few, and the
/// file can hold the chunk offset table that window needs.
ExrDataWindow checkExrHeader(const std::string& file, std::string_view bytes);

}  // namespace terrain
