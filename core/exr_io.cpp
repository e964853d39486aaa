// OpenEXR through its C++ interface, in memory both ways: a frame is encoded
// into memory and written with the checked atomic writer (OpenEXR's own file
// output drops errors raised while it closes the file), and a file is read
// once, its header checked (core/exr_header.h), then decoded from memory.
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include <OpenEXR/Iex.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfIO.h>
#include <OpenEXR/ImfRgbaFile.h>
#include <OpenEXR/ImfStdIO.h>

#include "core/error.h"
#include "core/exr_header.h"
#include "core/file_io.h"
#include "core/image_io.h"

namespace terrain {
namespace {

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

// The pixels of an RGBA file, one Rgba per pixel of the data window.
std::vector<Imf::Rgba> decodeRgba(const std::string& file, const std::string& bytes, const ExrDataWindow& w) {
    std::vector<Imf::Rgba> px(static_cast<std::size_t>(w.width()) * static_cast<std::size_t>(w.height()));
    try {
        MemoryInput stream(file, bytes);
        Imf::RgbaInputFile in(stream);
        const Imath::Box2i dw = in.dataWindow();
        if (dw.min.x != w.x0 || dw.min.y != w.y0 || dw.max.x != w.x1 || dw.max.y != w.y1)
            throw IoError(file, "corrupt EXR: inconsistent data window");
        // OpenEXR addresses pixel (x, y) at base + x + y * width; the base lies
        // outside the buffer when the window does not start at (0, 0), so it is
        // computed in integers rather than as an out-of-range pointer.
        const std::uintptr_t origin = reinterpret_cast<std::uintptr_t>(px.data()) -
                                      (static_cast<std::uintptr_t>(std::intptr_t{w.x0}) +
                                       static_cast<std::uintptr_t>(std::intptr_t{w.y0}) * w.width()) *
                                          sizeof(Imf::Rgba);
        in.setFrameBuffer(reinterpret_cast<Imf::Rgba*>(origin), 1, static_cast<std::size_t>(w.width()));
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

}  // namespace terrain
