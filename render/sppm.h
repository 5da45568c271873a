// render — pbrt-v3's "sppm" integrator: stochastic progressive photon mapping (Hachisuka and
// Jensen 2009), the integrator of pbrt-v3's caustic scenes, whose light reaches the diffuse
// surfaces the camera sees through specular ones from a point or spot light: paths from the
// camera cannot find it, photons from the light do (algorithms.md §25).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

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
/// density of the direction, times the light's chance of being chosen) (pbrt-v3's Sample_Le).
struct Emission {
    Vec3 org, dir;
    Rgb beta;
};

/// The photons of a scene's lights, all of them or its delta lights alone (point, spot,
/// goniometric, projection, distant): a light chosen by power (pbrt-v3's Power(), evenly where
/// none has any), its photon drawn as pbrt-v3 samples each light type's emission.
class LightEmitter {
  public:
    LightEmitter(const Scene& scene, bool delta_only);
    bool empty() const { return m_lights.empty(); }
    /// The photon of the Halton sequence's point `index`: its light from the radical inverse of
    /// `index` in base 2, its position and direction from bases 3, 5, 7 and 11. False where there
    /// is none (a light of no chance, a zero density or weight, a light at infinity around an
    /// empty scene).
    bool emit(uint64_t index, Emission& e) const;

  private:
    const Scene& m_scene;
    std::vector<std::size_t> m_lights;  // indices in Scene::lights
    std::vector<double> m_cdf;          // m_lights' powers summed, from 0
};

}  // namespace cmam::render
