#include "render/memory.h"

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <stdexcept>

#include "render/error.h"
#include "render/lighttrace.h"
#include "render/sppm.h"

namespace cmam::render {

namespace {

constexpr std::size_t kUnlimited = ~std::size_t(0);

std::size_t physical_memory() {
    const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGE_SIZE);
    if (pages <= 0 || page <= 0) return kUnlimited;
    return static_cast<std::size_t>(pages) * static_cast<std::size_t>(page);
}

// cgroup v2's limit of the process's group ("max": none).
std::size_t cgroup_limit() {
    std::ifstream in("/sys/fs/cgroup/memory.max");
    std::string s;
    if (!(in >> s) || s == "max") return kUnlimited;
    try {
        return static_cast<std::size_t>(std::stoull(s));
    } catch (const std::exception&) {
        return kUnlimited;
    }
}

// /proc/self/statm field `k` (0: virtual size, 1: resident), in bytes.
std::size_t statm(int k) {
    std::ifstream in("/proc/self/statm");
    std::size_t v[2] = {0, 0};
    in >> v[0] >> v[1];
    return v[k] * static_cast<std::size_t>(sysconf(_SC_PAGE_SIZE));
}

}  // namespace

std::map<const texture::FilteredTexture*, TextureUses> texture_uses(const Scene& scene) {
    std::map<const texture::FilteredTexture*, TextureUses> uses;
    for (const TextureNode& n : scene.textures) {
        if (n.kind != TextureNode::Kind::Image || !n.image) continue;
        TextureUses& u = uses[n.image];
        switch (n.filter.kind) {
            case texture::FilterKind::Nearest:
            case texture::FilterKind::Bilinear:
                break;
            case texture::FilterKind::Sat:
                u.pyramid = u.sat = true;
                break;
            case texture::FilterKind::Area:
                u.pyramid = u.row_prefix = true;
                break;
            default:
                u.pyramid = true;
        }
    }
    return uses;
}

MemoryNeed render_memory_need(const Scene& scene) {
    MemoryNeed need;
    // The framebuffer, plus per-row buffers of each worker (small beside it).
    need.film =
        static_cast<std::size_t>(scene.film.width()) * scene.film.height() * 3 * sizeof(float);
    if (scene.sppm.on)  // each pixel's state across the iterations
        need.film +=
            static_cast<std::size_t>(scene.film.width()) * scene.film.height() * sppm_pixel_bytes();
    else if (scene.light_tracing)  // the light paths' sums, a double per channel
        need.film += static_cast<std::size_t>(scene.film.width()) * scene.film.height() *
                     light_path_pixel_bytes();
    for (const auto& [tex, u] : texture_uses(scene)) {
        const texture::Image& im = tex->image();
        const double texels = double(im.width()) * im.height(), c = im.channels();
        // Levels above 0 add a third of level 0 (1/4 + 1/16 + ...), and so do their tables.
        if (u.pyramid && !tex->pyramid_built()) need.textures += std::size_t(texels * c * 4 / 3);
        if (u.sat)
            need.textures +=
                std::size_t(double(im.width() + 1) * (im.height() + 1) * c * 8 * 4 / 3);
        if (u.row_prefix && tex->row_prefix_bytes() == 0)
            need.textures += std::size_t(double(im.width() + 1) * im.height() * c * 4 * 4 / 3);
    }
    return need;
}

std::size_t memory_limit() {
    std::size_t limit = std::min(physical_memory(), cgroup_limit());
    rlimit r{};
    if (getrlimit(RLIMIT_AS, &r) == 0 && r.rlim_cur != RLIM_INFINITY)
        limit = std::min<std::size_t>(limit, r.rlim_cur);
    return limit;
}

std::size_t resident_memory() {
    return statm(1);
}

void check_render_memory(const Scene& scene, std::optional<std::size_t> limit) {
    const MemoryNeed need = render_memory_need(scene);
    const std::size_t max = limit ? *limit : memory_limit();
    // Address-space limits count what is mapped, not what is resident.
    rlimit r{};
    const bool virtual_limit =
        !limit && getrlimit(RLIMIT_AS, &r) == 0 && r.rlim_cur != RLIM_INFINITY && r.rlim_cur == max;
    const std::size_t have = virtual_limit ? statm(0) : resident_memory();
    if (need.total() <= max && have <= max - need.total()) return;
    const char* hint = need.film >= need.textures
                           ? "a smaller --resolution or --crop needs less"
                           : "the trilinear or EWA filter builds fewer tables than sat and area";
    throw RenderError("the render needs about " + format_bytes(need.total()) + " more (film " +
                      format_bytes(need.film) + ", texture pyramids and tables " +
                      format_bytes(need.textures) + ") on top of the " + format_bytes(have) +
                      " the scene takes, over the limit of " + format_bytes(max) +
                      (limit ? " set by --max-memory"
                             : " (what this process may use; --max-memory sets another)") +
                      "; " + hint);
}

std::string format_bytes(std::size_t bytes) {
    char buf[32];
    const double b = static_cast<double>(bytes), gib = 1024.0 * 1024 * 1024;
    if (b >= gib)
        std::snprintf(buf, sizeof buf, "%.1f GiB", b / gib);
    else
        std::snprintf(buf, sizeof buf, "%.0f MiB", std::ceil(b / (1024.0 * 1024)));
    return buf;
}

std::optional<std::size_t> parse_bytes(std::string_view text) {
    std::string s;
    for (char c : text)
        if (!std::isspace(static_cast<unsigned char>(c)))
            s += static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
    if (s.ends_with("IB"))  // "8GiB"
        s.resize(s.size() - 2);
    else if (s.ends_with("B"))  // "8GB", "100B"
        s.pop_back();
    double scale = 1;
    if (!s.empty() && std::isalpha(static_cast<unsigned char>(s.back()))) {
        const char u = s.back();
        scale = u == 'K'   ? 1024.0
                : u == 'M' ? 1024.0 * 1024
                : u == 'G' ? 1024.0 * 1024 * 1024
                : u == 'T' ? 1024.0 * 1024 * 1024 * 1024
                           : 0;
        if (scale == 0) return std::nullopt;
        s.pop_back();
    }
    if (s.empty()) return std::nullopt;
    std::size_t used = 0;
    double v;
    try {
        v = std::stod(s, &used);
    } catch (const std::exception&) {
        return std::nullopt;
    }
    if (used != s.size() || !(v > 0) || !std::isfinite(v * scale) || v * scale >= 1.8e19)
        return std::nullopt;
    return static_cast<std::size_t>(v * scale);
}

}  // namespace cmam::render
