// The path policy and the resource limits of io/files/input_policy.h.
#include "io/files/input_policy.h"

#include <algorithm>
#include <charconv>

namespace specbake::io {
namespace fs = std::filesystem;

namespace {

struct NamedLimit {
    const char* name;
    uint64_t InputLimits::*field;
};
constexpr NamedLimit kLimits[] = {
    {"texels", &InputLimits::texels},
    {"json-depth", &InputLimits::json_depth},
    {"json-bytes", &InputLimits::json_bytes},
    {"nodes", &InputLimits::nodes},
    {"primitives", &InputLimits::primitives},
    {"accessor-elements", &InputLimits::accessor_elements},
    {"texture-bytes", &InputLimits::texture_bytes},
    {"vertices", &InputLimits::vertices},
    {"faces", &InputLimits::faces},
};

bool starts_with(const fs::path& path, const fs::path& prefix) {
    auto p = path.begin();
    for (auto q = prefix.begin(); q != prefix.end(); ++q, ++p) {
        if (q->empty()) continue;  // the empty element a trailing separator leaves
        if (p == path.end() || *p != *q) return false;
    }
    return true;
}

fs::path real_path(const fs::path& p) {
    std::error_code ec;
    fs::path r = fs::weakly_canonical(fs::absolute(p, ec), ec);
    return ec ? fs::absolute(p, ec).lexically_normal() : r;
}

// True when no part of `rel` that exists below `folder` is a symbolic link: then folder / rel cannot lead out
// of the folder, whatever the folder's own real path is, and comparing real paths is not needed. `rel` is
// lexically normal and does not start with "..". One lstat per existing part, where the real paths cost a
// stat and a readlink per part of the whole path, twice: Assimp probes many names derived from each
// reference (its FileSystemFilter), so this was most of a small import's time.
bool no_symlink_below(const fs::path& folder, const fs::path& rel) {
    fs::path p = folder;
    for (const fs::path& part : rel) {
        p /= part;
        std::error_code ec;
        const fs::file_status s = fs::symlink_status(p, ec);
        if (s.type() == fs::file_type::not_found) return true;  // nothing below it exists (ENOENT, ENOTDIR)
        if (ec || fs::is_symlink(s)) return false;
    }
    return true;
}

bool in_allowed_root(const fs::path& candidate, const InputPolicy& policy) {
    const fs::path real = real_path(candidate);
    return std::any_of(policy.allowed_roots.begin(), policy.allowed_roots.end(),
                       [&](const fs::path& root) { return starts_with(real, root); });
}

}  // namespace

Result<void> set_limit(InputLimits& limits, const std::string& assignment) {
    std::string names;
    for (const NamedLimit& l : kLimits) names += std::string(names.empty() ? "" : ", ") + l.name;
    const size_t eq = assignment.find('=');
    const std::string name = assignment.substr(0, eq);
    const NamedLimit* limit = nullptr;
    for (const NamedLimit& l : kLimits)
        if (name == l.name) limit = &l;
    if (!limit || eq == std::string::npos)
        return make_error("--limit '" + assignment + "': expected NAME=VALUE with NAME one of " + names);
    std::string text = assignment.substr(eq + 1);
    int shift = 0;
    if (!text.empty() && (text.back() == 'K' || text.back() == 'M' || text.back() == 'G')) {
        shift = text.back() == 'K' ? 10 : text.back() == 'M' ? 20 : 30;
        text.pop_back();
    }
    uint64_t value = 0;
    const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
    if (text.empty() || ec != std::errc() || end != text.data() + text.size() || value == 0 ||
        value > (UINT64_MAX >> shift))
        return make_error("--limit " + name + ": '" + assignment.substr(eq + 1) + "' is not a whole number > 0");
    limits.*(limit->field) = value << shift;
    return {};
}

Result<void> add_allowed_root(InputPolicy& policy, const fs::path& folder) {
    std::error_code ec;
    if (!fs::is_directory(folder, ec)) return make_error("--allow-root " + folder.string() + ": not a folder");
    policy.allowed_roots.push_back(real_path(folder));
    return {};
}

std::string over_limit(const char* name, uint64_t value, uint64_t limit) {
    return std::to_string(value) + " exceeds the limit of " + std::to_string(limit) + " (--limit " + name + "=N " +
           "raises it)";
}

namespace {

// The length of the well-formed UTF-8 sequence starting at text[i] (RFC 3629: shortest forms only, no
// surrogates, nothing above U+10FFFF), or 0 when the bytes there are not one.
size_t utf8_sequence_length(const std::string& text, size_t i) {
    const uint8_t c = uint8_t(text[i]);
    const size_t n = c < 0x80 ? 0 : (c >> 5) == 0x6 ? 1 : (c >> 4) == 0xE ? 2 : (c >> 3) == 0x1E ? 3 : 4;
    if (n == 4 || i + n >= text.size()) return 0;
    uint32_t cp = n == 0 ? c : n == 1 ? c & 0x1F : n == 2 ? c & 0x0F : c & 0x07;
    for (size_t k = 1; k <= n; ++k) {
        const uint8_t cc = uint8_t(text[i + k]);
        if ((cc >> 6) != 0x2) return 0;
        cp = cp << 6 | (cc & 0x3F);
    }
    static constexpr uint32_t kMin[4] = {0, 0x80, 0x800, 0x10000};
    if (cp < kMin[n] || cp > 0x10FFFF || (cp >= 0xD800 && cp <= 0xDFFF)) return 0;
    return n + 1;
}

}  // namespace

bool is_valid_utf8(const std::string& text) {
    for (size_t i = 0; i < text.size();) {
        const size_t n = utf8_sequence_length(text, i);
        if (n == 0) return false;
        i += n;
    }
    return true;
}

std::string to_valid_utf8(const std::string& text) {
    std::string out;
    out.reserve(text.size());
    for (size_t i = 0; i < text.size();) {
        const size_t n = utf8_sequence_length(text, i);
        if (n == 0) {
            out += "\xEF\xBF\xBD";  // U+FFFD REPLACEMENT CHARACTER, one per byte that starts no sequence
            ++i;
        } else {
            out.append(text, i, n);
            i += n;
        }
    }
    return out;
}

std::string escape_invalid_utf8(const std::string& text) {
    std::string out;
    for (size_t i = 0; i < text.size();) {
        const size_t n = utf8_sequence_length(text, i);
        if (n == 0) {
            static constexpr char kHex[] = "0123456789ABCDEF";
            const uint8_t c = uint8_t(text[i]);
            out += "\\x";
            out += kHex[c >> 4];
            out += kHex[c & 0xF];
            ++i;
        } else {
            out.append(text, i, n);
            i += n;
        }
    }
    return out;
}

Result<void> check_utf8_path(const fs::path& path) {
    if (is_valid_utf8(path.string())) return {};
    return make_error(path.string() + ": the path is not valid UTF-8 (manifest.json records paths as UTF-8 text)");
}

Result<fs::path> resolve_in_folder(const fs::path& folder, const std::string& decoded, const InputPolicy& policy) {
    if (decoded.find('\0') != std::string::npos) return make_error("contains a NUL byte");
    if (decoded.empty()) return make_error("is empty");
    if (!is_valid_utf8(decoded)) return make_error("is not valid UTF-8 once percent-decoded");
    const fs::path given(decoded);
    const std::string hint = " (--allow-root DIR permits reading below DIR)";
    if (given.is_absolute() || given.has_root_name() || given.has_root_directory() || decoded[0] == '\\') {
        if (in_allowed_root(given, policy)) return given.lexically_normal();
        return make_error("is an absolute path" + hint);
    }
    const fs::path rel = given.lexically_normal();
    const fs::path candidate = folder / rel;
    if (rel.empty() || *rel.begin() == ".." || rel == ".") {
        if (in_allowed_root(candidate, policy)) return candidate.lexically_normal();
        return make_error("resolves outside the scene's folder" + hint);
    }
    // Lexically inside; a symbolic link on the way may still lead out.
    if (!no_symlink_below(folder, rel) && !starts_with(real_path(candidate), real_path(folder)) &&
        !in_allowed_root(candidate, policy))
        return make_error("leads outside the scene's folder through a symbolic link" + hint);
    return candidate;
}

Result<void> check_output_not_input(const fs::path& output_dir, std::span<const fs::path> inputs) {
    // Compared as files (device and inode, through stat on the paths as given), not as canonical paths:
    // those cannot be computed under a working folder longer than PATH_MAX, and two failed computations
    // would compare equal. A folder that does not exist yet holds nothing.
    for (const fs::path& in : inputs) {
        std::error_code ec;
        if (fs::equivalent(in, output_dir, ec))
            return make_error(output_dir.string() + ": the output is an input file; inputs are never overwritten");
        const fs::path folder = in.has_parent_path() ? in.parent_path() : fs::path(".");
        if (fs::equivalent(folder, output_dir, ec))
            return make_error(output_dir.string() + ": the output folder holds the input " + in.string() +
                              "; choose another folder so inputs are never overwritten");
    }
    return {};
}

}  // namespace specbake::io
