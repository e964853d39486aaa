#pragma once
// The sky: what the renderer draws behind the terrain and what the water
// reflects. It keeps two textures in step with the frame's lights:
//  - the environment's order-4 SH baked to a small equirectangular map
//    (band-limited, hence already prefiltered: the water's reflection and
//    the haze's colour), re-baked only when the SH changes;
//  - an HDR environment image at full resolution, uploaded once per image.
// The background is the analytic sky gradient, the image, or the SH map,
// with a disc for every key light (the sun) at its cap radiance.
#include <vector>

#include "engine/frame_data.h"
#include "render/gl.h"

namespace terrain::render {

/// Key lights drawn as discs in the background (the first ones).
inline constexpr int kSkyDiscs = 4;

class Sky {
public:
    explicit Sky(const Gl& gl);
    ~Sky();
    Sky(const Sky&) = delete;
    Sky& operator=(const Sky&) = delete;

    /// Brings the textures up to date with these lights.
    void upload(const engine::SceneLights& lights);
    /// The baked SH environment (equirectangular, RGB32F, wraps in azimuth).
    GLuint shTexture() const { return shTex_; }
    /// Binds the textures to units shUnit and imageUnit and sets `program`'s
    /// background uniforms (kSkyFragment) for `lights`.
    void setBackground(GLuint program, const engine::SceneLights& lights, int shUnit, int imageUnit) const;

private:
    const Gl& gl_;
    GLuint shTex_ = 0, imageTex_ = 0;
    gi::ShRgb bakedSh_{};
    bool baked_ = false;
    const engine::EnvironmentImage* uploadedImage_ = nullptr;
    std::vector<float> pixels_;
};

}  // namespace terrain::render
