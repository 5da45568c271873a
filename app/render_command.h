// cmam render: a scene to an image, with the command line's overrides of the scene.
#pragma once

#include <string>

namespace cmam::app {

struct RenderArgs {
    std::string scene;
    std::string output;
    int spp = 0;
    int threads = 0;
    bool quiet = false;
    bool stats = false;
    std::string lod, filter, cmam_miss = "average", cmam_tags = "scanline",
                             cmam_ellipse = "conjugate", cmam_sat_miss = "average",
                             cmam_adjacency = "on";
    bool cmam_hull = false, cmam_2d = false;
    std::string aov;
    std::string resolution, crop;
    std::string max_memory;  // empty: the machine's memory (render::memory_limit())
};

int run_render(const RenderArgs& args);

}  // namespace cmam::app
