// fuzz — scene building on parsed input: whatever parses is built (Embree geometry, textures,
// meshes, materials, lights) or rejected with a SceneError, so inconsistent counts, indices and
// values that the parser lets through reach render::build_scene. Paths resolve against
// fuzz/data (CMAM_FUZZ_DATA_DIR), whose textures and meshes are small.
#include <cstddef>
#include <cstdint>
#include <string>

#include "pbrt/parser.h"
#include "render/build_scene.h"
#include "render/scene.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
    const std::string text(reinterpret_cast<const char*>(data), size);
    const auto quiet = [](const std::string&) {};
    cmam::pbrt::SceneDesc desc;
    try {
        desc = cmam::pbrt::parse_string(text, CMAM_FUZZ_DATA_DIR "/fuzz.pbrt", quiet);
    } catch (const cmam::pbrt::SceneError&) {
        return -1;  // not added to the corpus: only what parses reaches the builder
    }
    try {
        auto scene = cmam::render::build_scene(desc, cmam::render::BuildOptions{}, quiet);
    } catch (const cmam::pbrt::SceneError&) {
    }
    return 0;
}
