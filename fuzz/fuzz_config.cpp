// libFuzzer target: the response-file and config-file parsers (cli/config.h). The first byte picks
// the parser: even = config text (TOML or JSON) sorted for a command, odd = a response file expanded
// (it may name itself or other files of the scratch folder, which is the working folder).
#include "fuzz/fuzz_common.h"
#include "cli/config.h"

#include <array>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    static const bool in_scratch = [] {
        std::filesystem::current_path(specbake::fuzz::scratch_dir());
        return true;
    }();
    (void)in_scratch;
    if (size == 0) return 0;
    const std::string text(reinterpret_cast<const char*>(data) + 1, size - 1);
    if (data[0] % 2 == 0) {
        auto tree = specbake::parse_config_text(text, "fuzz.toml");
        if (!tree) return 0;
        static const std::array<std::string, 4> globals{"quiet", "jobs", "verbose", "config"};
        static const std::array<std::string, 4> commands{"texture", "scene", "mesh", "bake"};
        for (const std::string& command : commands) {
            auto split = specbake::split_config(*tree, command, globals, commands, "fuzz.toml");
            if (split) (void)split->materials.to_json().dump();
        }
    } else {
        specbake::fuzz::write_scratch("args.rsp", reinterpret_cast<const uint8_t*>(text.data()), text.size());
        std::vector<std::string> files;
        (void)specbake::expand_response_files({"--first", "@args.rsp", "--last"}, &files);
    }
    return 0;
}
