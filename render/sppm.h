// render — pbrt-v3's "sppm" integrator: stochastic progressive photon mapping (Hachisuka and
// Jensen 2009), the integrator of pbrt-v3's caustic scenes, whose light reaches the diffuse
// surfaces the camera sees through specular ones from a point or spot light: paths from the
// camera cannot find it, photons from the light do (algorithms.md §25).
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>

#include "render/integrator.h"

namespace cmam::render {

/// Renders `scene` (Scene::sppm.on) by its iterations: in each, every pixel of the cropped film
/// traces a camera path to its visible point, gathering the emitted and direct light on the way;
/// photons leave the lights (chosen by power) and each hit after their first adds the photon,
/// times the visible point's BSDF, to every visible point within that pixel's radius; each pixel
/// then shrinks its radius by the photons it received (alpha 2/3). A pixel is its direct light's
/// mean plus its photons' flux over the disc of its radius and the photons shot. No pixel
/// filter: each pixel is its own estimate, as in pbrt-v3. The image is the same for any thread
/// count. `options.progress` is called after each iteration.
Framebuffer render_sppm(const Scene& scene, const RenderOptions& options, RenderStats* stats);

/// What render_sppm keeps per pixel of the cropped film (its state, visible point and BSDF, and
/// the visible points' grid), for the memory a render needs.
std::size_t sppm_pixel_bytes();

// What SPPM's photons and the light tracer's paths (lighttrace.h) start from.

/// A photon as a light emits it: its ray and weight, Le |cos| / (density of the position times
/// density of the direction) (pbrt-v3's Sample_Le, before the light's choice).
struct Emission {
    Vec3 org, dir;
    Rgb beta;
};

/// A photon of `light` from four uniform numbers (pbrt-v3's sampling of each light type's
/// emission); false when there is none (a zero density or weight, or a light at infinity around
/// an empty scene).
bool emit(const Scene& scene, const Light& light, const float (&u)[4], Emission& e);

/// A light's power as pbrt-v3 gives it (the luminance of its Power()), by which photons choose
/// their light; a projection light's cone is the one that holds its screen.
float light_power(const Scene& scene, const Light& light);

/// The radical inverse of `a` in base B (digits reversed behind the point): the Halton
/// sequence's coordinate of base B. The base is a constant, so the divisions are products.
template <uint64_t B>
float radical_inverse(uint64_t a) {
    uint64_t reversed = 0;
    double scale = 1;
    while (a != 0) {
        const uint64_t next = a / B;
        reversed = reversed * B + (a - next * B);
        scale /= double(B);
        a = next;
    }
    return std::min(float(double(reversed) * scale), 0x1.fffffep-1f);
}

}  // namespace cmam::render
