#include "core/image_io.h"

// OpenEXR's C interface: its C++ headers need Imath include paths that the
// build does not export, and half-float RGBA/Y is all an image viewer needs
// (use .npy for exact float32 ambient values).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>

#include <OpenEXR/ImfCRgbaFile.h>

#include "core/error.h"
#include "core/file_io.h"

namespace terrain {

namespace {

std::string lowerExtension(const std::string& file) {
    const auto dot = file.find_last_of('.');
    std::string e = dot == std::string::npos ? "" : file.substr(dot);
    for (char& c : e) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return e;
}

}  // namespace

void writeNpyArray(const std::string& file, const std::vector<std::size_t>& shape, const float* data) {
    std::string dims;
    std::size_t count = 1;
    for (std::size_t d : shape) {
        dims += std::to_string(d) + ", ";
        count *= d;
    }
    if (shape.size() > 1)
        dims.erase(dims.size() - 2);  // "(ny, nx)"; a 1-tuple keeps its comma: "(n,)"
    else if (!dims.empty())
        dims.erase(dims.size() - 1);
    std::string header = "{'descr': '<f4', 'fortran_order': False, 'shape': (" + dims + "), }";
    // magic (6) + version (2) + header length (2) + header, padded to 64 bytes, ending in '\n'
    const std::size_t total = 10 + header.size() + 1;
    header.append((64 - total % 64) % 64, ' ');
    header.push_back('\n');
    std::string bytes = "\x93NUMPY";
    bytes.push_back('\x01');
    bytes.push_back('\x00');
    const std::uint16_t len = static_cast<std::uint16_t>(header.size());
    bytes.push_back(static_cast<char>(len & 0xff));
    bytes.push_back(static_cast<char>(len >> 8));
    bytes += header;
    const std::size_t off = bytes.size();
    bytes.resize(off + count * 4);
    if (count) std::memcpy(&bytes[off], data, count * 4);  // x86-64 is little-endian
    writeFileAtomic(file, bytes);
}

void writeNpy(const std::string& file, const Grid& g) {
    writeNpyArray(file, {static_cast<std::size_t>(g.ny), static_cast<std::size_t>(g.nx)}, g.data());
}

void writeNpyRgb(const std::string& file, const std::array<Grid, 3>& rgb) {
    const Grid& g0 = rgb[0];
    std::vector<float> interleaved(g0.size() * 3);
    for (std::size_t i = 0; i < g0.size(); ++i)
        for (std::size_t c = 0; c < 3; ++c) interleaved[3 * i + c] = rgb[c].v[i];
    writeNpyArray(file, {static_cast<std::size_t>(g0.ny), static_cast<std::size_t>(g0.nx), 3}, interleaved.data());
}

void writeExr(const std::string& file, const std::vector<const Grid*>& channels) {
    if (channels.empty() || !channels[0] || (channels.size() != 1 && channels.size() != 3))
        throw IoError(file, "EXR output needs 1 or 3 channels");
    const int w = channels[0]->nx, h = channels[0]->ny;
    std::vector<ImfRgba> px(static_cast<std::size_t>(w) * h);
    for (std::size_t i = 0; i < px.size(); ++i) {
        const float r = channels[0]->v[i];
        const float g = channels.size() == 3 ? channels[1]->v[i] : r;
        const float b = channels.size() == 3 ? channels[2]->v[i] : r;
        ImfFloatToHalf(r, &px[i].r);
        ImfFloatToHalf(g, &px[i].g);
        ImfFloatToHalf(b, &px[i].b);
        ImfFloatToHalf(1.0f, &px[i].a);
    }
    const std::string tmp = temporaryNameFor(file);
    ImfHeader* header = ImfNewHeader();
    ImfHeaderSetDataWindow(header, 0, 0, w - 1, h - 1);
    ImfHeaderSetDisplayWindow(header, 0, 0, w - 1, h - 1);
    ImfOutputFile* out = ImfOpenOutputFile(tmp.c_str(), header, channels.size() == 3 ? IMF_WRITE_RGB : IMF_WRITE_Y);
    ImfDeleteHeader(header);
    if (!out) throw IoError(file, std::string("cannot write EXR: ") + ImfErrorMessage());
    const bool ok =
        ImfOutputSetFrameBuffer(out, px.data(), 1, static_cast<std::size_t>(w)) && ImfOutputWritePixels(out, h);
    const std::string err = ok ? "" : ImfErrorMessage();
    ImfCloseOutputFile(out);
    if (!ok) {
        std::remove(tmp.c_str());
        throw IoError(file, "cannot write EXR: " + err);
    }
    commitTemporary(tmp, file);
}

namespace {

std::vector<float> readExrRgb(const std::string& file, int& w, int& h) {
    ImfInputFile* in = ImfOpenInputFile(file.c_str());
    if (!in) throw IoError(file, std::string("cannot read EXR: ") + ImfErrorMessage());
    int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
    ImfHeaderDataWindow(ImfInputHeader(in), &x0, &y0, &x1, &y1);
    w = x1 - x0 + 1;
    h = y1 - y0 + 1;
    if (w <= 0 || h <= 0 || w > 65536 || h > 65536) {
        ImfCloseInputFile(in);
        throw IoError(file, "bad EXR data window");
    }
    std::vector<ImfRgba> px(static_cast<std::size_t>(w) * h);
    const bool ok = ImfInputSetFrameBuffer(in, px.data() - x0 - static_cast<std::ptrdiff_t>(y0) * w, 1,
                                           static_cast<std::size_t>(w)) &&
                    ImfInputReadPixels(in, y0, y1);
    const std::string err = ok ? "" : ImfErrorMessage();
    ImfCloseInputFile(in);
    if (!ok) throw IoError(file, "cannot read EXR: " + err);
    std::vector<float> rgb(px.size() * 3);
    for (std::size_t i = 0; i < px.size(); ++i) {
        rgb[i * 3 + 0] = ImfHalfToFloat(px[i].r);
        rgb[i * 3 + 1] = ImfHalfToFloat(px[i].g);
        rgb[i * 3 + 2] = ImfHalfToFloat(px[i].b);
    }
    return rgb;
}

// Radiance RGBE (.hdr): header lines, blank line, "-Y H +X W", then
// new-style run-length encoded scanlines (or flat RGBE pixels).
std::vector<float> readHdr(const std::string& file, int& w, int& h) {
    std::ifstream in(file, std::ios::binary);
    if (!in) throw IoError(file, "cannot open");
    std::string line;
    bool formatOk = false;
    if (!std::getline(in, line) || line.rfind("#?", 0) != 0) throw IoError(file, "not a Radiance HDR file");
    while (std::getline(in, line) && !line.empty())
        if (line.rfind("FORMAT=32-bit_rle_rgbe", 0) == 0) formatOk = true;
    if (!formatOk) throw IoError(file, "unsupported HDR format (need 32-bit_rle_rgbe)");
    if (!std::getline(in, line)) throw IoError(file, "missing resolution line");
    char ya[3] = {}, xa[3] = {};
    if (std::sscanf(line.c_str(), "%2s %d %2s %d", ya, &h, xa, &w) != 4 || std::string(ya) != "-Y" ||
        std::string(xa) != "+X" || w <= 0 || h <= 0 || w > 65536 || h > 65536)
        throw IoError(file, "unsupported resolution line '" + line + "' (need -Y H +X W)");
    std::vector<unsigned char> data((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::size_t pos = 0;
    auto byte = [&]() -> unsigned char {
        if (pos >= data.size()) throw IoError(file, "truncated pixel data");
        return data[pos++];
    };
    std::vector<float> rgb(static_cast<std::size_t>(w) * h * 3);
    std::vector<unsigned char> scan(static_cast<std::size_t>(w) * 4);
    for (int y = 0; y < h; ++y) {
        const unsigned char b0 = byte(), b1 = byte(), b2 = byte(), b3 = byte();
        if (w >= 8 && w < 32768 && b0 == 2 && b1 == 2 && ((b2 << 8) | b3) == w) {
            for (int c = 0; c < 4; ++c)
                for (int x = 0; x < w;) {
                    int count = byte();
                    if (count > 128) {
                        count -= 128;
                        const unsigned char v = byte();
                        if (x + count > w) throw IoError(file, "bad run length");
                        for (int k = 0; k < count; ++k) scan[static_cast<std::size_t>(x++) * 4 + c] = v;
                    } else {
                        if (count == 0 || x + count > w) throw IoError(file, "bad run length");
                        for (int k = 0; k < count; ++k) scan[static_cast<std::size_t>(x++) * 4 + c] = byte();
                    }
                }
        } else {
            scan[0] = b0;
            scan[1] = b1;
            scan[2] = b2;
            scan[3] = b3;
            for (int x = 1; x < w; ++x)
                for (int c = 0; c < 4; ++c) scan[static_cast<std::size_t>(x) * 4 + c] = byte();
        }
        for (int x = 0; x < w; ++x) {
            const unsigned char* p = &scan[static_cast<std::size_t>(x) * 4];
            const float f = p[3] ? std::ldexp(1.0f, p[3] - 136) : 0.0f;
            float* o = &rgb[(static_cast<std::size_t>(y) * w + x) * 3];
            o[0] = p[0] * f;
            o[1] = p[1] * f;
            o[2] = p[2] * f;
        }
    }
    return rgb;
}

}  // namespace

std::vector<float> readEquirect(const std::string& file, int& width, int& height) {
    const std::string ext = lowerExtension(file);
    if (ext == ".exr") return readExrRgb(file, width, height);
    if (ext == ".hdr") return readHdr(file, width, height);
    throw IoError(file, "environment map must be .exr or .hdr");
}

}  // namespace terrain
