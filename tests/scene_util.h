// Test helpers: build a scene from pbrt text.
#pragma once

#include <memory>
#include <string>

#include "pbrt/parser.h"
#include "render/build_scene.h"
#include "render/integrator.h"
#include "render/scene.h"

namespace cmam::test {

inline std::unique_ptr<render::Scene> scene_from(const std::string& text,
                                                 const std::string& filename = "t.pbrt",
                                                 int spp = 0) {
    pbrt::SceneDesc d = pbrt::parse_string(text, filename);
    render::BuildOptions o;
    o.spp_override = spp;
    return render::build_scene(d, o, {});
}

/// As scene_from, with every ObjectInstance an instance of its object (none built in place:
/// BuildOptions::flatten_instances), for tests of instancing itself.
inline std::unique_ptr<render::Scene> instanced_scene_from(const std::string& text) {
    render::BuildOptions o;
    o.flatten_instances = 0;
    return render::build_scene(pbrt::parse_string(text, "t.pbrt"), o, {});
}

/// The image of a scene from pbrt text, rendered on `threads` threads (0: all).
inline render::Framebuffer render_text(const std::string& text, int threads = 0,
                                       render::RenderStats* stats = nullptr) {
    auto scene = scene_from(text);
    render::RenderOptions o;
    o.threads = threads;
    return render::render(*scene, o, stats);
}

/// The mean of fb's values over pixels [c0, c1) x [r0, r1) (c1, r1 < 0: to the image's edge).
inline double mean_of(const render::Framebuffer& fb, int c0 = 0, int c1 = -1, int r0 = 0,
                      int r1 = -1) {
    if (c1 < 0) c1 = fb.width;
    if (r1 < 0) r1 = fb.height;
    double sum = 0;
    for (int y = r0; y < r1; ++y)
        for (int x = c0; x < c1; ++x)
            for (int c = 0; c < 3; ++c)
                sum += fb.rgb[(static_cast<std::size_t>(y) * fb.width + x) * 3 + c];
    return sum / (3.0 * (c1 - c0) * (r1 - r0));
}

/// A diffuse floor (albedo 1/2) at y = 0 and a mirror facing down at height 1.5, lit by
/// `light`: WorldBegin to WorldEnd. A light at height 1 reaches the floor directly and from its
/// mirror image at height 2, which only paths from the light find (SPPM's photons, bdpt's light
/// paths).
inline std::string mirror_world(const std::string& light) {
    return "WorldBegin\n" + light + R"(
Material "matte" "rgb Kd" [0.5 0.5 0.5]
Shape "trianglemesh" "integer indices" [0 1 2 0 2 3] "point P" [-10 0 -10 10 0 -10 10 0 10 -10 0 10]
Material "mirror" "rgb Kr" [1 1 1]
Shape "trianglemesh" "integer indices" [0 1 2 0 2 3]
  "point P" [-10 1.5 -10 10 1.5 -10 10 1.5 10 -10 1.5 10]
WorldEnd
)";
}

#ifdef CMAM_SCENES_DIR
/// A plane filling the view of a camera 5 units away on a width x height film, its bricks
/// texture's footprint from the CMAM and filtered by `area`, under a distant light; `before_world`
/// (an integrator, say) goes before WorldBegin.
inline std::string cmam_plane(int width, int height, const std::string& before_world = "") {
    return "LookAt 0 0 5  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" 30\n"
           "Film \"image\" \"integer xresolution\" " +
           std::to_string(width) + " \"integer yresolution\" " + std::to_string(height) + "\n" +
           before_world +
           "WorldBegin\nLightSource \"distant\" \"point from\" [0 0 5] \"point to\" [0 0 0]\n"
           "Texture \"t\" \"spectrum\" \"imagemap\" \"string filename\" \"" +
           std::string(CMAM_SCENES_DIR) +
           "/textures/bricks.png\" \"string lod\" \"cmam\" \"string filter\" \"area\"\n"
           "Material \"matte\" \"texture Kd\" \"t\"\n"
           "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3]\n"
           "  \"point P\" [-50 -10 0 50 -10 0 50 10 0 -50 10 0] \"float uv\" [0 0 20 0 20 4 0 4]\n"
           "WorldEnd\n";
}
#endif

}  // namespace cmam::test
