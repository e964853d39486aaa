// OpenEXR through its C++ interface, in memory both ways: a frame is encoded
// into memory and written with the checked atomic writer (OpenEXR's own file
// output drops errors raised while it closes the file), and a file is read
// once, its header checked (core/exr_header.h), then decoded from memory.
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include <OpenEXR/Iex.h>
#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFloatAttribute.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfIO.h>
#include <OpenEXR/ImfInputFile.h>
#include <OpenEXR/ImfOutputFile.h>
#include <OpenEXR/ImfRgbaFile.h>
#include <OpenEXR/ImfStdIO.h>

#include "core/error.h"
#include "core/exr_header.h"
#include "core/file_io.h"
#include "core/image_io.h"

namespace terrain {
namespace {

// A float attribute naming the metres between grid points.
constexpr const char* kCellSizeAttribute = "terrain:cellSize";
// Floats decoded at most (1 GiB: one 16384 x 16384 channel): a small file
// may declare many large channels, and each is allocated whole.
constexpr std::size_t kMaxDecodedFloats = std::size_t{1} << 28;
// Decoded bytes per byte of the file, at most, beyond the first MiB: deflate
// (EXR's ZIP) cannot expand more than about 1032 times, and terrain data
// compresses far less, so a file promising more declares pixels it does not hold.
constexpr std::size_t kMaxExpansion = 1032;
constexpr std::size_t kFreeDecodedBytes = std::size_t{1} << 20;

// OpenEXR input over bytes already in memory; reading past the end throws
// as OpenEXR's own file streams do.
class MemoryInput : public Imf::IStream {
public:
    MemoryInput(const std::string& file, const std::string& bytes) : Imf::IStream(file.c_str()), bytes_(bytes) {}

    bool read(char c[], int n) override {
        if (n < 0 || static_cast<std::uint64_t>(n) > bytes_.size() - pos_)
            throw Iex::InputExc("Unexpected end of file.");
        std::memcpy(c, bytes_.data() + pos_, static_cast<std::size_t>(n));
        pos_ += static_cast<std::size_t>(n);
        return pos_ < bytes_.size();
    }
    std::uint64_t tellg() override { return pos_; }
    void seekg(std::uint64_t pos) override {
        pos_ = pos < bytes_.size() ? static_cast<std::size_t>(pos) : bytes_.size();
    }

private:
    const std::string& bytes_;
    std::size_t pos_ = 0;
};

// OpenEXR addresses pixel (x, y) of a slice at base + x * xStride + y *
// yStride; the base lies outside the buffer when the window does not start
// at (0, 0), so it is computed in integers rather than as an out-of-range
// pointer.
char* sliceBase(void* data, const ExrDataWindow& w, std::size_t pixelBytes) {
    const std::uintptr_t origin =
        reinterpret_cast<std::uintptr_t>(data) - (static_cast<std::uintptr_t>(std::intptr_t{w.x0}) +
                                                  static_cast<std::uintptr_t>(std::intptr_t{w.y0}) * w.width()) *
                                                     pixelBytes;
    return reinterpret_cast<char*>(origin);
}

// Every channel must be full resolution: a sub-sampled one has no value per cell.
void checkFullResolution(const std::string& file, const Imf::ChannelList& channels) {
    for (auto c = channels.begin(); c != channels.end(); ++c)
        if (c.channel().xSampling != 1 || c.channel().ySampling != 1)
            throw IoError(
                file, std::string("EXR channel '") + c.name() + "' is sub-sampled; a layer needs one value per pixel");
}

// Reads the named channels (all of them when `only` is empty) as float
// grids, converting half and uint channels to float.
ExrChannels decodeChannels(const std::string& file, const std::string& bytes, const ExrDataWindow& w,
                           const std::string& only) {
    ExrChannels out;
    try {
        MemoryInput stream(file, bytes);
        Imf::InputFile in(stream);
        const Imath::Box2i dw = in.header().dataWindow();
        if (dw.min.x != w.x0 || dw.min.y != w.y0 || dw.max.x != w.x1 || dw.max.y != w.y1)
            throw IoError(file, "corrupt EXR: inconsistent data window");
        const Imf::ChannelList& channels = in.header().channels();
        checkFullResolution(file, channels);
        if (const auto* cell = in.header().findTypedAttribute<Imf::FloatAttribute>(kCellSizeAttribute))
            out.cellSize = cell->value();
        for (auto c = channels.begin(); c != channels.end(); ++c) {
            out.available.emplace_back(c.name());
            if (only.empty() || only == c.name()) out.names.emplace_back(c.name());
        }
        const std::size_t cells = static_cast<std::size_t>(w.width()) * static_cast<std::size_t>(w.height());
        const std::size_t floats = out.names.size() * cells;
        if (floats > kMaxDecodedFloats || floats * sizeof(float) > kFreeDecodedBytes + kMaxExpansion * bytes.size())
            throw IoError(file, std::to_string(out.names.size()) + " EXR channels of " + std::to_string(w.width()) +
                                    " x " + std::to_string(w.height()) + " pixels in " + std::to_string(bytes.size()) +
                                    " bytes: more than the file can hold or the engine reads at once (1 GiB)");
        out.grids.resize(out.names.size());
        Imf::FrameBuffer fb;
        for (std::size_t k = 0; k < out.names.size(); ++k) {
            out.grids[k].resize(w.width(), w.height());
            fb.insert(out.names[k], Imf::Slice(Imf::FLOAT, sliceBase(out.grids[k].data(), w, sizeof(float)),
                                               sizeof(float), sizeof(float) * static_cast<std::size_t>(w.width())));
        }
        if (out.names.empty()) return out;  // no channel of that name: nothing to read
        in.setFrameBuffer(fb);
        in.readPixels(w.y0, w.y1);
    } catch (const Error&) {
        throw;
    } catch (const std::exception& e) {
        throw IoError(file, std::string("corrupt or truncated EXR: ") + e.what());
    }
    return out;
}

// The pixels of an RGBA file, one Rgba per pixel of the data window.
std::vector<Imf::Rgba> decodeRgba(const std::string& file, const std::string& bytes, const ExrDataWindow& w) {
    std::vector<Imf::Rgba> px(static_cast<std::size_t>(w.width()) * static_cast<std::size_t>(w.height()));
    try {
        MemoryInput stream(file, bytes);
        Imf::RgbaInputFile in(stream);
        const Imath::Box2i dw = in.dataWindow();
        if (dw.min.x != w.x0 || dw.min.y != w.y0 || dw.max.x != w.x1 || dw.max.y != w.y1)
            throw IoError(file, "corrupt EXR: inconsistent data window");
        in.setFrameBuffer(reinterpret_cast<Imf::Rgba*>(sliceBase(px.data(), w, sizeof(Imf::Rgba))), 1,
                          static_cast<std::size_t>(w.width()));
        in.readPixels(w.y0, w.y1);
    } catch (const Error&) {
        throw;
    } catch (const std::exception& e) {
        throw IoError(file, std::string("corrupt or truncated EXR: ") + e.what());
    }
    return px;
}

}  // namespace

void writeExr(const std::string& file, const std::vector<const Grid*>& channels) {
    if (channels.empty() || !channels[0] || (channels.size() != 1 && channels.size() != 3))
        throw IoError(file, "EXR output needs 1 or 3 channels");
    const int w = channels[0]->nx, h = channels[0]->ny;
    std::vector<Imf::Rgba> px(static_cast<std::size_t>(w) * h);
    for (std::size_t i = 0; i < px.size(); ++i) {
        const float r = channels[0]->v[i];
        const float g = channels.size() == 3 ? channels[1]->v[i] : r;
        const float b = channels.size() == 3 ? channels[2]->v[i] : r;
        px[i] = Imf::Rgba(r, g, b, 1.0f);
    }
    Imf::StdOSStream encoded;
    try {
        // the file's offset table is written when `out` closes, at the end of this scope
        Imf::RgbaOutputFile out(encoded, Imf::Header(w, h), channels.size() == 3 ? Imf::WRITE_RGB : Imf::WRITE_Y);
        out.setFrameBuffer(px.data(), 1, static_cast<std::size_t>(w));
        out.writePixels(h);
    } catch (const std::exception& e) {
        throw IoError(file, std::string("cannot encode EXR: ") + e.what());
    }
    writeFileAtomic(file, encoded.str());
}

std::vector<float> readExrRgb(const std::string& file, int& width, int& height) {
    const std::string bytes = readFileBytes(file);
    const ExrDataWindow w = checkExrHeader(file, bytes);
    const std::vector<Imf::Rgba> px = decodeRgba(file, bytes, w);
    width = w.width();
    height = w.height();
    std::vector<float> rgb(px.size() * 3);
    for (std::size_t i = 0; i < px.size(); ++i) {
        rgb[i * 3 + 0] = px[i].r;
        rgb[i * 3 + 1] = px[i].g;
        rgb[i * 3 + 2] = px[i].b;
    }
    return rgb;
}

void writeExrChannels(const std::string& file, const std::vector<std::string>& names,
                      const std::vector<const Grid*>& grids, float cellSize) {
    if (grids.empty() || names.size() != grids.size()) throw IoError(file, "EXR output needs one name per channel");
    const int w = grids[0]->nx, h = grids[0]->ny;
    Imf::Header header(w, h);
    header.compression() = Imf::ZIP_COMPRESSION;  // lossless
    if (cellSize > 0.0f) header.insert(kCellSizeAttribute, Imf::FloatAttribute(cellSize));
    Imf::FrameBuffer fb;
    for (std::size_t k = 0; k < grids.size(); ++k) {
        if (grids[k]->nx != w || grids[k]->ny != h) throw IoError(file, "EXR channels of different sizes");
        if (names[k].empty() || header.channels().findChannel(names[k]))
            throw IoError(file, "EXR channel names must be distinct and not empty ('" + names[k] + "')");
        header.channels().insert(names[k], Imf::Channel(Imf::FLOAT));
        fb.insert(names[k], Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(const_cast<float*>(grids[k]->data())),
                                       sizeof(float), sizeof(float) * static_cast<std::size_t>(w)));
    }
    Imf::StdOSStream encoded;
    try {
        // the file's offset table is written when `out` closes, at the end of this scope
        Imf::OutputFile out(encoded, header);
        out.setFrameBuffer(fb);
        out.writePixels(h);
    } catch (const std::exception& e) {
        throw IoError(file, std::string("cannot encode EXR: ") + e.what());
    }
    writeFileAtomic(file, encoded.str());
}

ExrChannels readExrChannels(const std::string& file, const std::string& only) {
    const std::string bytes = readFileBytes(file);
    const ExrDataWindow w = checkExrHeader(file, bytes);
    return decodeChannels(file, bytes, w, only);
}

}  // namespace terrain
