// render — which footprint producer a texture's lookups use, and how CMAM rays are tagged.
// One name table each: the CLI, scene-parameter errors and --help all read them.
#pragma once

#include <cmam/texture/names.h>

#include <cstdint>
#include <optional>
#include <string_view>

namespace cmam::render {

/// Where a texture lookup's footprint comes from (its "level of detail" source): none (point
/// sampling), ray differentials, isotropic or anisotropic ray cones, or the CMAM.
enum class FootprintMethod : uint8_t { None, Differentials, Cones, ConesAniso, Cmam };
inline constexpr texture::NameTable kFootprintMethodNames{
    texture::Named<FootprintMethod>{FootprintMethod::None, "none"},
    texture::Named{FootprintMethod::Differentials, "differentials"},
    texture::Named{FootprintMethod::Cones, "cones"},
    texture::Named{FootprintMethod::ConesAniso, "cones-aniso"},
    texture::Named{FootprintMethod::Cmam, "cmam"}};

inline std::optional<FootprintMethod> parse_footprint_method(std::string_view name) {
    return kFootprintMethodNames.parse(name);
}
inline std::string_view to_string(FootprintMethod m) {
    return kFootprintMethodNames.name(m);
}

/// The set of footprint methods a scene's textures use (recorded while the scene is built).
class FootprintMethods {
  public:
    void add(FootprintMethod m) { m_bits |= uint8_t(1u << static_cast<unsigned>(m)); }
    bool has(FootprintMethod m) const { return m_bits & (1u << static_cast<unsigned>(m)); }

  private:
    uint8_t m_bits = 0;
};

/// Which rays share a CMAM tag ID (algorithms.md §6.2 item 2).
enum class TagPolicy : uint8_t { Scanline, Pixel };
inline constexpr texture::NameTable kTagPolicyNames{
    texture::Named<TagPolicy>{TagPolicy::Scanline, "scanline"},
    texture::Named{TagPolicy::Pixel, "pixel"}};

inline std::optional<TagPolicy> parse_tag_policy(std::string_view name) {
    return kTagPolicyNames.parse(name);
}
inline std::string_view to_string(TagPolicy p) {
    return kTagPolicyNames.name(p);
}

}  // namespace cmam::render
