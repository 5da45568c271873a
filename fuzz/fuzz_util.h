// fuzz — helpers shared by the fuzz targets.
#pragma once

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

namespace cmam::fuzz {

/// A file of this process's own (in TMPDIR or /tmp) that the fuzz input is written to, for the
/// entry points that read files; `suffix` is its extension. Removed when the process exits.
inline std::string scratch_path(const std::string& suffix) {
    struct Scratch {
        std::string path;
        ~Scratch() { std::remove(path.c_str()); }
    };
    const char* dir = std::getenv("TMPDIR");
    static thread_local std::vector<Scratch> made;
    made.push_back({std::string(dir && *dir ? dir : "/tmp") + "/cmam-fuzz-" +
                    std::to_string(getpid()) + suffix});
    return made.back().path;
}

/// Writes `size` bytes to `path`, replacing it; aborts if that fails (not a finding).
inline void write_file(const std::string& path, const uint8_t* data, std::size_t size) {
    std::FILE* f = std::fopen(path.c_str(), "wb");
    if (!f || (size && std::fwrite(data, 1, size, f) != size) || std::fclose(f) != 0) {
        std::perror(path.c_str());
        std::abort();
    }
}

}  // namespace cmam::fuzz
