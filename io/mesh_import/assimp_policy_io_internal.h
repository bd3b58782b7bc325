// The file access Assimp gets while importing a mesh file: every file it opens (the asset, an OBJ's .mtl,
// a glTF's buffers ...) goes through the path policy of io/files/input_policy.h and is recorded.
#pragma once

#include "core/result.h"
#include "io/files/input_policy.h"

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace Assimp {
class IOSystem;
}

namespace specbake::io {

// What one import read, and what the policy refused.
struct AssimpReads {
    std::vector<std::filesystem::path> files;  // the files opened besides the asset, resolved, first-opened order
    std::string refused;  // "referenced file 'REF' refused: WHY", the first refusal; empty when none
};

// Called before a file is opened for reading (`asset`: the file being imported, opened while no stream of
// it is open; else a file it references, which may be the asset itself opened again while it is being
// read); an error refuses the file like the path policy does.
using AssimpOpenCheck = std::function<Result<void>(const std::filesystem::path& file, bool asset)>;

// A new IOSystem for Assimp::Importer::SetIOHandler (the importer owns and deletes it). Reads only: a name
// Assimp asks for is resolved once, relative to the asset's folder (resolve_in_folder), and the resolved
// path is what is opened; a refused name is reported as missing to Assimp and recorded in `reads`, and so
// is a file `check` refuses (the asset's refusal is recorded as its message alone).
Assimp::IOSystem* new_policy_io_system(const std::filesystem::path& asset, const InputPolicy& policy,
                                       AssimpReads& reads, AssimpOpenCheck check = {});

}  // namespace specbake::io
