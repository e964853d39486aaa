// The size limit for grids and images read from files.
#include "core/size_limits.h"

#include "core/error.h"

namespace terrain {

void checkDeclaredSize(const std::string& file, std::int64_t width, std::int64_t height, const char* what) {
    if (width < 1 || height < 1 || width > kMaxGridSide || height > kMaxGridSide)
        throw IoError(file, "declares " + std::to_string(width) + " x " + std::to_string(height) + " " + what +
                                "; the engine accepts 1 to " + std::to_string(kMaxGridSide) + " per side");
}

}  // namespace terrain
