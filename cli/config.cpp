#include "cli/config.h"

#include "io/files/file_read.h"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <cctype>
#include <set>
#include <sstream>

namespace specbake {
namespace {

constexpr int kMaxResponseDepth = 16;
// Nesting alone does not bound the work: a file naming the next one ten times, sixteen levels deep, is
// 10^16 reads. The files read and the arguments they give are bounded as a whole (cli/config.h).
constexpr size_t kMaxResponseReads = 4096;
constexpr size_t kMaxResponseArguments = size_t(1) << 20;
constexpr size_t kMaxResponseBytes = size_t(64) << 20;

struct ExpansionBudget {
    size_t reads = 0;
    size_t bytes = 0;
};

Result<void> split_response_text(const std::string& text, const std::string& file, std::vector<std::string>& out) {
    size_t i = 0;
    const size_t n = text.size();
    while (i < n) {
        while (i < n && std::isspace(static_cast<unsigned char>(text[i]))) ++i;
        if (i >= n) break;
        if (text[i] == '#') {
            while (i < n && text[i] != '\n') ++i;
            continue;
        }
        std::string word;
        while (i < n && !std::isspace(static_cast<unsigned char>(text[i]))) {
            const char c = text[i];
            if (c == '"' || c == '\'') {
                const size_t close = text.find(c, i + 1);
                if (close == std::string::npos) return make_error(file + ": unterminated quote in response file");
                word.append(text, i + 1, close - i - 1);
                i = close + 1;
            } else {
                word += c;
                ++i;
            }
        }
        out.push_back(std::move(word));
    }
    return {};
}

// Offset of the first byte that does not belong to well-formed UTF-8 (RFC 3629: no overlong forms, no
// surrogates, nothing above U+10FFFF), or npos. Config values end up in JSON manifests, which need it.
size_t invalid_utf8_at(const std::string& text) {
    const auto* p = reinterpret_cast<const unsigned char*>(text.data());
    const size_t n = text.size();
    for (size_t i = 0; i < n;) {
        const unsigned c = p[i];
        size_t len = 0;
        unsigned lo = 0x80, hi = 0xBF;  // allowed range of the second byte
        if (c < 0x80) len = 1;
        else if (c >= 0xC2 && c <= 0xDF) len = 2;
        else if (c >= 0xE0 && c <= 0xEF) len = 3, lo = c == 0xE0 ? 0xA0 : 0x80, hi = c == 0xED ? 0x9F : 0xBF;
        else if (c >= 0xF0 && c <= 0xF4) len = 4, lo = c == 0xF0 ? 0x90 : 0x80, hi = c == 0xF4 ? 0x8F : 0xBF;
        else return i;
        if (i + len > n) return i;
        for (size_t k = 1; k < len; ++k) {
            const unsigned b = p[i + k];
            if (b < (k == 1 ? lo : 0x80) || b > (k == 1 ? hi : 0xBF)) return i;
        }
        i += len;
    }
    return std::string::npos;
}

Result<void> expand_into(const std::vector<std::string>& args, int depth, std::vector<std::string>& out,
                         std::vector<std::string>* files_read, ExpansionBudget& budget) {
    for (const std::string& arg : args) {
        if (arg.size() < 2 || arg[0] != '@') {
            out.push_back(arg);
            continue;
        }
        const std::string file = arg.substr(1);
        if (depth >= kMaxResponseDepth)
            return make_error(file + ": response files nested deeper than " + std::to_string(kMaxResponseDepth) +
                              " (a file that includes itself?)");
        if (++budget.reads > kMaxResponseReads)
            return make_error(file + ": response files name other response files more than " +
                              std::to_string(kMaxResponseReads) + " times in all (nested @FILE repeated?)");
        auto bytes = io::read_file(file);
        if (!bytes) return make_error(file + ": cannot read response file");
        budget.bytes += bytes->size();
        if (budget.bytes > kMaxResponseBytes)
            return make_error(file + ": response files hold more than " + std::to_string(kMaxResponseBytes >> 20) +
                              " MiB in all");
        if (files_read && std::find(files_read->begin(), files_read->end(), file) == files_read->end())
            files_read->push_back(file);
        std::vector<std::string> words;
        auto split = split_response_text(std::string(bytes->begin(), bytes->end()), file, words);
        if (!split) return split.error();
        auto nested = expand_into(words, depth + 1, out, files_read, budget);
        if (!nested) return nested.error();
        if (out.size() > kMaxResponseArguments)
            return make_error(file + ": response files expand to more than " + std::to_string(kMaxResponseArguments) +
                              " arguments");
    }
    return {};
}

std::vector<std::string> scalar_strings(const nlohmann::json& value) {
    auto one = [](const nlohmann::json& v) { return v.is_string() ? v.get<std::string>() : v.dump(); };
    std::vector<std::string> out;
    if (value.is_array()) {
        for (const nlohmann::json& v : value) out.push_back(one(v));
    } else {
        out.push_back(one(value));
    }
    return out;
}

bool contains(std::span<const std::string> names, const std::string& name) {
    return std::find(names.begin(), names.end(), name) != names.end();
}

Result<void> add_materials(const nlohmann::json& table, const std::string& source, MaterialOverrides& out) {
    if (!table.is_object()) return make_error(source + ": 'materials' must be a table of material names");
    for (auto m = table.begin(); m != table.end(); ++m) {
        if (!m.value().is_object())
            return make_error(source + ": materials." + m.key() + " must be a table of options");
        for (auto kv = m.value().begin(); kv != m.value().end(); ++kv) {
            if (kv.value().is_object())
                return make_error(source + ": materials." + m.key() + "." + kv.key() + " must be a value");
            const std::vector<std::string> values = scalar_strings(kv.value());
            if (values.empty()) return make_error(source + ": materials." + m.key() + "." + kv.key() + " has no value");
            out.set(m.key(), kv.key(), values.front());
        }
    }
    return {};
}

}  // namespace

Result<std::vector<std::string>> expand_response_files(const std::vector<std::string>& args,
                                                       std::vector<std::string>* files_read) {
    std::vector<std::string> out;
    ExpansionBudget budget;
    auto r = expand_into(args, 0, out, files_read, budget);
    if (!r) return r.error();
    return out;
}

Result<nlohmann::json> parse_config_text(const std::string& text, const std::string& source_name) {
    if (const size_t bad = invalid_utf8_at(text); bad != std::string::npos)
        return make_error(source_name + ": not valid UTF-8 (byte " + std::to_string(bad) + ")");
    const size_t first = text.find_first_not_of(" \t\r\n");
    if (first != std::string::npos && text[first] == '{') {
        // JSON allows a key twice (the parser keeps the last); TOML does not, and neither does a config:
        // which of two values counts must not depend on the format.
        std::vector<std::set<std::string>> open_objects;
        std::string duplicate;
        auto check_keys = [&](int, nlohmann::json::parse_event_t event, nlohmann::json& parsed) {
            using Event = nlohmann::json::parse_event_t;
            if (event == Event::object_start) open_objects.emplace_back();
            else if (event == Event::object_end && !open_objects.empty()) open_objects.pop_back();
            else if (event == Event::key && !open_objects.empty() && parsed.is_string() &&
                     !open_objects.back().insert(parsed.get<std::string>()).second && duplicate.empty())
                duplicate = parsed.get<std::string>();
            return true;
        };
        nlohmann::json j = nlohmann::json::parse(text, check_keys, false);
        if (j.is_discarded() || !j.is_object()) return make_error(source_name + ": not valid JSON");
        if (!duplicate.empty())
            return make_error(source_name + ": key '" + duplicate + "' appears twice in one object");
        return j;
    }
    std::vector<CLI::ConfigItem> items;
    try {
        std::istringstream in(text);
        items = CLI::ConfigTOML().from_config(in);
    } catch (const CLI::Error& e) {
        return make_error(source_name + ": not valid TOML: " + e.what());
    }
    nlohmann::json tree = nlohmann::json::object();
    for (const CLI::ConfigItem& item : items) {
        if (item.name == "++" || item.name == "--") continue;  // section open/close markers
        nlohmann::json* node = &tree;
        for (const std::string& parent : item.parents) {
            if (node->contains(parent) && !(*node)[parent].is_object())
                return make_error(source_name + ": '" + parent + "' is both a value and a table");
            node = &(*node)[parent];
        }
        if (item.inputs.size() == 1) {
            (*node)[item.name] = item.inputs.front();
        } else {
            (*node)[item.name] = item.inputs;
        }
    }
    return tree;
}

void MaterialOverrides::set(const std::string& material, const std::string& key, std::string value) {
    table_[material][key] = std::move(value);
}

std::optional<std::string> MaterialOverrides::find(const std::string& material, const std::string& key) const {
    auto m = table_.find(material);
    if (m == table_.end()) return std::nullopt;
    auto v = m->find(key);
    if (v == m->end()) return std::nullopt;
    return v->get<std::string>();
}

Result<std::optional<double>> MaterialOverrides::number(const std::string& material, const std::string& key) const {
    const std::optional<std::string> text = find(material, key);
    if (!text) return std::optional<double>();
    try {
        size_t used = 0;
        const double v = std::stod(*text, &used);
        if (used == text->size()) return std::optional<double>(v);
    } catch (const std::exception&) {
    }
    return make_error("materials." + material + "." + key + ": '" + *text + "' is not a number");
}

MaterialOverrides& material_overrides() {
    static MaterialOverrides overrides;
    return overrides;
}

Result<SplitConfig> split_config(const nlohmann::json& tree, const std::string& command,
                                 std::span<const std::string> global_options,
                                 std::span<const std::string> subcommands, const std::string& source_name) {
    SplitConfig out;
    for (auto it = tree.begin(); it != tree.end(); ++it) {
        const std::string& key = it.key();
        const nlohmann::json& value = it.value();
        if (key == "materials") {
            auto r = add_materials(value, source_name, out.materials);
            if (!r) return r.error();
        } else if (!value.is_object()) {
            if (contains(global_options, key) || command.empty()) {
                out.entries.push_back({{}, key, scalar_strings(value)});
            } else {
                out.entries.push_back({{command}, key, scalar_strings(value)});
            }
        } else if (contains(subcommands, key)) {
            if (key != command) continue;  // one file can configure several commands
            for (auto sub = value.begin(); sub != value.end(); ++sub) {
                if (sub.key() == "materials") {
                    auto r = add_materials(sub.value(), source_name, out.materials);
                    if (!r) return r.error();
                } else if (sub.value().is_object()) {
                    return make_error(source_name + ": unknown table [" + key + "." + sub.key() + "]");
                } else {
                    out.entries.push_back({{key}, sub.key(), scalar_strings(sub.value())});
                }
            }
        } else {
            return make_error(source_name + ": unknown table [" + key + "]");
        }
    }
    return out;
}

}  // namespace specbake
