#include "io/output/depfile.h"

#include "io/files/atomic_write.h"

#include <algorithm>
#include <vector>

namespace specbake::io {

namespace {

// Why `c` cannot be written in a depfile that both GNU Make (4.3) and Ninja (1.11) read back as the same
// name, or null when it can. Ninja ends a name at any character outside its plain set and keeps the
// backslash of every escape but "\ ", "\#", "\:" and "$$", so these have no spelling there; '=' and
// '[' change what Make reads (a variable assignment, a wildcard).
const char* inexpressible(char c) {
    switch (c) {
    case '\n':
    case '\r': return "a line break, which ends a depfile line";
    case '\t': return "a tab, which Ninja reads as the end of a name";
    case ';': return "';', which starts a recipe in Make and ends a name in Ninja";
    case '|': return "'|', which starts order-only prerequisites in Make and ends a name in Ninja";
    case '=': return "'=', which makes Make read the line as a variable assignment";
    case '[': return "'[', which Make expands as a wildcard";
    case '*':
    case '?': return "a wildcard character, which Make expands and Ninja reads as the end of a name";
    case '&':
    case '\'':
    case '"':
    case '<':
    case '>':
    case '^':
    case '`': return "a shell character that Ninja reads as the end of a name (it has no escape for it)";
    default: return nullptr;
    }
}

}  // namespace

Result<std::string> escape_depfile_path(const std::string& given) {
    if (given.empty()) return make_error("depfile: empty path");
    auto refuse = [&given](const std::string& why) -> Result<std::string> {
        std::string shown;  // on one line
        for (char c : given) shown += c == '\n' ? std::string("\\n") : c == '\r' ? std::string("\\r") : c == '\t' ? std::string("\\t") : std::string(1, c);
        return make_error("depfile: cannot write the path '" + shown + "': it holds " + why +
                          "; rename the file or leave out --depfile");
    };
    // A leading '~' is a home folder to Make; "./~" names the same file for both tools.
    const std::string path = given[0] == '~' ? "./" + given : given;
    if (path.back() == '\\') return refuse("a backslash at its end, which continues the depfile line");
    if (path.back() == ':') return refuse("':' at its end, which Ninja reads as the end of the targets");
    if (path.back() == ')' && path.find('(') != std::string::npos)
        return refuse("a name in parentheses at its end, which Make reads as an archive member");
    std::string out;
    out.reserve(path.size() + 8);
    size_t backslashes = 0;  // run of backslashes just written, doubled when a space follows (gcc -MD rule)
    for (char c : path) {
        if (const char* why = inexpressible(c)) return refuse(why);
        if (c == ' ') {
            out.append(backslashes, '\\');
            out += "\\ ";
        } else if (c == '#' || c == ':') {
            if (backslashes > 0) return refuse(std::string("a backslash before '") + c + "', which Make and Ninja read differently");
            out += '\\';
            out += c;
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
