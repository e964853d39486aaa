#include "app/gi_images.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
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

// The planes' compass bearings (degrees clockwise from north) and their
// order by bearing.
struct BearingOrder {
    std::vector<double> bearing;      // per plane, in the engine's order
    std::vector<std::size_t> sorted;  // plane indices by ascending bearing
};
BearingOrder bearingOrder(const gi::HorizonAngles& h, const GeoReference& geo) {
    // a raster without georeferencing is taken as north-up: row 0 north, columns east
    const double east = geo.georeferenced() ? geo.transform[1] : 1.0;
    const double north = geo.georeferenced() ? geo.transform[5] : -1.0;
    BearingOrder b;
    for (double phi : h.azimuths) b.bearing.push_back(gi::compassAzimuthDegrees(phi, east, north));
    b.sorted.resize(b.bearing.size());
    for (std::size_t i = 0; i < b.sorted.size(); ++i) b.sorted[i] = i;
    std::stable_sort(b.sorted.begin(), b.sorted.end(),
                     [&](std::size_t a, std::size_t c) { return b.bearing[a] < b.bearing[c]; });
    return b;
}

std::string exrBearingName(double bearing) {
    const long thousandths = std::lround(bearing * 1000.0);
    char name[32];
    std::snprintf(name, sizeof name, "az%03ld_%03ld", thousandths / 1000, thousandths % 1000);
    return name;
}

std::string tifBearingName(double bearing) {
    char name[32];
    std::snprintf(name, sizeof name, "%.10g", bearing);
    return name;
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

void writeHorizons(const std::string& file, const gi::HorizonAngles& horizons, const GeoReference& geo) {
    const std::string ext = extensionOf(file);
    if (ext != ".npy" && ext != ".exr" && !isGeoTiffPath(file))
        throw InputError("--out-horizons must end in .npy, .exr or .tif (got '" + file + "')");
    if (horizons.degrees.empty()) throw InputError("--out-horizons: no horizon angles to write");
    const BearingOrder order = bearingOrder(horizons, geo);
    const Grid& first = horizons.degrees.front();
    if (ext == ".npy") {
        std::vector<float> planes;
        planes.reserve(first.size() * order.sorted.size());
        for (std::size_t j : order.sorted)
            planes.insert(planes.end(), horizons.degrees[j].v.begin(), horizons.degrees[j].v.end());
        writeNpyArray(file,
                      {order.sorted.size(), static_cast<std::size_t>(first.ny), static_cast<std::size_t>(first.nx)},
                      planes.data());
        return;
    }
    std::vector<std::string> names;
    std::vector<const Grid*> grids;
    for (std::size_t j : order.sorted) {
        names.push_back(ext == ".exr" ? exrBearingName(order.bearing[j]) : tifBearingName(order.bearing[j]));
        grids.push_back(&horizons.degrees[j]);
    }
    if (ext == ".exr") {
        writeExrChannels(file, names, grids);
        return;
    }
    std::vector<Grid> bands;
    for (const Grid* g : grids) bands.push_back(*g);
    writeGeoTiff(file, bands, geo, names);
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
