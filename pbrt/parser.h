// pbrt — parser for the pbrt-v3 scene format (the subset documented in README.md).
// Text -> SceneDesc; knows nothing about rendering. Errors are SceneError with FILE:LINE:COL.
#pragma once

#include <string>

#include "pbrt/error.h"
#include "pbrt/scene_desc.h"

namespace cmam::pbrt {

/// Parses the scene file at `path` (following Include directives).
SceneDesc parse_file(const std::string& path, const WarningSink& warn = {});
/// Parses `text` as if it were the file `filename` (for tests and tools).
SceneDesc parse_string(const std::string& text, const std::string& filename = "<string>",
                       const WarningSink& warn = {});

/// Resolves `name`, as written in the file at `loc`, as pbrt-v3 does: relative to the main
/// scene file's directory `base_dir` (SceneDesc::base_dir), in Included files too; a path that
/// does not exist there but does beside the file at `loc` resolves there.
std::string resolve_path(const std::string& base_dir, const FileLoc& loc, const std::string& name);

}  // namespace cmam::pbrt
