#include "app/progress.h"

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <system_error>

#include <unistd.h>

#include "core/error.h"
#include "core/file_io.h"

namespace terrain::app {
namespace {
double nowSeconds() {
    return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}
}  // namespace

Progress::Progress(std::string label, long long total, bool enabled)
    : label_(std::move(label)), total_(total), start_(nowSeconds()) {
    const char* env = std::getenv("TERRAIN_PROGRESS");
    enabled_ = enabled && total > 0 && (isatty(1) || (env && env[0] == '1'));
}

void Progress::update(long long done) {
    if (!enabled_) return;
    const int percent = static_cast<int>(100 * done / total_);
    if (percent == lastPercent_) return;
    lastPercent_ = percent;
    const double elapsed = nowSeconds() - start_;
    const double eta = done > 0 ? elapsed * static_cast<double>(total_ - done) / static_cast<double>(done) : 0.0;
    const int width = 30;
    const int filled = percent * width / 100;
    std::string bar(static_cast<std::size_t>(filled), '#');
    bar.append(static_cast<std::size_t>(width - filled), '.');
    std::printf("\r%s [%s] %3d%% %lld/%lld  %.1fs elapsed, %.1fs left ", label_.c_str(), bar.c_str(), percent, done,
                total_, elapsed, eta);
    std::fflush(stdout);
}

void Progress::clear() {
    if (enabled_ && lastPercent_ >= 0) {
        std::printf("\r%*s\r", 90, "");
        lastPercent_ = -1;
    }
}

void Progress::finish() {
    if (enabled_) std::printf("\n");
    enabled_ = false;
}

void ensureWritableDirectory(const std::string& dir) {
    std::error_code ec;
    std::filesystem::create_directories(dir, ec);
    if (ec) throw IoError(dir, "cannot create the output folder: " + ec.message());
    if (!std::filesystem::is_directory(dir)) throw IoError(dir, "is not a folder");
    const std::string probe = (std::filesystem::path(dir) / ".terrain-write-test").string();
    try {
        writeFileAtomic(probe, "ok");
    } catch (const IoError&) {
        throw IoError(dir, "the output folder is not writable");
    }
    std::filesystem::remove(probe, ec);
}

void checkWritableFile(const std::string& file) {
    std::error_code ec;
    if (std::filesystem::is_directory(file, ec)) throw IoError(file, "is a folder, not a file");
    std::filesystem::path dir = std::filesystem::path(file).parent_path();
    if (dir.empty()) dir = ".";
    if (!std::filesystem::is_directory(dir, ec)) throw IoError(file, "its folder does not exist");
    if (access(dir.c_str(), W_OK) != 0) throw IoError(file, "its folder is not writable");
}

}  // namespace terrain::app
