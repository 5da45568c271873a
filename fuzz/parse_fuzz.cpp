// fuzz — the tokenizer and the parser on arbitrary text: every input parses or throws a located
// SceneError. Include paths resolve against fuzz/data (CMAM_FUZZ_DATA_DIR).
#include <cstddef>
#include <cstdint>
#include <string>

#include "pbrt/parser.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
    const std::string text(reinterpret_cast<const char*>(data), size);
    try {
        cmam::pbrt::parse_string(text, CMAM_FUZZ_DATA_DIR "/fuzz.pbrt", [](const std::string&) {});
    } catch (const cmam::pbrt::SceneError&) {
    }
    return 0;
}
