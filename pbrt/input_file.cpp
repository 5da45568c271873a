#include "pbrt/input_file.h"

#include <filesystem>

namespace cmam::pbrt {

std::string not_a_regular_file(const std::string& path) {
    std::error_code ec;
    const auto status = std::filesystem::status(path, ec);
    if (ec || !std::filesystem::exists(status) || std::filesystem::is_regular_file(status))
        return {};
    return std::filesystem::is_directory(status) ? "it is a directory" : "it is not a regular file";
}

}  // namespace cmam::pbrt
