// specbake as a build step, end to end: determinism across --jobs and runs, the up-to-date skip and what
// rebakes, depfile contents, exit codes of a batch with a bad input, response files and --config.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <unistd.h>

namespace fs = std::filesystem;

namespace {

struct CommandResult {
    int code = -1;
    std::string out, err;
};

std::string read_text(const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

std::string quote(const std::string& s) { return "'" + s + "'"; }

class PipelineCli : public ::testing::Test {
protected:
    void SetUp() override {
        // A space in the folder name exercises depfile escaping and quoting everywhere.
        dir_ = fs::temp_directory_path() / ("specbake pipe " + std::to_string(::getpid()));
        fs::remove_all(dir_);
        fs::create_directories(dir_ / "scene");
        fs::copy_file(fs::path(SPECBAKE_SOURCE_DIR) / "tests/consumer/quad.gltf", dir_ / "scene/quad.gltf");
        ASSERT_EQ(run({"texture", "--demo", "-q", "-o", (dir_ / "scene/demo").string()}).code, 0);
        std::ofstream(dir_ / "scene/broken.gltf") << "{ this is not glTF";
    }
    void TearDown() override { fs::remove_all(dir_); }

    CommandResult run(const std::vector<std::string>& args) {
        std::string cmd = quote(SPECBAKE_EXE);
        for (const std::string& a : args) cmd += " " + quote(a);
        const fs::path out = dir_ / "stdout.txt", err = dir_ / "stderr.txt";
        cmd += " >" + quote(out.string()) + " 2>" + quote(err.string());
        CommandResult r;
        const int status = std::system(cmd.c_str());
        r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
        r.out = read_text(out);
        r.err = read_text(err);
        return r;
    }
    std::string scene() const { return (dir_ / "scene/quad.gltf").string(); }
    std::string texture() const { return (dir_ / "scene/demo/demo_normal.png").string(); }
    fs::path out(const std::string& name) const { return dir_ / name; }

    // Every file under `root` by relative path -> content.
    static std::map<std::string, std::string> tree(const fs::path& root) {
        std::map<std::string, std::string> files;
        for (const auto& e : fs::recursive_directory_iterator(root))
            if (e.is_regular_file()) files[fs::relative(e.path(), root).generic_string()] = read_text(e.path());
        return files;
    }

    fs::path dir_;
};

size_t count_lines_with(const std::string& text, const std::string& needle) {
    size_t n = 0;
    std::istringstream in(text);
    for (std::string line; std::getline(in, line);) n += line.find(needle) != std::string::npos;
    return n;
}

}  // namespace

TEST_F(PipelineCli, BakeIsByteIdenticalAcrossJobsAndRuns) {
    ASSERT_EQ(run({"-j", "1", "bake", scene(), "-q", "-o", out("j1").string()}).code, 0);
    ASSERT_EQ(run({"-j", "2", "bake", scene(), "-q", "-o", out("j2").string()}).code, 0);
    ASSERT_EQ(run({"bake", "--jobs", "2", scene(), "-q", "-o", out("again").string()}).code, 0);
    const auto a = tree(out("j1")), b = tree(out("j2")), c = tree(out("again"));
    EXPECT_GE(a.size(), 3u);
    EXPECT_TRUE(a == b) << "--jobs 1 and --jobs 2 differ";
    EXPECT_TRUE(b == c) << "two runs differ";
}

TEST_F(PipelineCli, TextureBakeIsByteIdenticalAcrossJobs) {
    ASSERT_EQ(run({"-j", "1", "texture", "--demo", "-q", "-o", out("t1").string()}).code, 0);
    ASSERT_EQ(run({"-j", "2", "texture", "--demo", "-q", "-o", out("t2").string()}).code, 0);
    EXPECT_TRUE(tree(out("t1")) == tree(out("t2")));
}

TEST_F(PipelineCli, SecondRunIsSkippedAndChangesRebake) {
    const std::string o = out("baked").string();
    ASSERT_EQ(run({"bake", scene(), "-q", "-o", o}).code, 0);
    const auto first = tree(o);

    CommandResult second = run({"bake", scene(), "-o", o});
    EXPECT_EQ(second.code, 0);
    EXPECT_NE(second.out.find("up to date"), std::string::npos) << second.out << second.err;
    EXPECT_TRUE(tree(o) == first);

    CommandResult forced = run({"bake", scene(), "--force", "-o", o});
    EXPECT_EQ(forced.code, 0);
    EXPECT_EQ(forced.out.find("up to date"), std::string::npos);
    EXPECT_TRUE(tree(o) == first) << "a forced rebake of the same inputs gives the same bytes";

    CommandResult setting = run({"bake", scene(), "--isotropic", "max", "-o", o});
    EXPECT_EQ(setting.code, 0);
    EXPECT_EQ(setting.out.find("up to date"), std::string::npos);
    EXPECT_NE(read_text(out("baked") / "manifest.json").find("\"max\""), std::string::npos);

    CommandResult same_again = run({"bake", scene(), "--isotropic", "max", "-o", o});
    EXPECT_NE(same_again.out.find("up to date"), std::string::npos);

    // The referenced texture changes (the scene file does not): rebake.
    ASSERT_EQ(run({"texture", "--demo", "-q", "--roughness-value", "0.2", "-o", (dir_ / "other").string()}).code, 0);
    std::ofstream(texture(), std::ios::app) << '\n';
    CommandResult changed = run({"-v", "bake", scene(), "--isotropic", "max", "-o", o});
    EXPECT_EQ(changed.code, 0);
    EXPECT_EQ(changed.out.find("up to date"), std::string::npos);
    EXPECT_NE(changed.err.find("demo_normal.png changed"), std::string::npos) << changed.err;
}

TEST_F(PipelineCli, DepfileListsSceneAndReferencedTexture) {
    const fs::path o = out("dep");
    const fs::path d = out("dep.d");
    ASSERT_EQ(run({"bake", scene(), "-q", "-o", o.string(), "--depfile", d.string()}).code, 0);
    auto esc = [](std::string s) {
        std::string r;
        for (char c : s) r += c == ' ' ? std::string("\\ ") : std::string(1, c);
        return r;
    };
    const std::string expected_deps[] = {texture(), scene()};  // sorted
    const std::string expected = esc((o / "manifest.json").string()) + ": \\\n  " + esc(expected_deps[0]) +
                                 " \\\n  " + esc(expected_deps[1]) + "\n";
    EXPECT_EQ(read_text(d), expected);
    // A skipped run writes the same depfile.
    fs::remove(d);
    CommandResult skipped = run({"bake", scene(), "-o", o.string(), "--depfile", d.string()});
    EXPECT_NE(skipped.out.find("up to date"), std::string::npos);
    EXPECT_EQ(read_text(d), expected);
}

TEST_F(PipelineCli, BatchWithABadInputFailsOnlyThatInput) {
    const std::string bad = (dir_ / "scene/broken.gltf").string();
    CommandResult r = run({"bake", scene(), bad, "-q", "-o", out("batch").string()});
    EXPECT_EQ(r.code, 1) << r.err;
    EXPECT_EQ(count_lines_with(r.err, "specbake: error:"), 1u) << r.err;
    EXPECT_NE(r.err.find("broken.gltf"), std::string::npos) << r.err;
    EXPECT_TRUE(fs::exists(out("batch") / "quad" / "quad.gltf"));
    EXPECT_TRUE(fs::exists(out("batch") / "manifest.json"));
}

TEST_F(PipelineCli, UsageErrorsExitTwo) {
    EXPECT_EQ(run({"bake", scene(), "--no-such-option", "-o", out("u").string()}).code, 2);
    EXPECT_EQ(run({"@" + (dir_ / "missing.txt").string()}).code, 2);
    EXPECT_EQ(run({"--config", (dir_ / "missing.toml").string(), "bake", scene(), "-o", out("u").string()}).code, 2);
    EXPECT_EQ(run({}).code, 2);
    EXPECT_EQ(run({"--help"}).code, 0);
    // verify --define takes NAME or NAME=VALUE (a C identifier, a one-line value); rejected before any GL work.
    for (const char* bad : {"1X", "A-B", "=1", "", "A=b\\c", "A=b\nc"}) {
        const CommandResult r = run({"verify", "--builtin", "sphere", "--define", bad});
        EXPECT_EQ(r.code, 2) << bad;
        EXPECT_NE(r.err.find("--define"), std::string::npos) << bad << ": " << r.err;
    }
}

TEST_F(PipelineCli, ResponseFileGivesTheArguments) {
    std::ofstream(dir_ / "list.txt") << "# scenes to bake\nbake\n\"" << scene() << "\"\n-q -o '" << out("resp").string()
                                     << "'\n";
    CommandResult r = run({"@" + (dir_ / "list.txt").string()});
    EXPECT_EQ(r.code, 0) << r.err;
    EXPECT_TRUE(fs::exists(out("resp") / "manifest.json"));
}

TEST_F(PipelineCli, ConfigFileAndCommandLinePrecedence) {
    std::ofstream(dir_ / "c.toml") << "# flat keys go to the command being run\nisotropic = \"max\"\n"
                                   << "[texture]\nformat = \"dds\"\n";
    std::ofstream(dir_ / "c.json") << R"({"bake": {"isotropic": "sum", "container": "dds"}})";
    auto kernel_of = [&](const fs::path& o) {
        const std::string m = read_text(o / "manifest.json");
        for (const char* k : {"mean", "sum", "max"})
            if (m.find(std::string("\"isotropic\": \"") + k + "\"") != std::string::npos) return std::string(k);
        return std::string("?");
    };
    ASSERT_EQ(run({"--config", (dir_ / "c.toml").string(), "bake", scene(), "-q", "-o", out("c1").string()}).code, 0);
    EXPECT_EQ(kernel_of(out("c1")), "max");
    ASSERT_EQ(run({"bake", "--config", (dir_ / "c.toml").string(), scene(), "--isotropic", "mean", "-q", "-o",
                   out("c2").string()})
                  .code,
              0);
    EXPECT_EQ(kernel_of(out("c2")), "mean") << "the command line wins";
    ASSERT_EQ(run({"bake", scene(), "--config", (dir_ / "c.json").string(), "-q", "-o", out("c3").string()}).code, 0);
    EXPECT_EQ(kernel_of(out("c3")), "sum");
    EXPECT_FALSE(tree(out("c3")).empty());
    bool has_dds = false;
    for (const auto& [path, bytes] : tree(out("c3"))) has_dds |= path.ends_with(".dds");
    EXPECT_TRUE(has_dds);

    std::ofstream(dir_ / "typo.toml") << "kernal = \"max\"\n";
    CommandResult typo = run({"--config", (dir_ / "typo.toml").string(), "bake", scene(), "-q", "-o", out("c4").string()});
    EXPECT_EQ(typo.code, 2);
}

TEST_F(PipelineCli, InspectCheckExitCodes) {
    const fs::path t = out("tex");
    ASSERT_EQ(run({"texture", "--demo", "-q", "-o", t.string()}).code, 0);
    CommandResult good = run({"inspect", "--check", (t / "texture_lean.ktx2").string(), t.string()});
    EXPECT_EQ(good.code, 0) << good.err;
    const std::string bytes = read_text(t / "texture_lean.ktx2");
    std::ofstream(out("cut.ktx2"), std::ios::binary) << bytes.substr(0, bytes.size() / 2);
    CommandResult bad = run({"inspect", "--check", (t / "texture_kernel.ktx2").string(), out("cut.ktx2").string()});
    EXPECT_EQ(bad.code, 1);
    EXPECT_EQ(count_lines_with(bad.err, "specbake: error:"), 1u) << bad.err;
    EXPECT_NE(bad.err.find("cut.ktx2"), std::string::npos);
    // The manifest check sees an edited output.
    std::ofstream(t / "texture_kernel.ktx2", std::ios::app) << 'x';
    EXPECT_EQ(run({"inspect", "--check", t.string()}).code, 1);
}

TEST_F(PipelineCli, TextureSecondRunIsSkippedAndSettingRebakes) {
    const std::string o = out("tex").string();
    const std::string d = out("tex.d").string();
    ASSERT_EQ(run({"texture", "--normal", texture(), "--roughness-value", "0.3", "-q", "-o", o, "--depfile", d}).code, 0);
    EXPECT_NE(read_text(d).find("demo_normal.png"), std::string::npos) << read_text(d);
    const auto first = tree(o);
    CommandResult again = run({"texture", "--normal", texture(), "--roughness-value", "0.3", "-o", o});
    EXPECT_NE(again.out.find("up to date"), std::string::npos) << again.out << again.err;
    EXPECT_TRUE(tree(o) == first);
    CommandResult changed = run({"texture", "--normal", texture(), "--roughness-value", "0.4", "-q", "-o", o});
    EXPECT_EQ(changed.code, 0);
    EXPECT_EQ(changed.out.find("up to date"), std::string::npos);
    EXPECT_FALSE(tree(o) == first);
}
