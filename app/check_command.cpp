// cmam check: parse and build a scene, report its problems, render nothing.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "app/command.h"
#include "app/common.h"
#include "pbrt/parser.h"
#include "render/build_scene.h"
#include "render/scene.h"

namespace cmam::app {

namespace {

struct CheckArgs {
    std::string scene;
};

int run_check(const CheckArgs& a) {
    pbrt::SceneDesc desc = pbrt::parse_file(a.scene, print_warning);
    auto scene = render::build_scene(desc, {}, print_warning);
    // Triangles, quadrics and curve segments as rendered: an object's count once per instance.
    render::PrimitiveCounts counts;
    render::count_primitives(scene->primitives, counts);
    for (const auto& in : scene->instances)
        render::count_primitives(scene->objects[in.object].primitives, counts);
    const std::size_t tris = counts.triangles, quadrics = counts.quadrics,
                      curves = counts.curve_segments;
    // (Curves, as media, only where there are some.)
    const std::string curve_text =
        curves == 0
            ? ""
            : ", " + std::to_string(curves) + (curves == 1 ? " curve segment" : " curve segments");
    // Instances built in place (their shapes counted among the triangles above) included.
    std::string instances;
    const std::size_t placed = scene->instances.size() + scene->instances_in_place,
                      objects = scene->objects.size() + scene->objects_in_place;
    if (placed > 0) {
        instances = " (" + std::to_string(placed) + " instances of " + std::to_string(objects) +
                    (objects == 1 ? " object" : " objects");
        if (scene->instances_in_place == placed)
            instances += ", built in place";
        else if (scene->instances_in_place > 0)
            instances += ", " + std::to_string(scene->instances_in_place) + " built in place";
        instances += ")";
    }
    // (Media only where there are some, so that other scenes' line stays as it was.)
    std::string media;
    if (!scene->media.empty())
        media = ", " + std::to_string(scene->media.size()) +
                (scene->media.size() == 1 ? " medium" : " media");
    std::printf(
        "%s: ok: %dx%d film, %d spp, %zu triangles, %zu quadrics%s%s, %zu lights, %zu materials, "
        "%zu textures%s\n",
        a.scene.c_str(), scene->film.width(), scene->film.height(),
        scene->sppm.on ? scene->sppm.iterations : scene->sampler.spp(), tris, quadrics,
        curve_text.c_str(), instances.c_str(), scene->lights.size(), scene->materials.size(),
        scene->textures.size(), media.c_str());
    return 0;
}

void add_check_options(CLI::App& cmd, CheckArgs& a) {
    cmd.add_option("scene", a.scene, "Scene file (.pbrt)")->required();
}

}  // namespace

Command add_check_command(CLI::App& app) {
    return make_command(app, "check", "Parse and build a scene, report problems, render nothing",
                        add_check_options, run_check);
}

}  // namespace cmam::app
