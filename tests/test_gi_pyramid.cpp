// gi/pyramid: the height pyramid's steps (Eq. 14), levels against analytic
// fields (constant, ramp, single spike), sizes, and determinism.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <utility>
#include <vector>

#include <doctest/doctest.h>

#include "core/parallel.h"
#include "gi/pyramid.h"
#include "tests/gi_test_terrain.h"

using namespace terrain;
using namespace terrain::gi;
using gi_test::gridOf;
using gi_test::sameBits;

namespace {

PyramidSettings pyramidSettings(int levelsPerOctave, int levelOffset, float peakBlend) {
    PyramidSettings ps;
    ps.levelsPerOctave = levelsPerOctave;
    ps.levelOffset = levelOffset;
    ps.peakBlend = peakBlend;
    return ps;
}

// The centred cubic B-spline basis (support [-2, 2], peak 2/3 at 0).
double cubicBspline(double t) {
    t = std::fabs(t);
    if (t < 1.0) return 2.0 / 3.0 - t * t + 0.5 * t * t * t;
    if (t < 2.0) return (2.0 - t) * (2.0 - t) * (2.0 - t) / 6.0;
    return 0.0;
}

// Octave o and blend q of level l (f_l = (1 - q) S_o + q S_(o+1)), clamped to the top octave.
struct LevelBlend {
    int o;
    double q;
};
LevelBlend levelBlend(int l, int kv, int nOctaves) {
    if (l / kv >= nOctaves - 1) return {nOctaves - 1, 0.0};
    return {l / kv, static_cast<double>(l % kv) / kv};
}

// Largest |level l - expected(x, y)| over the receivers at cells x in [x0, x1), y in [y0, y1).
template <class Expected>
double worstLevelError(const HeightPyramid& p, int l, int x0, int x1, int y0, int y1, Expected&& expected) {
    double worst = 0.0;
    const PaddedField& f = p.levels[static_cast<std::size_t>(l)];
    for (int Y = 0; Y < p.nyr; ++Y)
        for (int X = 0; X < p.nxr; ++X) {
            const int x = p.subsample * X, y = p.subsample * Y;
            if (x < x0 || x >= x1 || y < y0 || y >= y1) continue;
            worst = std::max(worst, std::fabs(static_cast<double>(f.row(Y)[X]) - expected(x, y)));
        }
    return worst;
}

Grid bumpy(int nx, int ny) {
    return gridOf(nx, ny, [](int x, int y) {
        return static_cast<float>(30.0 * std::sin(0.13 * x) * std::cos(0.09 * y) + 7.0 * std::sin(0.71 * x + 0.37 * y) +
                                  ((x * 7 + y * 13) % 5 == 0 ? 12.0 : 0.0));
    });
}

// The level samples a receiver reads, logical region plus the replicated column and row.
bool sameLevels(const HeightPyramid& a, const HeightPyramid& b) {
    if (a.levels.size() != b.levels.size() || a.nxr != b.nxr || a.nyr != b.nyr) return false;
    for (std::size_t l = 0; l < a.levels.size(); ++l)
        for (int Y = 0; Y <= a.nyr; ++Y)
            if (!std::equal(a.levels[l].row(Y), a.levels[l].row(Y) + a.nxr + 1, b.levels[l].row(Y),
                            [](float u, float v) { return std::memcmp(&u, &v, sizeof(float)) == 0; }))
                return false;
    return true;
}

}  // namespace

TEST_CASE("gi.pyramid: steps grow as 2^(i / k_v) from one receiver spacing to the domain diagonal (Eq. 14)") {
    struct Case {
        int nx, ny, kv, ov, s;
        float cell;
    };
    const Case cases[] = {{64, 64, 4, 2, 1, 1.0f},
                          {37, 23, 4, 2, 2, 2.5f},
                          {200, 136, 3, 1, 4, 0.5f},
                          {129, 65, 16, 6, 1, 3.0f},
                          {50, 7, 1, 0, 2, 10.0f}};
    for (const Case& c : cases) {
        const Grid g(c.nx, c.ny, 1.0f);
        HeightPyramid p;
        buildHeightPyramid(g.cview(), c.cell, c.s, pyramidSettings(c.kv, c.ov, 0.0f), p);
        INFO(c.nx << "x" << c.ny << " k_v " << c.kv << " o_v " << c.ov << " s " << c.s);
        REQUIRE(p.steps.size() >= 2);
        const double diag = std::hypot(c.nx - 1.0, c.ny - 1.0);
        // the first step is one receiver spacing; each next one 2^(1 / k_v) longer
        CHECK(p.steps[0].tauCells == doctest::Approx(c.s).epsilon(1e-12));
        for (std::size_t i = 1; i < p.steps.size(); ++i)
            CHECK(p.steps[i].tauCells / p.steps[i - 1].tauCells ==
                  doctest::Approx(std::exp2(1.0 / c.kv)).epsilon(1e-12));
        // the last step reaches the diagonal, the one before does not
        CHECK(p.steps.back().tauCells >= diag * (1.0 - 1e-12));
        CHECK(p.steps[p.steps.size() - 2].tauCells < diag);
        // step i (tau = 2^(i / k_v)) reads level i - k_v o_v, raw heights below 0
        int maxLevel = -1;
        for (const PyramidStep& st : p.steps) {
            const double i = c.kv * std::log2(st.tauCells);
            const long iRound = std::lround(i);
            CHECK(std::fabs(i - static_cast<double>(iRound)) < 1e-9);
            const int expected = std::max(-1, static_cast<int>(iRound) - c.kv * c.ov);
            CHECK(st.level == expected);
            CHECK(st.invTauWorld == doctest::Approx(1.0 / (st.tauCells * c.cell)).epsilon(1e-6));
            maxLevel = std::max(maxLevel, expected);
        }
        CHECK(static_cast<int>(p.levels.size()) == maxLevel + 1);
    }
}

TEST_CASE("gi.pyramid: a constant field: octaves and level 0 exactly the constant, every level within 4 ulp") {
    // 2x2 means and maxima of equal values are exact. The B-spline synthesis
    // is not: its four float weights sum to 1 only up to rounding, so levels
    // from octave 1 on may drift by a few ulp (measured: up to 3).
    const std::pair<int, int> sizes[] = {{64, 64}, {37, 23}, {5, 9}, {2, 2}, {1, 1}};
    for (float value : {123.456f, -7.3f})
        for (const auto& size : sizes)
            for (int s : {1, 2, 4})
                for (float blend : {0.0f, 0.5f, 1.0f}) {
                    const int nx = size.first, ny = size.second;  // plain locals: INFO captures them
                    const Grid g(nx, ny, value);
                    HeightPyramid p;
                    buildHeightPyramid(g.cview(), 1.0f, s, pyramidSettings(4, 0, blend), p);
                    INFO(nx << "x" << ny << " s " << s << " peakBlend " << blend << " value " << value);
                    REQUIRE(!p.levels.empty());
                    long octaveOff = 0, level0Off = 0;
                    for (const std::vector<Grid>* oct : {&p.meanOctaves, &p.maxOctaves})
                        for (const Grid& o : *oct)
                            for (float v : o.v) octaveOff += v != value;
                    const double ulp = std::nextafter(std::fabs(value), INFINITY) - std::fabs(value);
                    double worstUlps = 0.0;
                    for (std::size_t l = 0; l < p.levels.size(); ++l) {
                        const PaddedField& f = p.levels[l];
                        for (int Y = 0; Y <= f.ny; ++Y)
                            for (int X = 0; X <= f.nx; ++X) {
                                const float v = f.row(Y)[X];
                                if (l == 0) level0Off += v != value;
                                worstUlps = std::max(worstUlps, std::fabs(static_cast<double>(v) - value) / ulp);
                            }
                    }
                    CHECK(octaveOff == 0);
                    CHECK(level0Off == 0);
                    CHECK(worstUlps <= 4.0);
                }
}

TEST_CASE("gi.pyramid: a linear ramp stays the ramp away from the borders; max octaves add (|a|+|b|)(2^o - 1) / 2") {
    // h = c + a x + b y. A 2x2 mean of a ramp is the ramp at the block centre,
    // and the cubic B-spline reproduces linear functions, so every mean level is
    // the ramp at the receiver. A 2x2 max picks the block's upper corner: the
    // max octave o is the ramp at its texel centre plus (|a| + |b|)(2^o - 1) / 2,
    // so level l with blend p is the ramp plus p ((1 - q) D_o + q D_(o+1)).
    // Tolerance 2e-4: about ten ulp of float rounding on heights below 150
    // (ulp 1.5e-5), and 500 times below the error of a quarter-cell shift (0.1).
    const double c0 = 40.0, a = 0.37, b = -0.21;
    const int nx = 200, ny = 136, kv = 4;
    const Grid g = gridOf(nx, ny, [&](int x, int y) { return static_cast<float>(c0 + a * x + b * y); });
    for (int s : {1, 2, 4})
        for (float blend : {0.0f, 0.5f, 1.0f}) {
            HeightPyramid p;
            buildHeightPyramid(g.cview(), 1.0f, s, pyramidSettings(kv, 0, blend), p);
            const int nOct = p.octaves;
            auto drift = [&](int o) { return (std::fabs(a) + std::fabs(b)) * (std::exp2(o) - 1.0) / 2.0; };
            int checked = 0;
            for (int l = 0; l < static_cast<int>(p.levels.size()); ++l) {
                const LevelBlend lb = levelBlend(l, kv, nOct);
                const int top = lb.q > 0.0 ? lb.o + 1 : lb.o;
                const int margin = 4 << top;  // taps reach 2 texels, and the odd edges replicate
                if (2 * margin >= ny - 1) continue;
                const double lift = blend * ((1.0 - lb.q) * drift(lb.o) + lb.q * drift(lb.o + 1));
                const double err = worstLevelError(p, l, margin, nx - margin, margin, ny - margin,
                                                   [&](int x, int y) { return c0 + a * x + b * y + lift; });
                INFO("s " << s << " peakBlend " << blend << " level " << l);
                CHECK(err < 2e-4);
                ++checked;
            }
            CHECK(checked >= 4 * kv);
        }
}

TEST_CASE("gi.pyramid: a single spike: mean octaves divide it by 4^o, max octaves keep it, levels blend by peakBlend") {
    // Spike of height H on 0: B_o^mean holds H / 4^o in one texel, B_o^max H.
    // S_o is the cubic B-spline of that texel at the receivers, scaled by
    // A_o = p + (1 - p) / 4^o, so the level peak grows strictly with p. Note the
    // B-spline approximates: even with p = 1 a one-texel peak reads at most
    // (2/3)^2 H at the levels.
    const int n = 128, sx = 61, sy = 67, kv = 4;
    const double H = 1000.0;
    const Grid g = gridOf(n, n, [&](int x, int y) { return x == sx && y == sy ? static_cast<float>(H) : 0.0f; });
    std::vector<std::vector<double>> peaks;  // [blend][level]
    for (int s : {1, 2})
        for (float blend : {0.0f, 0.25f, 0.5f, 0.75f, 1.0f}) {
            HeightPyramid p;
            buildHeightPyramid(g.cview(), 1.0f, s, pyramidSettings(kv, 0, blend), p);
            INFO("s " << s << " peakBlend " << blend);
            const int nOct = p.octaves;
            REQUIRE(nOct == 8);  // 128 .. 1
            for (int o = 1; o < nOct; ++o) {
                const Grid& mean = p.meanOctaves[static_cast<std::size_t>(o - 1)];
                double sum = 0.0;
                for (float v : mean.v) sum += v;
                CHECK(mean(sx >> o, sy >> o) == static_cast<float>(H / std::exp2(2 * o)));
                CHECK(sum == doctest::Approx(H / std::exp2(2 * o)).epsilon(1e-12));
                if (blend > 0.0f) {
                    const Grid& mx = p.maxOctaves[static_cast<std::size_t>(o - 1)];
                    CHECK(mx(sx >> o, sy >> o) == static_cast<float>(H));
                    CHECK(*std::max_element(mx.v.begin(), mx.v.end()) == static_cast<float>(H));
                }
            }
            auto synth = [&](int o, int x, int y) {
                if (o == 0) return x == sx && y == sy ? H : 0.0;
                const double scale = std::exp2(o), amp = blend + (1.0 - blend) / (scale * scale);
                const double ux = (x + 0.5) / scale - 0.5 - (sx >> o), uy = (y + 0.5) / scale - 0.5 - (sy >> o);
                return H * amp * cubicBspline(ux) * cubicBspline(uy);
            };
            std::vector<double> peak;
            for (int l = 0; l < static_cast<int>(p.levels.size()); ++l) {
                const LevelBlend lb = levelBlend(l, kv, nOct);
                const int top = lb.q > 0.0 ? lb.o + 1 : lb.o;
                // the spike's texel and its B-spline taps lie inside octave `top` (no edge clamping)
                if (top > 4) break;
                const double err = worstLevelError(p, l, 0, n, 0, n, [&](int x, int y) {
                    return (1.0 - lb.q) * synth(lb.o, x, y) + lb.q * synth(lb.o + 1, x, y);
                });
                CHECK_MESSAGE(err < 2e-4, "level " << l);  // H 2^-22: a few ulp of H
                const PaddedField& f = p.levels[static_cast<std::size_t>(l)];
                double m = 0.0;
                for (int Y = 0; Y < f.ny; ++Y)
                    for (int X = 0; X < f.nx; ++X) m = std::max(m, static_cast<double>(f.row(Y)[X]));
                peak.push_back(m);
                if (l > 0 && lb.q == 0.0) {
                    CHECK(m <= 4.0 / 9.0 * H * (blend + (1.0 - blend) / std::exp2(2 * lb.o)) * (1.0 + 1e-6));
                    if (blend == 1.0f) CHECK(m > 0.3 * H);  // no 4^-o decay of the max pyramid
                }
            }
            if (s == 1) peaks.push_back(peak);
        }
    // monotone in the blend at every filtered level
    for (std::size_t k = 1; k < peaks.size(); ++k)
        for (std::size_t l = static_cast<std::size_t>(kv); l < peaks[k].size(); ++l)
            CHECK(peaks[k][l] > peaks[k - 1][l]);
    CHECK(peaks.back()[4 * kv] > 100.0 * peaks.front()[4 * kv]);  // 4^4 lower without the max octaves
}

TEST_CASE("gi.pyramid: sizes of non-square, non-power-of-two and tiny fields at 1x/2x/4x; raw phases and level 0") {
    const std::pair<int, int> sizes[] = {{37, 23}, {64, 48}, {33, 65}, {5, 1}, {1, 7}, {2, 2}, {1, 1}};
    for (const auto& size : sizes)
        for (int s : {1, 2, 4}) {
            const int nx = size.first, ny = size.second;  // plain locals: INFO captures them
            const Grid g = gridOf(nx, ny, [](int x, int y) {
                return static_cast<float>(3 * x - 2 * y) + 0.25f * static_cast<float>(x * y % 7);
            });
            HeightPyramid p;
            buildHeightPyramid(g.cview(), 2.0f, s, pyramidSettings(4, 0, 0.5f), p);
            INFO(nx << "x" << ny << " s " << s);
            const int nxr = (nx - 1) / s + 1, nyr = (ny - 1) / s + 1;
            CHECK(p.nxr == nxr);
            CHECK(p.nyr == nyr);
            REQUIRE(!p.levels.empty());
            bool finite = true, level0 = true, padded = true;
            for (const PaddedField& f : p.levels) {
                CHECK(f.nx == nxr);
                CHECK(f.ny == nyr);
                CHECK(f.stride == nxr + 1);
                for (int Y = 0; Y <= nyr; ++Y) {
                    for (int X = 0; X <= nxr; ++X) finite = finite && std::isfinite(f.row(Y)[X]);
                    padded = padded && f.row(Y)[nxr] == f.row(std::min(Y, nyr - 1))[nxr - 1];
                }
            }
            // level 0 is the unfiltered height at the receiver (f_0 = f)
            for (int Y = 0; Y < nyr; ++Y)
                for (int X = 0; X < nxr; ++X) level0 = level0 && p.levels[0].row(Y)[X] == g(s * X, s * Y);
            CHECK(finite);
            CHECK(level0);
            CHECK(padded);
            // octave sizes halve, rounding up
            int w = nx, h = ny;
            for (const Grid& o : p.meanOctaves) {
                w = (w + 1) / 2;
                h = (h + 1) / 2;
                CHECK(o.nx == w);
                CHECK(o.ny == h);
            }
            // raw heights by column phase: plane q, column X holds column min(s X + q, nx - 1)
            CHECK(p.rawPhaseWidth == nx / s + 1);
            bool raw = true;
            for (int q = 0; q < s; ++q)
                for (int y = 0; y <= ny; ++y)
                    for (int X = 0; X < p.rawPhaseWidth; ++X)
                        raw = raw && p.rawPhaseRow(q, y)[X] == g(std::min(s * X + q, nx - 1), std::min(y, ny - 1));
            CHECK(raw);
        }
}

TEST_CASE("gi.pyramid: bit-identical for 1, 2 and 3 threads; a rebuild into a used pyramid equals a fresh one") {
    const Grid g = bumpy(300, 200);
    for (int s : {1, 2, 4}) {
        const PyramidSettings ps = pyramidSettings(4, 0, 0.5f);
        auto build = [&] {
            HeightPyramid p;
            buildHeightPyramid(g.cview(), 1.5f, s, ps, p);
            return p;
        };
        const HeightPyramid one = withThreads(1, build);
        for (int t : {2, 3}) {
            const HeightPyramid other = withThreads(t, build);
            INFO("s " << s << ", " << t << " threads");
            REQUIRE(other.levels.size() == one.levels.size());
            for (std::size_t l = 0; l < one.levels.size(); ++l) CHECK(sameBits(one.levels[l].v, other.levels[l].v));
            for (std::size_t o = 0; o < one.synth.size(); ++o) CHECK(sameBits(one.synth[o].v, other.synth[o].v));
            for (std::size_t o = 0; o < one.meanOctaves.size(); ++o) {
                CHECK(sameBits(one.meanOctaves[o].v, other.meanOctaves[o].v));
                CHECK(sameBits(one.maxOctaves[o].v, other.maxOctaves[o].v));
            }
            CHECK(sameBits(one.rawPhase, other.rawPhase));
        }
        // reuse: a different size and settings first, then this field
        HeightPyramid reused;
        const Grid small = bumpy(77, 51);
        buildHeightPyramid(small.cview(), 1.0f, 2, pyramidSettings(2, 1, 1.0f), reused);
        buildHeightPyramid(g.cview(), 1.5f, s, ps, reused);
        CHECK(sameLevels(reused, one));
        buildHeightPyramid(small.cview(), 1.0f, s, ps, reused);
        HeightPyramid fresh;
        buildHeightPyramid(small.cview(), 1.0f, s, ps, fresh);
        CHECK(sameLevels(reused, fresh));
    }
}

TEST_CASE("gi.pyramid: a rebuild over a box of changed cells gives the full build's bits") {
    // heights changed inside a box (a cell, corners, edges, the interior,
    // everything), rebuilt from the pyramid of the heights before, against a
    // fresh build: every octave image, synthesis, level and raw phase
    struct Case {
        int nx, ny;
    };
    for (const Case size : {Case{97, 61}, Case{64, 64}})
        for (int s : {1, 2, 3, 4})
            for (const float blend : {0.0f, 0.9f})
                for (const CellBox box : {CellBox{0, 0, 1, 1}, CellBox{40, 30, 45, 35}, CellBox{size.nx - 3, 0, size.nx, 5},
                                          CellBox{0, size.ny - 7, 9, size.ny},
                                          CellBox{size.nx - 1, size.ny - 1, size.nx, size.ny},
                                          CellBox{11, 0, 12, size.ny}, CellBox{0, 0, size.nx, size.ny}}) {
                    CAPTURE(size.nx);
                    CAPTURE(s);
                    CAPTURE(blend);
                    CAPTURE(box.x0);
                    CAPTURE(box.y0);
                    CAPTURE(box.x1);
                    CAPTURE(box.y1);
                    const PyramidSettings ps = pyramidSettings(4, 0, blend);
                    const Grid before = bumpy(size.nx, size.ny);
                    Grid after = before;
                    for (int y = box.y0; y < box.y1; ++y)
                        for (int x = box.x0; x < box.x1; ++x)
                            after(x, y) -= 5.0f + 0.3f * static_cast<float>((x * 3 + y) % 7);
                    HeightPyramid rebuilt, fresh;
                    buildHeightPyramid(before.cview(), 1.5f, s, ps, rebuilt);
                    const std::uint64_t previous = rebuilt.buildId;
                    buildHeightPyramid(after.cview(), 1.5f, s, ps, rebuilt, box);
                    buildHeightPyramid(after.cview(), 1.5f, s, ps, fresh);
                    // the build says what it redid: a copy of the raw heights follows with these rows
                    const bool whole = box.x0 == 0 && box.y0 == 0 && box.x1 == size.nx && box.y1 == size.ny;
                    CHECK(rebuilt.buildId != previous);
                    CHECK(rebuilt.basedOn == (whole ? 0u : previous));
                    CHECK(rebuilt.rawRowsRedone.y0 <= box.y0);
                    CHECK(rebuilt.rawRowsRedone.y1 >= box.y1);
                    CHECK(fresh.basedOn == 0u);
                    CHECK(sameLevels(rebuilt, fresh));
                    REQUIRE(rebuilt.synth.size() == fresh.synth.size());
                    for (std::size_t o = 0; o < fresh.synth.size(); ++o)
                        CHECK(sameBits(rebuilt.synth[o].v, fresh.synth[o].v));
                    REQUIRE(rebuilt.meanOctaves.size() == fresh.meanOctaves.size());
                    for (std::size_t o = 0; o < fresh.meanOctaves.size(); ++o) {
                        CHECK(sameBits(rebuilt.meanOctaves[o].v, fresh.meanOctaves[o].v));
                        if (blend > 0.0f) CHECK(sameBits(rebuilt.maxOctaves[o].v, fresh.maxOctaves[o].v));
                    }
                    CHECK(sameBits(rebuilt.rawPhase, fresh.rawPhase));
                    // a box that misses the change leaves the old pyramid's cells there
                    if (box.x0 > 0) {
                        HeightPyramid stale;
                        buildHeightPyramid(before.cview(), 1.5f, s, ps, stale);
                        buildHeightPyramid(after.cview(), 1.5f, s, ps, stale, CellBox{0, 0, 1, 1});
                        CHECK_FALSE(sameLevels(stale, fresh));
                    }
                }
}
