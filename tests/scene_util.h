// Test helpers: build a scene from pbrt text.
#pragma once

#include <memory>
#include <string>

#include "pbrt/parser.h"
#include "render/build_scene.h"
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
