// Hostile input and failing disks: every reader either reads a damaged file
// or throws terrain::Error quickly, with bounded memory and a bounded
// message; every writer reports a failed write and leaves the previous file
// as it was.
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include <doctest/doctest.h>
#include <sys/resource.h>
#include <unistd.h>
#include <zlib.h>

#include "core/error.h"
#include "core/file_io.h"
#include "core/image_io.h"
#include "core/png_io.h"
#include "core/size_limits.h"
#include "gi/albedo_io.h"
#include "sim/heightmap_io.h"
#include "sim/terrain.h"
#include "sim/vdb_io.h"
#include "tests/scratch_files.h"

using namespace terrain;
namespace fs = std::filesystem;
using terrain::test::readBytes;
using terrain::test::scratchDir;
using terrain::test::writeBytes;

namespace {

int filesIn(const fs::path& dir) {
    int n = 0;
    for (const auto& e : fs::directory_iterator(dir)) n += e.is_regular_file() ? 1 : 0;
    return n;
}

// The longest message an IoError about `file` may carry.
std::size_t messageBound(const fs::path& file) { return file.string().size() + 2 + kMaxErrorDetail; }

// Runs read(); it may succeed, or throw a terrain::Error whose message is
// one bounded line. Anything else (another exception) fails the test.
// Returns whether it threw.
bool readsOrFailsCleanly(const fs::path& file, const std::function<void()>& read) {
    try {
        read();
        return false;
    } catch (const Error& e) {
        const std::string what = e.what();
        CHECK(what.size() <= messageBound(file));
        CHECK(what.find('\n') == std::string::npos);
        return true;
    } catch (const std::exception& e) {
        FAIL("not a terrain::Error: " << e.what());
    }
    return true;
}

// Damaged copies of a file: 1 to 4 bytes each overwritten (random, 0, 0xff,
// or one bit flipped), half of them within the first headBytes (headers,
// tables), from a fixed seed.
std::vector<std::string> mutants(const std::string& bytes, int count, std::size_t headBytes) {
    std::mt19937 rng(20240611u);
    std::vector<std::string> out;
    for (int m = 0; m < count; ++m) {
        std::string b = bytes;
        const int edits = 1 + static_cast<int>(rng() % 4);
        for (int e = 0; e < edits; ++e) {
            const std::size_t span = (m % 2 == 0) ? std::min(headBytes, b.size()) : b.size();
            const std::size_t at = rng() % span;
            switch (rng() % 4) {
                case 0:
                    b[at] = static_cast<char>(rng());
                    break;
                case 1:
                    b[at] = 0;
                    break;
                case 2:
                    b[at] = static_cast<char>(0xff);
                    break;
                default:
                    b[at] = static_cast<char>(b[at] ^ (1 << (rng() % 8)));
                    break;
            }
        }
        out.push_back(std::move(b));
    }
    return out;
}

// Fails when the enclosed reads took long or grew the process's peak memory
// by much: the readers must check sizes before allocating.
class CostGuard {
public:
    CostGuard() : start_(std::chrono::steady_clock::now()), peakKb_(peakKb()) {}
    ~CostGuard() {
        const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
        CHECK_MESSAGE(seconds < 20.0, "reads took " << seconds << " s");
        CHECK_MESSAGE(peakKb() - peakKb_ < 1024 * 1024,
                      "peak memory grew by " << (peakKb() - peakKb_) / 1024 << " MiB");
    }

private:
    static long peakKb() {
        rusage u{};
        getrusage(RUSAGE_SELF, &u);
        return u.ru_maxrss;
    }
    std::chrono::steady_clock::time_point start_;
    long peakKb_;
};

// A file size limit for this process, as a full disk would be: writes past
// it fail with EFBIG (SIGXFSZ ignored meanwhile).
class FileSizeLimit {
public:
    explicit FileSizeLimit(rlim_t bytes) {
        getrlimit(RLIMIT_FSIZE, &saved_);
        savedHandler_ = std::signal(SIGXFSZ, SIG_IGN);
        rlimit limit = saved_;
        limit.rlim_cur = bytes;
        setrlimit(RLIMIT_FSIZE, &limit);
    }
    ~FileSizeLimit() {
        setrlimit(RLIMIT_FSIZE, &saved_);
        std::signal(SIGXFSZ, savedHandler_);
    }

private:
    rlimit saved_{};
    void (*savedHandler_)(int) = nullptr;
};

TerrainState smallTerrain(int nx, int ny) {
    TerrainState s;
    s.allocate(nx, ny, 2.0f, LayerSet{.water = true, .sediment = true});
    for (std::size_t i = 0; i < s.bedrock.size(); ++i) {
        s.bedrock.v[i] = 100.0f + 0.37f * static_cast<float>(i % 17) - 0.11f * static_cast<float>(i % 5);
        s.soil.v[i] = 0.01f * static_cast<float>(i % 3);
        s.water.v[i] = (i % 4 == 0) ? 0.0f : 0.5f;
        s.suspended.v[i] = 1e-4f * static_cast<float>(i % 7);
    }
    return s;
}

// --- PNG crafting -----------------------------------------------------------
std::string bigEndian(std::uint32_t v) {
    return {static_cast<char>(v >> 24), static_cast<char>(v >> 16), static_cast<char>(v >> 8), static_cast<char>(v)};
}

std::string pngChunk(const std::string& type, const std::string& data) {
    const std::string body = type + data;
    const auto crc = static_cast<std::uint32_t>(
        crc32(0, reinterpret_cast<const Bytef*>(body.data()), static_cast<uInt>(body.size())));
    return bigEndian(static_cast<std::uint32_t>(data.size())) + body + bigEndian(crc);
}

// A PNG with the given header and deflate-compressed `pixels` as its data.
std::string pngFile(std::uint32_t w, std::uint32_t h, int depth, int colour, const std::string& pixels) {
    uLongf packedSize = compressBound(static_cast<uLong>(pixels.size()));
    std::string packed(packedSize, '\0');
    compress(reinterpret_cast<Bytef*>(packed.data()), &packedSize, reinterpret_cast<const Bytef*>(pixels.data()),
             static_cast<uLong>(pixels.size()));
    packed.resize(packedSize);
    const std::string ihdr =
        bigEndian(w) + bigEndian(h) + std::string{static_cast<char>(depth), static_cast<char>(colour), 0, 0, 0};
    return "\x89PNG\r\n\x1a\n" + pngChunk("IHDR", ihdr) + pngChunk("IDAT", packed) + pngChunk("IEND", "");
}

// Recomputes every chunk's CRC, so a damaged chunk reaches the decoder
// instead of failing its checksum.
void fixPngCrcs(std::string& png) {
    std::size_t at = 8;
    while (at + 12 <= png.size()) {
        const std::uint32_t length = (std::uint32_t{static_cast<unsigned char>(png[at])} << 24) |
                                     (std::uint32_t{static_cast<unsigned char>(png[at + 1])} << 16) |
                                     (std::uint32_t{static_cast<unsigned char>(png[at + 2])} << 8) |
                                     static_cast<unsigned char>(png[at + 3]);
        if (length > png.size() - at - 12) return;
        const auto crc = static_cast<std::uint32_t>(
            crc32(0, reinterpret_cast<const Bytef*>(png.data() + at + 4), static_cast<uInt>(length + 4)));
        png.replace(at + 8 + length, 4, bigEndian(crc));
        at += 12 + length;
    }
}

// --- Radiance HDR crafting --------------------------------------------------
std::string hdrHeader(const std::string& resolution) {
    return "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n" + resolution + "\n";
}

// A w x h image, run-length encoded (w >= 8): each channel one run per row.
std::string hdrFile(int w, int h) {
    std::string b = hdrHeader("-Y " + std::to_string(h) + " +X " + std::to_string(w));
    for (int y = 0; y < h; ++y) {
        b += {2, 2, static_cast<char>(w >> 8), static_cast<char>(w & 0xff)};
        for (int c = 0; c < 4; ++c)
            for (int x = 0; x < w; x += 127) {
                const int run = std::min(127, w - x);
                b += static_cast<char>(128 + run);
                b += static_cast<char>(c == 3 ? 128 + y : 10 * c + y);
            }
    }
    return b;
}

}  // namespace

// ---------------------------------------------------------------------------
// Errors and failing writes
// ---------------------------------------------------------------------------
TEST_CASE("io.bad: an error's detail is one bounded line") {
    const IoError e("f.vdb", std::string(5000, 'x') + "\nsecond line\x01");
    const std::string what = e.what();
    CHECK(what.size() == std::string("f.vdb: ").size() + kMaxErrorDetail);
    CHECK(what.find('\n') == std::string::npos);
    CHECK(what.substr(what.size() - 3) == "...");
    CHECK(boundedLine("a\tb\nc") == "a b c");
    CHECK(boundedLine("\xc3\xa9\xc3\xa9\xc3\xa9x", 6) == "\xc3\xa9...");  // never half a character
    CHECK(boundedLine("\xc3\xa9\xc3\xa9\xc3\xa9x", 7) == "\xc3\xa9\xc3\xa9\xc3\xa9x");
}

TEST_CASE("io.bad: a write that fails at flush or close is an error (/dev/full)") {
    std::FILE* full = std::fopen("/dev/full", "wb");
    REQUIRE(full != nullptr);
    const std::string data(1000, 'x');
    CHECK(std::fwrite(data.data(), 1, data.size(), full) == data.size());  // buffered: looks fine
    CHECK_THROWS_WITH_AS(closeWrittenFile(full, "out.bin"), doctest::Contains("out.bin: write failed"), IoError);
}

TEST_CASE("io.bad: every writer reports a full disk and keeps the previous file") {
    const fs::path dir = scratchDir("full");
    const TerrainState s = smallTerrain(40, 30);
    Grid h;
    s.groundHeight(h);
    const std::vector<std::pair<std::string, std::function<void(const std::string&)>>> writers = {
        {"frame.vdb", [&](const std::string& f) { writeVdb(f, s); }},
        {"frame.png", [&](const std::string& f) { writePngHeightmap(f, h, 0.01f, 0.0f); }},
        {"frame.exr",
         [&](const std::string& f) {
             writeExr(f, {&s.bedrock, &s.soil, &s.water});
         }},
        {"frame.npy", [&](const std::string& f) { writeNpy(f, h); }},
        {"frame.txt", [&](const std::string& f) { writeFileAtomic(f, std::string(100000, 't')); }},
    };
    for (const auto& writer : writers) {
        // plain locals: Clang 14 lambdas (doctest's CAPTURE) cannot capture structured bindings
        const std::string& name = writer.first;
        const auto& write = writer.second;
        CAPTURE(name);
        const std::string file = (dir / name).string();
        writeBytes(file, std::string(64, 'k'));  // the previous, good file
        {
            const FileSizeLimit limit(48);
            CHECK_THROWS_WITH_AS(write(file), doctest::Contains(name.c_str()), IoError);
        }
        CHECK(readBytes(file) == std::string(64, 'k'));
        CHECK(filesIn(dir) == 1);  // no temporary left behind
        write(file);               // and without the limit it writes
        CHECK(readBytes(file).size() > 64);
        fs::remove(file);
    }
    fs::remove_all(dir);
}

TEST_CASE("io.bad: writing onto a folder fails and leaves the folder") {
    const fs::path dir = scratchDir("folder");
    fs::create_directories(dir / "out.npy");
    Grid g(4, 4, 1.0f);
    CHECK_THROWS_AS(writeNpy((dir / "out.npy").string(), g), IoError);
    CHECK(fs::is_directory(dir / "out.npy"));
    CHECK(filesIn(dir) == 0);
    fs::remove_all(dir);
}

// ---------------------------------------------------------------------------
// OpenVDB
// ---------------------------------------------------------------------------
TEST_CASE("io.bad: truncated VDB frames fail quickly at every length") {
    const fs::path dir = scratchDir("vdbcut");
    const fs::path good = dir / "good.vdb", cut = dir / "cut.vdb";
    writeVdb(good.string(), smallTerrain(12, 10));
    const std::string bytes = readBytes(good);
    const CostGuard cost;
    for (std::size_t length = 0; length < bytes.size(); length += (length < 400 ? 1 : 211)) {
        CAPTURE(length);
        writeBytes(cut, bytes.substr(0, length));
        TerrainState r;
        CHECK(readsOrFailsCleanly(cut, [&] { readVdb(cut.string(), r, {}); }));
    }
    fs::remove_all(dir);
}

TEST_CASE("io.bad: 300 damaged VDB frames each read back or fail cleanly") {
    const fs::path dir = scratchDir("vdbmut");
    const fs::path good = dir / "good.vdb", bad = dir / "bad.vdb";
    const TerrainState s = smallTerrain(12, 10);
    writeVdb(good.string(), s);
    const CostGuard cost;
    int failed = 0;
    for (const std::string& m : mutants(readBytes(good), 300, 1200)) {
        writeBytes(bad, m);
        TerrainState r;
        failed += readsOrFailsCleanly(bad, [&] {
            readVdb(bad.string(), r, LayerSet{.water = true, .sediment = true});
            checkFinite(r);
        });
    }
    MESSAGE(failed << " of 300 damaged frames rejected");
    CHECK(failed > 0);
    fs::remove_all(dir);
}

TEST_CASE("io.bad: a VDB file that is not a frame is rejected with one line") {
    const fs::path dir = scratchDir("vdbnot");
    const fs::path good = dir / "good.vdb", bad = dir / "bad.vdb";
    writeVdb(good.string(), smallTerrain(12, 10));
    const std::string bytes = readBytes(good);
    auto patched = [&](std::size_t at, std::uint32_t value) {
        std::string b = bytes;
        std::memcpy(&b[at], &value, 4);
        writeBytes(bad, b);
        TerrainState r;
        try {
            readVdb(bad.string(), r, {});
        } catch (const IoError& e) {
            return std::string(e.what());
        }
        return std::string("no error");
    };
    CHECK(patched(8, 225).find("format 225 is not supported") != std::string::npos);  // version
    const std::size_t gridCountAt = 8 + 4 + 8 + 1 + 36 + 4;                           // after an empty file metadata
    CHECK(patched(gridCountAt, 0x7fffffff).find("2147483647 grids") != std::string::npos);  // grid count
    CHECK(patched(gridCountAt, 0).find("contains no grids") != std::string::npos);
    std::string stream = bytes;
    stream[20] = 0;  // the grid offsets flag io::Stream writes
    writeBytes(bad, stream);
    TerrainState r;
    CHECK_THROWS_WITH_AS(readVdb(bad.string(), r, {}), doctest::Contains("stream"), IoError);
    fs::remove_all(dir);
}

// ---------------------------------------------------------------------------
// PNG
// ---------------------------------------------------------------------------
TEST_CASE("io.bad: a PNG's declared size is checked before anything is allocated") {
    const fs::path dir = scratchDir("pngsize");
    const fs::path file = dir / "h.png";
    const CostGuard cost;
    const std::string huge = pngFile(60000, 60000, 16, 0, std::string(64, '\0'));
    CHECK(huge.size() < 100);
    writeBytes(file, huge);
    CHECK_THROWS_WITH_AS(readPngHeightmap(file.string()), doctest::Contains("60000 x 60000 pixels"), IoError);
    CHECK_THROWS_WITH_AS(peekPngHeader(file.string()), doctest::Contains("1 to 16384"), IoError);
    // within the limit but far more pixels than a file this short can hold
    writeBytes(file, pngFile(16384, 16384, 16, 0, std::string(64, '\0')));
    CHECK_THROWS_WITH_AS(readPngHeightmap(file.string()), doctest::Contains("truncated PNG"), IoError);
    writeBytes(file, pngFile(0, 0, 16, 0, ""));
    CHECK_THROWS_WITH_AS(readPngHeightmap(file.string()), doctest::Contains("0 x 0"), IoError);
    fs::remove_all(dir);
}

TEST_CASE("io.bad: truncated and damaged PNGs throw terrain::Error") {
    const fs::path dir = scratchDir("pngmut");
    const fs::path good = dir / "good.png", bad = dir / "bad.png";
    Grid h(23, 17);
    for (std::size_t i = 0; i < h.size(); ++i) h.v[i] = static_cast<float>((i * 7919) % 65536);
    writePngHeightmap(good.string(), h, 1.0f, 0.0f);
    const std::string bytes = readBytes(good);
    const CostGuard cost;
    for (std::size_t length = 0; length < bytes.size(); ++length) {
        CAPTURE(length);
        writeBytes(bad, bytes.substr(0, length));
        CHECK(readsOrFailsCleanly(bad, [&] { readPngHeightmap(bad.string()); }));
    }
    int failed = 0;
    for (std::string m : mutants(bytes, 300, 64)) {
        fixPngCrcs(m);  // so the damage reaches the decoder
        writeBytes(bad, m);
        failed += readsOrFailsCleanly(bad, [&] { readPngHeightmap(bad.string()); });
    }
    MESSAGE(failed << " of 300 damaged PNGs rejected");
    CHECK(failed > 0);
    fs::remove_all(dir);
}

TEST_CASE("io.bad: 8-bit grey PNGs are read at 16-bit scale, colour PNGs rejected") {
    const fs::path dir = scratchDir("png8");
    const fs::path file = dir / "h.png";
    std::string rows;
    for (int y = 0; y < 3; ++y) rows += std::string{0, static_cast<char>(10 * y), static_cast<char>(255), 7, 0};
    writeBytes(file, pngFile(4, 3, 8, 0, rows));
    int depth = 0;
    const Grid g = readPngHeightmap(file.string(), 1.0f, 0.0f, &depth);
    CHECK(depth == 8);
    CHECK(g(0, 2) == 20.0f * 257.0f);
    CHECK(g(1, 0) == 65535.0f);
    CHECK(readHeightmap(file.string(), 1.0f, 0.0f).nx == 4);  // accepted, with a warning on stderr
    std::string rgb;
    for (int y = 0; y < 3; ++y) rgb += std::string(1, '\0') + std::string(12, 'a');
    writeBytes(file, pngFile(4, 3, 8, 2, rgb));
    CHECK_THROWS_WITH_AS(readPngHeightmap(file.string()), doctest::Contains("is a colour PNG (RGB)"), IoError);
    fs::remove_all(dir);
}

TEST_CASE("io.bad: tiny heightmaps and non-finite heights name the problem") {
    const fs::path dir = scratchDir("hmsmall");
    const std::string png = (dir / "one.png").string();
    writePngHeightmap(png, Grid(1, 1, 5.0f), 1.0f, 0.0f);
    CHECK(readPngHeightmap(png).nx == 1);  // a valid PNG...
    CHECK_THROWS_WITH_AS(readHeightmap(png, 1.0f, 0.0f), doctest::Contains("at least 2 x 2"), IoError);  // ...too small
    TerrainState line;
    line.allocate(5, 1, 1.0f, {});
    const std::string vdb = (dir / "line.vdb").string();
    writeVdb(vdb, line);
    CHECK_THROWS_WITH_AS(readHeightmap(vdb, 1.0f, 0.0f), doctest::Contains("5 x 1 cells"), IoError);
    Grid ramp(3, 2);
    ramp(1, 0) = 65535.0f;
    const std::string rampFile = (dir / "ramp.png").string();
    writePngHeightmap(rampFile, ramp, 1.0f, 0.0f);
    CHECK_THROWS_WITH_AS(readHeightmap(rampFile, 1e38f, 1e38f), doctest::Contains("pixel (1, 0)"), IoError);
    fs::remove_all(dir);
}

TEST_CASE("io.bad: albedo and exponent maps check their header before decoding") {
    const fs::path dir = scratchDir("albedo");
    const fs::path file = dir / "a.png";
    const CostGuard cost;
    writeBytes(file, pngFile(16384, 16384, 8, 2, std::string(64, '\0')));
    CHECK_THROWS_WITH_AS(gi::loadAlbedo(file.string(), 16384, 16384), doctest::Contains("truncated PNG"), IoError);
    std::vector<std::uint8_t> rgb(8 * 6 * 3, 90);
    writePngRgb(file.string(), 8, 6, rgb);
    const std::string bytes = readBytes(file);
    writeBytes(file, bytes.substr(0, bytes.size() - 20));
    CHECK_THROWS_AS(gi::loadAlbedo(file.string(), 8, 6), IoError);
    writePngHeightmap(file.string(), Grid(8, 6, 3.0f), 1.0f, 0.0f);
    writeBytes(file, readBytes(file).substr(0, 60));
    gi::AlbedoMap map = gi::loadAlbedo("0.5,0.5,0.5", 8, 6);
    CHECK_THROWS_AS(gi::loadPhongExponentMap(file.string(), 8, 6, 2.0f, 50.0f, map), IoError);
    fs::remove_all(dir);
}

// ---------------------------------------------------------------------------
// Environment maps: Radiance HDR and OpenEXR
// ---------------------------------------------------------------------------
TEST_CASE("io.bad: HDR sizes are checked against the limit and the file") {
    const fs::path dir = scratchDir("hdr");
    const fs::path file = dir / "sky.hdr";
    int w = 0, h = 0;
    writeBytes(file, hdrFile(20, 3));
    const std::vector<float> rgb = readHdrRgb(file.string(), w, h);
    CHECK((w == 20 && h == 3));
    CHECK(rgb[3 * (2 * 20 + 5) + 1] == std::ldexp(12.0f, 128 + 2 - 136));  // green of row 2
    const CostGuard cost;
    writeBytes(file, hdrHeader("-Y 4 +X 30000") + std::string(8, '\x02'));
    CHECK_THROWS_WITH_AS(readHdrRgb(file.string(), w, h), doctest::Contains("30000 x 4 pixels"), IoError);
    writeBytes(file, hdrHeader("-Y 65536 +X 65536"));
    CHECK_THROWS_WITH_AS(readHdrRgb(file.string(), w, h), doctest::Contains("1 to 16384"), IoError);
    writeBytes(file, hdrHeader("-Y 1000 +X 1000") + std::string(10, '\x02'));
    CHECK_THROWS_WITH_AS(readHdrRgb(file.string(), w, h), doctest::Contains("truncated HDR"), IoError);
    writeBytes(file, hdrHeader("-Y 99999999999999999999 +X 4"));
    CHECK_THROWS_WITH_AS(readHdrRgb(file.string(), w, h), doctest::Contains("resolution line"), IoError);
    writeBytes(file, "#?RADIANCE\n" + std::string(200000, 'x'));
    CHECK_THROWS_WITH_AS(readHdrRgb(file.string(), w, h), doctest::Contains("header"), IoError);
    fs::remove_all(dir);
}

TEST_CASE("io.bad: truncated and damaged HDR and EXR maps fail cleanly") {
    const fs::path dir = scratchDir("envmut");
    const fs::path hdr = dir / "sky.hdr", exr = dir / "sky.exr";
    writeBytes(hdr, hdrFile(20, 6));
    const TerrainState s = smallTerrain(12, 7);
    writeExr(exr.string(), {&s.bedrock, &s.soil, &s.water});
    int w = 0, h = 0;
    const std::vector<float> back = readExrRgb(exr.string(), w, h);
    CHECK((w == 12 && h == 7 && back[3 * 5] == doctest::Approx(s.bedrock.v[5]).epsilon(1e-3)));
    const CostGuard cost;
    for (const fs::path& file : {hdr, exr}) {
        CAPTURE(file);
        const std::string bytes = readBytes(file);
        const fs::path bad = dir / ("bad" + file.extension().string());
        for (std::size_t length = 0; length < bytes.size(); length += (length < 200 ? 1 : 7)) {
            writeBytes(bad, bytes.substr(0, length));
            CHECK(readsOrFailsCleanly(bad, [&] { readEquirect(bad.string(), w, h); }));
        }
        for (const std::string& m : mutants(bytes, 300, 400)) {
            writeBytes(bad, m);
            readsOrFailsCleanly(bad, [&] { readEquirect(bad.string(), w, h); });
        }
    }
    fs::remove_all(dir);
}

TEST_CASE("io.bad: an EXR data window is checked before OpenEXR allocates") {
    const fs::path dir = scratchDir("exrwin");
    const fs::path file = dir / "sky.exr";
    const TerrainState s = smallTerrain(12, 7);
    writeExr(file.string(), {&s.bedrock});
    const std::string bytes = readBytes(file);
    const std::size_t window = bytes.find("dataWindow");
    REQUIRE(window != std::string::npos);
    const std::size_t box = window + std::string("dataWindow").size() + 1 + std::string("box2i").size() + 1 + 4;
    auto withWindow = [&](std::int32_t x1, std::int32_t y1) {
        std::string b = bytes;
        std::memcpy(&b[box + 8], &x1, 4);
        std::memcpy(&b[box + 12], &y1, 4);
        writeBytes(file, b);
    };
    const CostGuard cost;
    int w = 0, h = 0;
    withWindow(999999, 6);
    CHECK_THROWS_WITH_AS(readExrRgb(file.string(), w, h), doctest::Contains("1 to 16384"), IoError);
    withWindow(11, 16000);
    CHECK_THROWS_WITH_AS(readExrRgb(file.string(), w, h), doctest::Contains("truncated EXR"), IoError);
    withWindow(11, std::numeric_limits<std::int32_t>::max());
    CHECK_THROWS_AS(readExrRgb(file.string(), w, h), IoError);
    fs::remove_all(dir);
}
