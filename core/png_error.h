#pragma once
// libpng's error handling for our readers and writers. libpng reports an
// error by calling onPngError, which stores the text in a fixed buffer (no
// allocation, nothing that can throw inside libpng) and longjmps back to the
// setjmp of the function that called libpng. That function must hold no
// object with a destructor: the jump would skip it. So every libpng call
// with a setjmp armed sits in a small function of plain C types, and
// everything owning memory lives in its caller.
#include <cstdio>

#include <png.h>

namespace terrain::png_detail {

/// The text of libpng's last error, bounded.
struct PngErrorText {
    char text[160] = "unknown libpng error";
};

[[noreturn]] inline void onPngError(png_structp png, png_const_charp message) {
    if (auto* error = static_cast<PngErrorText*>(png_get_error_ptr(png)))
        std::snprintf(error->text, sizeof error->text, "%s", message ? message : "unknown libpng error");
    png_longjmp(png, 1);
}

inline void onPngWarning(png_structp, png_const_charp) {}

}  // namespace terrain::png_detail
