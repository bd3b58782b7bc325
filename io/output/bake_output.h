// How a bake's files reach their output folder (docs/build-pipelines.md#output-folders-are-transactional):
// under the folder's lock, staged and committed as one transaction (io/output/output_folder.h), and only over a bake
// of the same inputs: a folder holds one bake, and a bake of other inputs is refused unless the caller
// replaces it.
#pragma once

#include "io/output/manifest.h"
#include "io/output/output_folder.h"

#include <filesystem>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace specbake::io {

// The identity recorded for `texture --demo`, in place of an input path.
inline constexpr const char* kDemoIdentity = "(demo)";

// The inputs that name the bake a manifest records: the scenes of a scene bake (its plan's "scene"
// entries), the normal map of a texture bake (its plan's "target"), or kDemoIdentity.
std::vector<std::string> bake_identity(const Manifest& manifest);
// The files of that bake in its folder: every output, and the inputs a demo bake generated there.
std::vector<std::string> bake_files(const Manifest& manifest);

class BakeOutput {
public:
    // Takes the folder's lock unless the caller holds it (`held`), reads the bake the folder holds, and
    // refuses, naming both, when that bake is of inputs `identity` does not include (unless `replace`),
    // or when its manifest.json is not a specbake manifest (same). Refuses a folder inside the output
    // folder of another bake (an ancestor holding a specbake manifest.json), whose check it would break.
    // Then opens the stage.
    static Result<BakeOutput> open(const std::filesystem::path& dir, const OutputLock* held,
                                   const std::vector<std::string>& identity, bool replace,
                                   const std::function<void(const std::string&)>& on_wait = {});

    const std::filesystem::path& stage() const { return tx_.stage(); }
    // The error with staged paths replaced by final ones.
    Error final_names(const Error& e) const { return make_error(tx_.final_names(e.message)); }
    // Commits the stage; the previous bake's files that were not written again are removed. Without
    // `replace`, a staged file whose place holds a file the folder's manifest does not list (a user's file,
    // or any file of a folder without a manifest) is refused, naming it, and nothing changes.
    Result<void> commit();

private:
    std::optional<OutputLock> own_lock_;  // destroyed after tx_: the stage goes first
    OutputTransaction tx_;
    std::vector<std::string> previous_files_;
    bool replace_ = false;
};

// Refuses a depfile path that is one of `inputs` (the same file, whatever the spelling) or lies inside the
// output folder `dir` (whose files a bake replaces and whose manifest it must stay able to read).
Result<void> check_depfile_path(const std::filesystem::path& depfile, const std::filesystem::path& dir,
                                std::span<const std::filesystem::path> inputs);

// For the commands: checks the depfile path against the output folder and the `inputs` the command was
// given (check_depfile_path), takes `dir`'s lock (calling `on_wait` with a line that names the process it
// waits for) and checks that `depfile` (when not empty) can be written, all before any work is done.
Result<OutputLock> lock_output_folder(const std::filesystem::path& dir, const std::string& depfile,
                                      std::span<const std::filesystem::path> inputs,
                                      const std::function<void(const std::string&)>& on_wait = {});

}  // namespace specbake::io
