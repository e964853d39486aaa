// Headless OpenGL through OSMesa (Mesa's off-screen interface; llvmpipe here).
// The renderer draws into its own framebuffer objects, so the OSMesa buffer
// itself is a tiny placeholder that only makes the context current.
#include <cstdlib>
#include <string>
#include <vector>

#include <GL/osmesa.h>

#include "render/context.h"

namespace terrain::render {
namespace {

class OsMesaContext final : public GlContext {
public:
    OsMesaContext() {
        // Mesa crashes instead of failing when asked for a driver OSMesa cannot load.
        if (const char* driver = std::getenv("GALLIUM_DRIVER")) {
            const std::string d(driver);
            if (!d.empty() && d != "llvmpipe" && d != "softpipe")
                throw ContextError("OSMesa: GALLIUM_DRIVER='" + d +
                                   "' is not a software driver OSMesa can use (llvmpipe, softpipe)");
        }
        // Newest first: 4.5 core (llvmpipe), then 3.3 core.
        const int versions[][2] = {{4, 5}, {3, 3}};
        for (const auto& v : versions) {
            const int attribs[] = {OSMESA_FORMAT,
                                   OSMESA_RGBA,
                                   OSMESA_DEPTH_BITS,
                                   24,
                                   OSMESA_STENCIL_BITS,
                                   0,
                                   OSMESA_PROFILE,
                                   OSMESA_CORE_PROFILE,
                                   OSMESA_CONTEXT_MAJOR_VERSION,
                                   v[0],
                                   OSMESA_CONTEXT_MINOR_VERSION,
                                   v[1],
                                   0};
            ctx_ = OSMesaCreateContextAttribs(attribs, nullptr);
            if (ctx_) break;
        }
        if (!ctx_)
            throw ContextError("OSMesa: cannot create an OpenGL 3.3+ core context (is Mesa's OSMesa/llvmpipe usable?)");
        buffer_.assign(kSide * kSide * 4, 0);
        makeCurrent();
    }
    ~OsMesaContext() override { OSMesaDestroyContext(ctx_); }
    OsMesaContext(const OsMesaContext&) = delete;
    OsMesaContext& operator=(const OsMesaContext&) = delete;

    void makeCurrent() override {
        if (!OSMesaMakeCurrent(ctx_, buffer_.data(), GL_UNSIGNED_BYTE, kSide, kSide))
            throw ContextError("OSMesa: cannot make the context current");
    }
    GlGetProcAddress procAddress() const override {
        return [](const char* name) -> GlProc { return reinterpret_cast<GlProc>(OSMesaGetProcAddress(name)); };
    }

private:
    static constexpr int kSide = 16;
    OSMesaContext ctx_ = nullptr;
    std::vector<unsigned char> buffer_;
};

}  // namespace

std::unique_ptr<GlContext> createHeadlessContext() { return std::make_unique<OsMesaContext>(); }

}  // namespace terrain::render
