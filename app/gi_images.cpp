#include "app/gi_images.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/geotiff_io.h"
#include "core/image_io.h"
#include "core/png_io.h"

namespace terrain::app {
namespace {

std::uint8_t srgbByte(float linear) {
    const float v = std::clamp(linear, 0.0f, 1.0f);
    const float e = v <= 0.0031308f ? 12.92f * v : 1.055f * std::pow(v, 1.0f / 2.4f) - 0.055f;
    return static_cast<std::uint8_t>(std::lround(e * 255.0f));
}

// The false-colour ramp: t in [0, 1] through control colours (sRGB bytes)
// of rising lightness.
std::array<std::uint8_t, 3> ramp(float t) {
    static const float stops[6][3] = {{0, 0, 0},     {40, 20, 110},  {150, 30, 140},
                                      {235, 90, 60}, {250, 200, 40}, {255, 255, 255}};
    const float x = std::clamp(t, 0.0f, 1.0f) * 5.0f;
    const int i = std::min(static_cast<int>(x), 4);
    const float f = x - static_cast<float>(i);
    std::array<std::uint8_t, 3> c;
    for (int k = 0; k < 3; ++k)
        c[static_cast<std::size_t>(k)] =
            static_cast<std::uint8_t>(std::lround(stops[i][k] + f * (stops[i + 1][k] - stops[i][k])));
    return c;
}

void writeFalseColour(const std::string& file, const std::array<Grid, 3>& rgb) {
    const std::size_t n = rgb[0].size();
    std::vector<float> lum(n);
    for (std::size_t i = 0; i < n; ++i) lum[i] = 0.2126f * rgb[0].v[i] + 0.7152f * rgb[1].v[i] + 0.0722f * rgb[2].v[i];
    std::vector<float> sorted = lum;
    const std::size_t at = std::min(n - 1, n * 99 / 100);
    std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(at), sorted.end());
    const float top = sorted[at] > 0.0f ? sorted[at] : 1.0f;
    std::vector<std::uint8_t> px(n * 3);
    for (std::size_t i = 0; i < n; ++i) {
        const std::array<std::uint8_t, 3> c = ramp(lum[i] / top);
        std::copy(c.begin(), c.end(), px.begin() + static_cast<std::ptrdiff_t>(3 * i));
    }
    writePngRgb(file, rgb[0].nx, rgb[0].ny, px, 3);
}

}  // namespace

std::string extensionOf(const std::string& f) {
    const auto dot = f.find_last_of('.');
    std::string e = dot == std::string::npos ? "" : f.substr(dot);
    for (char& c : e) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return e;
}

void writeShade(const std::string& file, const std::array<Grid, 3>& rgb, float exposure, const GeoReference& geo) {
    const std::string ext = extensionOf(file);
    if (ext == ".exr") {
        writeExr(file, {&rgb[0], &rgb[1], &rgb[2]});
        return;
    }
    if (isGeoTiffPath(file)) {
        writeGeoTiff(file, rgb, geo);
        return;
    }
    if (ext != ".png") throw InputError("--out-shade must end in .png, .exr or .tif (got '" + file + "')");
    std::vector<std::uint8_t> px(rgb[0].size() * 3);
    for (std::size_t i = 0; i < rgb[0].size(); ++i)
        for (std::size_t c = 0; c < 3; ++c) px[i * 3 + c] = srgbByte(exposure * rgb[c].v[i]);
    writePngRgb(file, rgb[0].nx, rgb[0].ny, px, 3);
}

void writeAmbient(const std::string& file, const Grid& ambient, const GeoReference& geo) {
    const std::string ext = extensionOf(file);
    if (ext == ".npy")
        writeNpy(file, ambient);
    else if (ext == ".exr")
        writeExr(file, {&ambient});
    else if (isGeoTiffPath(file))
        writeGeoTiff(file, std::span<const Grid>(&ambient, 1), geo);
    else
        throw InputError("--out-ambient must end in .npy, .exr or .tif (got '" + file + "')");
}

void writeIndirect(const std::string& file, const std::array<Grid, 3>& rgb, const GeoReference& geo) {
    const std::string ext = extensionOf(file);
    if (isGeoTiffPath(file))
        writeGeoTiff(file, rgb, geo);
    else if (ext == ".npy")
        writeNpyRgb(file, rgb);
    else if (ext == ".exr")
        writeExr(file, {&rgb[0], &rgb[1], &rgb[2]});
    else if (ext == ".png")
        writeFalseColour(file, rgb);
    else
        throw InputError("--out-indirect must end in .npy, .exr, .png or .tif (got '" + file + "')");
}

void writeGiExr(const std::string& file, const Grid& heights, float cellSize, const std::array<Grid, 3>& shade,
                const Grid& ambient, const std::array<Grid, 3>* indirect) {
    std::vector<std::string> names{"height", "ambient", "shade.R", "shade.G", "shade.B"};
    std::vector<const Grid*> grids{&heights, &ambient, &shade[0], &shade[1], &shade[2]};
    if (indirect) {
        names.insert(names.end(), {"indirect.R", "indirect.G", "indirect.B"});
        grids.insert(grids.end(), {&(*indirect)[0], &(*indirect)[1], &(*indirect)[2]});
    }
    writeExrChannels(file, names, grids, cellSize);
}

}  // namespace terrain::app
