// Depfile syntax and the content-hash up-to-date check.
#include "io/output/depfile.h"
#include "io/output/manifest.h"
#include "io/files/sha256.h"
#include "io/output/up_to_date.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <unistd.h>

namespace fs = std::filesystem;
using namespace specbake::io;

namespace {

void write_text(const fs::path& p, const std::string& text) {
    fs::create_directories(p.parent_path());
    std::ofstream(p, std::ios::binary) << text;
}

}  // namespace

TEST(Depfile, EscapesSpacesHashColonAndDollar) {
    EXPECT_EQ(*escape_depfile_path("plain/file.png"), "plain/file.png");
    EXPECT_EQ(*escape_depfile_path("my file.png"), "my\\ file.png");
    EXPECT_EQ(*escape_depfile_path("a#b"), "a\\#b");
    EXPECT_EQ(*escape_depfile_path("cost$1"), "cost$$1");
    EXPECT_EQ(*escape_depfile_path("c:olon"), "c\\:olon");
    // A backslash before a space is doubled, so the parser does not read "\ " as an escaped space only.
    EXPECT_EQ(*escape_depfile_path("dir\\ x"), "dir\\\\\\ x");
    // Backslashes elsewhere stay as they are.
    EXPECT_EQ(*escape_depfile_path("a\\b\\n.png"), "a\\b\\n.png");
    // A leading '~' is a home folder to Make.
    EXPECT_EQ(*escape_depfile_path("~x.png"), "./~x.png");
    EXPECT_EQ(*escape_depfile_path("n\xc3\xa4.png"), "n\xc3\xa4.png");
}

TEST(Depfile, RejectsLineBreaksAndEmptyPaths) {
    EXPECT_FALSE(escape_depfile_path("a\nb").ok());
    EXPECT_FALSE(escape_depfile_path("").ok());
    const std::vector<std::string> targets{"out/manifest.json"};
    const std::vector<std::string> deps{"ok.png", "bad\r.png"};
    EXPECT_FALSE(format_depfile(targets, deps).ok());
    EXPECT_FALSE(format_depfile({}, deps).ok());
}

// Names that Make 4.3 and Ninja 1.11 cannot both read back (tests/cli/depfile_tools_test.cpp runs the
// tools): a clear error naming the path, on one line.
TEST(Depfile, RejectsWhatMakeAndNinjaCannotBothRead) {
    for (const char* name : {"a\tb", "a;b", "a|b", "a=b", "t[1].png", "a*b", "a?b", "a&b", "a'b", "a\"b", "a<b",
                             "a>b", "a^b", "a`b", "trail\\", "c:", "lib(m.o)", "a\\#b", "a\\:b", "a\nb"}) {
        auto r = escape_depfile_path(name);
        ASSERT_FALSE(r.ok()) << name;
        EXPECT_NE(r.error().message.find("cannot write the path"), std::string::npos) << r.error().message;
        EXPECT_EQ(r.error().message.find('\n'), std::string::npos) << r.error().message;
    }
}

TEST(Depfile, SortsAndDeduplicatesDependencies) {
    const std::vector<std::string> targets{"out dir/manifest.json", "out dir/a.glb"};
    const std::vector<std::string> deps{"z.gltf", "a b.png", "z.gltf", "m$.bin"};
    auto text = format_depfile(targets, deps);
    ASSERT_TRUE(text.ok());
    EXPECT_EQ(*text, "out\\ dir/manifest.json out\\ dir/a.glb: \\\n  a\\ b.png \\\n  m$$.bin \\\n  z.gltf\n");
}

TEST(Depfile, WritesAtomically) {
    const fs::path dir = fs::temp_directory_path() / ("specbake_depfile_" + std::to_string(::getpid()));
    fs::remove_all(dir);
    const std::vector<std::string> targets{"t"};
    const std::vector<std::string> deps{"d"};
    ASSERT_TRUE(write_depfile(dir / "sub" / "x.d", targets, deps).ok());
    std::ifstream in(dir / "sub" / "x.d");
    std::string all((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    EXPECT_EQ(all, "t: \\\n  d\n");
    size_t files = 0;
    for ([[maybe_unused]] auto& e : fs::directory_iterator(dir / "sub")) ++files;
    EXPECT_EQ(files, 1u);
    fs::remove_all(dir);
}

class UpToDate : public ::testing::Test {
protected:
    void SetUp() override {
        dir_ = fs::temp_directory_path() / ("specbake_uptodate_" + std::to_string(::getpid()));
        fs::remove_all(dir_);
        write_text(dir_ / "in" / "scene.gltf", "scene");
        write_text(dir_ / "in" / "tex.png", "texture");
        write_text(dir_ / "out" / "scene.gltf", "baked scene");
        Manifest m;
        m.version = "1.2.3";
        m.settings = {{"kernel", "mean"}};
        m.inputs.push_back({(dir_ / "in" / "scene.gltf").string(), *sha256_file(dir_ / "in" / "scene.gltf")});
        m.inputs.push_back({(dir_ / "in" / "tex.png").string(), *sha256_file(dir_ / "in" / "tex.png")});
        ManifestOutput o;
        o.kind = "scene";
        o.path = "scene.gltf";
        o.format = "gltf";
        m.outputs.push_back(o);
        ASSERT_TRUE(write_manifest(dir_ / "out", m).ok());
        query_.output_dir = dir_ / "out";
        query_.inputs = {(dir_ / "in" / "scene.gltf").string()};
        query_.settings = {{"kernel", "mean"}};
        query_.tool_version = "1.2.3";
    }
    void TearDown() override { fs::remove_all(dir_); }

    fs::path dir_;
    FreshnessQuery query_;
};

TEST_F(UpToDate, SameInputsSettingsAndVersion) {
    const Freshness f = check_up_to_date(query_);
    EXPECT_TRUE(f.up_to_date) << f.reason;
    // The referenced texture comes back for the depfile of the skipped run.
    ASSERT_EQ(f.recorded_inputs.size(), 2u);
    EXPECT_EQ(f.recorded_inputs[1], (dir_ / "in" / "tex.png").string());
}

TEST_F(UpToDate, TimestampsDoNotMatter) {
    fs::last_write_time(dir_ / "in" / "scene.gltf", fs::file_time_type::clock::now() + std::chrono::hours(1));
    EXPECT_TRUE(check_up_to_date(query_).up_to_date);
}

TEST_F(UpToDate, ChangedReferencedInputRebakes) {
    write_text(dir_ / "in" / "tex.png", "texture, edited");
    const Freshness f = check_up_to_date(query_);
    EXPECT_FALSE(f.up_to_date);
    EXPECT_NE(f.reason.find("tex.png changed"), std::string::npos) << f.reason;
}

TEST_F(UpToDate, ChangedSettingVersionOrInputListRebakes) {
    FreshnessQuery q = query_;
    q.settings["kernel"] = "max";
    EXPECT_FALSE(check_up_to_date(q).up_to_date);
    q = query_;
    q.tool_version = "1.2.4";
    EXPECT_FALSE(check_up_to_date(q).up_to_date);
    q = query_;
    q.inputs.push_back((dir_ / "in" / "other.gltf").string());
    EXPECT_FALSE(check_up_to_date(q).up_to_date);
}

TEST_F(UpToDate, MissingOrEditedOutputRebakes) {
    write_text(dir_ / "out" / "scene.gltf", "hand-edited");
    EXPECT_FALSE(check_up_to_date(query_).up_to_date);
    fs::remove(dir_ / "out" / "scene.gltf");
    EXPECT_FALSE(check_up_to_date(query_).up_to_date);
}

TEST_F(UpToDate, MissingOrCorruptManifestRebakes) {
    write_text(dir_ / "out" / "manifest.json", "{ not json");
    EXPECT_FALSE(check_up_to_date(query_).up_to_date);
    fs::remove(dir_ / "out" / "manifest.json");
    EXPECT_FALSE(check_up_to_date(query_).up_to_date);
}

TEST_F(UpToDate, MarkFreshTouchesOnlyTheTimestamp) {
    const fs::path manifest = dir_ / "out" / "manifest.json";
    const std::string before = *sha256_file(manifest);
    fs::last_write_time(manifest, fs::file_time_type::clock::now() - std::chrono::hours(2));
    const auto old_time = fs::last_write_time(manifest);
    mark_manifest_fresh(dir_ / "out");
    EXPECT_GT(fs::last_write_time(manifest), old_time);
    EXPECT_EQ(*sha256_file(manifest), before);
}
