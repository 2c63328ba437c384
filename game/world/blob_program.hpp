#pragma once
// The blob monster's behaviour program (scene data: a JSON file the `blob` section names, format in
// docs/blob.md): its states, each one's behaviour and parameters, and the triggers between them.
// Read and validated here; run by fluid/blob (fluid::stepBlobMachine).

#include "fluid/blob/behaviour.hpp"
#include "fluid/blob/blob.hpp"

#include <filesystem>
#include <string>
#include <vector>

namespace game {

// Reads and validates the program at `path` for a body with `params`; `walls` are the names of the
// level's colliders, in order (coat_wall's `wall` key resolves to its index). On failure returns
// false with `error` naming the file, the key path and the value ("blob.program: file: states[2]..").
bool loadBlobProgram(const std::filesystem::path& path, const fluid::BlobParams& params,
                     const std::vector<std::string>& walls, fluid::BlobProgram& out, std::string& error);

}  // namespace game
