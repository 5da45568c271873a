// render — building a renderable Scene from a parsed pbrt-v3 scene (the code is in build/).
// The one header of the tracer that sees the scene format.
#pragma once

#include <memory>
#include <optional>

#include "pbrt/error.h"
#include "pbrt/scene_desc.h"
#include "render/scene.h"

namespace cmam::render {

struct BuildOptions {
    int spp_override = 0;  // 0: the scene's sampler
    /// Replace every image texture by its mean and every checkerboard by the mean of its two
    /// inputs: the "untextured" render that separates geometric edges from texture detail.
    bool untextured = false;
    // Overrides for every image texture (the scene file's choices otherwise).
    std::optional<FootprintMethod> lod;
    std::optional<texture::FilterKind> filter;
    TagPolicy tags = TagPolicy::Scanline;
    texture::CmamOptions cmam;
    /// The memory the process may use (nullopt: memory_limit() of memory.h): a mesh file whose
    /// header announces more than what is left of it is refused before it is read.
    std::optional<std::size_t> max_memory;
    /// Threads that read the scene's image and mesh files (0: all cores).
    int threads = 0;
    /// Object instances that are cheap to copy are built in place, each instance's shapes
    /// placed by the instance's transform composed with theirs, instead of as instances of one
    /// shared object (a ray then crosses one level of Embree's hierarchy, not two): an object
    /// used once, and an object whose uses together come to at most this many triangles (curve
    /// segments and quadrics count one each) while the scene's copies stay within it. Objects
    /// with curves stay instances. 0: every ObjectInstance is an instance.
    std::size_t flatten_instances = std::size_t(1) << 16;
};

/// Builds a renderable scene; throws pbrt::SceneError with locations on any problem.
std::unique_ptr<Scene> build_scene(const pbrt::SceneDesc& desc, const BuildOptions& options,
                                   const pbrt::WarningSink& warn);

}  // namespace cmam::render
