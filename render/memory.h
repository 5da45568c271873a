// render — what a render will allocate, and how much memory the process may use, so that a
// scene too big for the machine is refused with its sizes before rendering, not ended by the
// allocator part way.
#pragma once

#include <cstddef>
#include <map>
#include <optional>
#include <string>
#include <string_view>

#include "render/scene.h"

namespace cmam::render {

/// Memory a render of `scene` allocates beyond what building it took.
struct MemoryNeed {
    std::size_t film = 0;      // the framebuffer
    std::size_t textures = 0;  // MIP pyramids and tables the filters build on first use
    std::size_t total() const { return film + textures; }
};

/// An upper bound: tables not built yet are counted for every level, summed-area tables in
/// double precision.
MemoryNeed render_memory_need(const Scene& scene);

/// Which tables the filters reading one image texture build.
struct TextureUses {
    bool pyramid = false, sat = false, row_prefix = false;
};
/// Every image texture the scene's texture nodes read, with the tables their filters build.
std::map<const texture::FilteredTexture*, TextureUses> texture_uses(const Scene& scene);

/// The memory the process may use: the smallest of the machine's physical memory, the cgroup's
/// memory.max and RLIMIT_AS.
std::size_t memory_limit();
/// What the process has resident now.
std::size_t resident_memory();

/// Refuses (RenderError, with the sizes) a render that would take the process over
/// `limit` bytes (nullopt: memory_limit()).
void check_render_memory(const Scene& scene, std::optional<std::size_t> limit);

/// "512 MiB", "3.2 GiB".
std::string format_bytes(std::size_t bytes);
/// Parses "8G", "512M", "2048K" (powers of 1024) or a number of bytes (also "8GB", "8 GiB");
/// nullopt if not.
std::optional<std::size_t> parse_bytes(std::string_view text);

}  // namespace cmam::render
