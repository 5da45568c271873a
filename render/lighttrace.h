// render — the light paths of pbrt-v3's "bdpt" and "mlt" integrators: the caustics of point,
// spot, goniometric, projection and distant lights through mirrors and glass, which a camera
// path cannot reach (it would have to hit a light of no area), traced from the lights and joined
// to the camera (pbrt-v3's bidirectional strategy t = 1, algorithms.md §27). The path tracer
// renders everything else.
#pragma once

#include <cstddef>

#include "render/integrator.h"

namespace cmam::render {

/// Whether the light paths can join `camera`: a perspective camera (a pinhole or a thin lens,
/// pbrt-v3's only camera with an importance) whose frame is rigid.
bool light_tracing_camera(const Camera& camera);

/// Adds the light paths' part to `fb`, the path tracer's image of the cropped film
/// (Scene::light_tracing): as many paths as the film has camera samples, each from a delta light
/// chosen by power; a path whose first bounce is specular is joined to the camera at each later
/// hit with non-specular lobes, and what the camera sees there lands in the pixel it falls in
/// (no pixel filter, as pbrt-v3's splats). The image is the same for any thread count.
void add_light_paths(const Scene& scene, const RenderOptions& options, RenderStats* stats,
                     Framebuffer& fb);

/// What add_light_paths keeps per pixel of the cropped film (its sums), for the memory a render
/// needs.
std::size_t light_path_pixel_bytes();

}  // namespace cmam::render
