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

}  // namespace cmam::test
