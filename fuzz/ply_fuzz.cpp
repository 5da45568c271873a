// fuzz — the PLY reader on arbitrary bytes: it returns a mesh or throws SceneError. A mesh it
// returns is then built as a "plymesh" shape, so what the reader lets through (element counts,
// partial normals or uvs, indices) reaches render::build_scene, which must reject it with a
// SceneError or build it.
#include <cstddef>
#include <cstdint>
#include <string>

#include "fuzz/fuzz_util.h"
#include "pbrt/parser.h"
#include "pbrt/ply.h"
#include "render/build_scene.h"
#include "render/scene.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
    static const std::string path = cmam::fuzz::scratch_path(".ply");
    static const cmam::pbrt::SceneDesc desc = cmam::pbrt::parse_string(
        "Film \"image\" \"integer xresolution\" 8 \"integer yresolution\" 8\n"
        "Camera \"perspective\"\nWorldBegin\nShape \"plymesh\" \"string filename\" \"" +
        path + "\"\nWorldEnd\n");
    cmam::fuzz::write_file(path, data, size);
    try {
        cmam::pbrt::read_ply(path);
    } catch (const cmam::pbrt::SceneError&) {
        return 0;
    }
    try {
        auto scene = cmam::render::build_scene(desc, cmam::render::BuildOptions{},
                                               [](const std::string&) {});
    } catch (const cmam::pbrt::SceneError&) {
    }
    return 0;
}
