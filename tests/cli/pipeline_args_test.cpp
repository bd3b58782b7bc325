// Response files, config files and per-material overrides.
#include "cli/config.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <unistd.h>

namespace fs = std::filesystem;
using namespace specbake;

namespace {

class TempDir {
public:
    TempDir() : path_(fs::temp_directory_path() / ("specbake_args_" + std::to_string(::getpid()))) {
        fs::remove_all(path_);
        fs::create_directories(path_);
    }
    ~TempDir() { fs::remove_all(path_); }
    fs::path write(const std::string& name, const std::string& text) const {
        std::ofstream(path_ / name, std::ios::binary) << text;
        return path_ / name;
    }

private:
    fs::path path_;
};

}  // namespace

TEST(ResponseFile, ExpandsWordsQuotesCommentsAndNesting) {
    TempDir dir;
    const fs::path inner = dir.write("inner.txt", "c.gltf\n# a comment line @ignored\n'd e.gltf'\n");
    const fs::path outer =
        dir.write("list.txt", "a.gltf   \"b c.gltf\"  # trailing comment\n@" + inner.string() + "\n-j 2\n");
    auto args = expand_response_files({"bake", "@" + outer.string(), "-o", "out"});
    ASSERT_TRUE(args.ok()) << args.error().message;
    const std::vector<std::string> expected{"bake", "a.gltf", "b c.gltf", "c.gltf", "d e.gltf",
                                            "-j",   "2",      "-o",       "out"};
    EXPECT_EQ(*args, expected);
}

TEST(ResponseFile, LeavesOtherArgumentsAlone) {
    auto args = expand_response_files({"@", "x@y", "--name=@z"});
    ASSERT_TRUE(args.ok());
    EXPECT_EQ(*args, (std::vector<std::string>{"@", "x@y", "--name=@z"}));
}

TEST(ResponseFile, ErrorsNameTheFile) {
    TempDir dir;
    auto missing = expand_response_files({"@/nonexistent/list.txt"});
    ASSERT_FALSE(missing.ok());
    EXPECT_NE(missing.error().message.find("/nonexistent/list.txt"), std::string::npos);

    const fs::path unterminated = dir.write("bad.txt", "a \"b c\n");
    auto bad = expand_response_files({"@" + unterminated.string()});
    ASSERT_FALSE(bad.ok());
    EXPECT_NE(bad.error().message.find("unterminated quote"), std::string::npos);

    const fs::path self = fs::temp_directory_path() / ("specbake_args_" + std::to_string(::getpid())) / "self.txt";
    dir.write("self.txt", "@" + self.string());
    auto loop = expand_response_files({"@" + self.string()});
    ASSERT_FALSE(loop.ok());
    EXPECT_NE(loop.error().message.find("nested"), std::string::npos);
}

TEST(ConfigFile, TomlAndJsonGiveTheSameTree) {
    const std::string toml =
        "jobs = 2\nisotropic = \"max\"\n[bake]\nformat = \"glb\"\n[materials.Steel]\nisotropic = \"sum\"\n";
    const std::string json =
        R"({"jobs": 2, "isotropic": "max", "bake": {"format": "glb"}, "materials": {"Steel": {"isotropic": "sum"}}})";
    auto t = parse_config_text(toml, "c.toml");
    auto j = parse_config_text(json, "c.json");
    ASSERT_TRUE(t.ok()) << t.error().message;
    ASSERT_TRUE(j.ok()) << j.error().message;
    EXPECT_EQ((*t)["bake"]["format"], "glb");
    EXPECT_EQ((*t)["materials"]["Steel"]["isotropic"], "sum");
    EXPECT_EQ((*j)["materials"]["Steel"]["isotropic"], "sum");
    EXPECT_EQ((*t)["jobs"], "2");  // TOML values stay text for the argument parser
    EXPECT_EQ((*j)["jobs"], 2);
}

TEST(ConfigFile, InvalidJsonNamesTheFile) {
    auto j = parse_config_text("{ \"a\": ", "broken.json");
    ASSERT_FALSE(j.ok());
    EXPECT_NE(j.error().message.find("broken.json"), std::string::npos);
}

TEST(ConfigFile, SplitsGlobalCommandAndMaterialEntries) {
    const nlohmann::json tree = {{"jobs", 3},
                                 {"isotropic", "max"},
                                 {"sizes", {1, 2}},
                                 {"bake", {{"format", "glb"}, {"materials", {{"Cloth", {{"isotropic", "mean"}}}}}}},
                                 {"texture", {{"container", "dds"}}},
                                 {"materials", {{"Steel", {{"roughness-value", 0.25}}}}}};
    const std::vector<std::string> globals{"jobs", "quiet"};
    const std::vector<std::string> subs{"bake", "texture"};
    auto split = split_config(tree, "bake", globals, subs, "c.json");
    ASSERT_TRUE(split.ok()) << split.error().message;
    bool saw_jobs = false, saw_kernel = false, saw_format = false, saw_sizes = false;
    for (const ConfigEntry& e : split->entries) {
        if (e.key == "jobs") saw_jobs = e.section.empty() && e.values == std::vector<std::string>{"3"};
        if (e.key == "isotropic") saw_kernel = e.section == std::vector<std::string>{"bake"};
        if (e.key == "format") saw_format = e.section == std::vector<std::string>{"bake"};
        if (e.key == "sizes") saw_sizes = e.values == std::vector<std::string>{"1", "2"};
        EXPECT_NE(e.key, "container") << "tables of other commands are skipped";
    }
    EXPECT_TRUE(saw_jobs && saw_kernel && saw_format && saw_sizes);
    EXPECT_EQ(split->materials.find("Cloth", "isotropic"), "mean");
    auto r = split->materials.number("Steel", "roughness-value");
    ASSERT_TRUE(r.ok());
    EXPECT_DOUBLE_EQ(r->value(), 0.25);
    EXPECT_FALSE(split->materials.find("Steel", "isotropic").has_value());
    EXPECT_FALSE(split->materials.find("Nobody", "isotropic").has_value());
}

TEST(ConfigFile, UnknownTablesAndBadNumbersAreErrors) {
    const std::vector<std::string> globals{"jobs"};
    const std::vector<std::string> subs{"bake"};
    auto unknown = split_config({{"bakery", {{"x", 1}}}}, "bake", globals, subs, "c.json");
    ASSERT_FALSE(unknown.ok());
    EXPECT_NE(unknown.error().message.find("[bakery]"), std::string::npos);
    auto split = split_config({{"materials", {{"M", {{"roughness-value", "rough"}}}}}}, "bake", globals, subs, "c");
    ASSERT_TRUE(split.ok());
    EXPECT_FALSE(split->materials.number("M", "roughness-value").ok());
}

// Found by fuzz/fuzz_config.cpp: a material override given as an empty array (read past the end of an
// empty list), and config text that is not UTF-8 (accepted, then fatal when the manifest is written).
TEST(ConfigFile, EmptyMaterialValueAndInvalidUtf8AreErrorsNamingTheFile) {
    const std::vector<std::string> globals{"jobs"};
    const std::vector<std::string> subs{"bake"};
    auto empty = split_config({{"materials", {{"M", {{"kappa", nlohmann::json::array()}}}}}}, "bake", globals, subs,
                              "c.json");
    ASSERT_FALSE(empty.ok());
    EXPECT_NE(empty.error().message.find("c.json: materials.M.kappa has no value"), std::string::npos)
        << empty.error().message;
    auto bad = parse_config_text("[materials.St\xFE\xFF" "el]\nkappa = \"1\"\n", "bad.toml");
    ASSERT_FALSE(bad.ok());
    EXPECT_NE(bad.error().message.find("bad.toml: not valid UTF-8 (byte 13)"), std::string::npos) << bad.error().message;
    for (const char* truncated : {"a = \"\xC3\"", "a = \"\xE2\x82\"", "a = \"\xED\xA0\x80\"", "a = \"\xC0\xAF\""})
        EXPECT_FALSE(parse_config_text(truncated, "t.toml").ok()) << truncated;
    auto good = parse_config_text("[materials.\"Stahl \xC3\x84 \xE2\x82\xAC \xF0\x9F\x98\x80\"]\nkappa = \"1\"\n", "ok.toml");
    ASSERT_TRUE(good.ok()) << good.error().message;
}

TEST(ResponseFile, NestedExpansionIsBoundedAsAWhole) {
    TempDir dir;
    // Six levels, each naming the one below ten times: 10^6 reads without a bound, refused at once.
    std::vector<fs::path> levels{dir.write("level0.txt", "a.gltf\n")};
    for (int level = 1; level <= 6; ++level) {
        std::string text;
        for (int k = 0; k < 10; ++k) text += "@" + levels.back().string() + "\n";
        levels.push_back(dir.write("level" + std::to_string(level) + ".txt", text));
    }
    auto fan = expand_response_files({"@" + levels.back().string()});
    ASSERT_FALSE(fan.ok());
    EXPECT_NE(fan.error().message.find("level"), std::string::npos) << fan.error().message;
    EXPECT_NE(fan.error().message.find("4096"), std::string::npos) << fan.error().message;
    // Two levels of ten are fine, and each file is listed once for the depfile.
    std::vector<std::string> files;
    auto small = expand_response_files({"@" + levels[2].string()}, &files);
    ASSERT_TRUE(small.ok()) << small.error().message;
    EXPECT_EQ(small->size(), 100u);
    EXPECT_EQ(files.size(), 3u);
    // One file whose words exceed the argument bound.
    std::string many;
    for (size_t i = 0; i < (size_t(1) << 20) + 1; ++i) many += "a ";
    auto wide = expand_response_files({"@" + dir.write("wide.txt", many).string()});
    ASSERT_FALSE(wide.ok());
    EXPECT_NE(wide.error().message.find("wide.txt"), std::string::npos) << wide.error().message;
    EXPECT_NE(wide.error().message.find("arguments"), std::string::npos) << wide.error().message;
}
