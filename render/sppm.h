// render — pbrt-v3's "sppm" integrator: stochastic progressive photon mapping (Hachisuka and
// Jensen 2009), the integrator of pbrt-v3's caustic scenes, whose light reaches the diffuse
// surfaces the camera sees through specular ones from a point or spot light: paths from the
// camera cannot find it, photons from the light do (algorithms.md §25).
#pragma once

#include <cstddef>

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

}  // namespace cmam::render
