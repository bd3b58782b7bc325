#include "io/output/depfile.h"

#include "io/files/atomic_write.h"

#include <algorithm>
#include <vector>

namespace specbake::io {

Result<std::string> escape_depfile_path(const std::string& path) {
    if (path.empty()) return make_error("depfile: empty path");
    std::string out;
    out.reserve(path.size() + 8);
    size_t backslashes = 0;  // run of backslashes just written, doubled when a space follows (gcc -MD rule)
    for (char c : path) {
        if (c == '\n' || c == '\r') return make_error("depfile: path '" + path + "' holds a line break");
        if (c == ' ' || c == '\t') {
            out.append(backslashes, '\\');
            out += '\\';
            out += c;
        } else if (c == '#') {
            out += "\\#";
        } else if (c == '$') {
            out += "$$";
        } else {
            out += c;
        }
        backslashes = c == '\\' ? backslashes + 1 : 0;
    }
    return out;
}

Result<std::string> format_depfile(std::span<const std::string> targets, std::span<const std::string> deps) {
    if (targets.empty()) return make_error("depfile: no target");
    std::string text;
    for (size_t i = 0; i < targets.size(); ++i) {
        auto escaped = escape_depfile_path(targets[i]);
        if (!escaped) return escaped.error();
        if (i) text += ' ';
        text += *escaped;
    }
    text += ':';
    std::vector<std::string> sorted(deps.begin(), deps.end());
    std::sort(sorted.begin(), sorted.end());
    sorted.erase(std::unique(sorted.begin(), sorted.end()), sorted.end());
    for (const std::string& dep : sorted) {
        auto escaped = escape_depfile_path(dep);
        if (!escaped) return escaped.error();
        text += " \\\n  ";
        text += *escaped;
    }
    text += '\n';
    return text;
}

Result<void> write_depfile(const std::filesystem::path& file, std::span<const std::string> targets,
                           std::span<const std::string> deps) {
    auto text = format_depfile(targets, deps);
    if (!text) return make_error(file.string() + ": " + text.error().message);
    return write_file_atomic(file, *text);
}

}  // namespace specbake::io
