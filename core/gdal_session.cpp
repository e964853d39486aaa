// GDAL set up once and kept quiet: errors are collected, never printed.
#include "core/gdal_session.h"

#include <mutex>

#include <cpl_conv.h>
#include <cpl_error.h>
#include <gdal.h>

#include "core/error.h"

namespace terrain::gdal {

void ensureRegistered() {
    static std::once_flag once;
    std::call_once(once, [] {
        // No .aux.xml side-car is read or written beside a user's file, and
        // opening a file lists no directory: the file alone decides.
        CPLSetConfigOption("GDAL_PAM_ENABLED", "NO");
        CPLSetConfigOption("GDAL_DISABLE_READDIR_ON_OPEN", "EMPTY_DIR");
        CPLSetConfigOption("CPL_DEBUG", "OFF");
        GDALAllRegister();
    });
}

namespace {
extern "C" void CPL_STDCALL forwardToCapture(CPLErr level, CPLErrorNum code, const char* text) {
    auto* self = static_cast<ErrorCapture*>(CPLGetErrorHandlerUserData());
    if (self) ErrorCapture::handleFromGdal(static_cast<int>(level), static_cast<int>(code), text, self);
}
}  // namespace

ErrorCapture::ErrorCapture() { CPLPushErrorHandlerEx(forwardToCapture, this); }

ErrorCapture::~ErrorCapture() { CPLPopErrorHandler(); }

void ErrorCapture::handleFromGdal(int level, int /*code*/, const char* text, void* self) {
    auto* capture = static_cast<ErrorCapture*>(self);
    if (level < CE_Failure || capture->failed_) return;
    capture->failed_ = true;
    capture->first_ = boundedLine(text ? text : "");
}

std::string ErrorCapture::message(const std::string& fallback) const { return first_.empty() ? fallback : first_; }

}  // namespace terrain::gdal
