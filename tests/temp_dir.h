// For tests: a folder of the test process's own in the system temporary folder, removed with
// everything in it when the object goes out of scope (also when an assertion ends the test).
#pragma once

#include <unistd.h>

#include <filesystem>
#include <string>

namespace cmam::test {

struct TempDir {
    std::filesystem::path path;
    explicit TempDir(const std::string& prefix)
        : path(std::filesystem::temp_directory_path() /
               (prefix + "_" + std::to_string(::getpid()))) {
        std::filesystem::remove_all(path);
        std::filesystem::create_directories(path);
    }
    ~TempDir() {
        std::error_code ec;
        std::filesystem::remove_all(path, ec);
    }
    TempDir(const TempDir&) = delete;
    TempDir& operator=(const TempDir&) = delete;
};

}  // namespace cmam::test
