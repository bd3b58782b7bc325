// Many assets in one process: scenes bake side by side with at most one per thread in flight, outputs the
// same bytes whatever --jobs, and the progress display (plain lines, nothing with -q, a line on a terminal).
#include "cli/progress.h"
#include "pipeline/scene_job.h"

#include <gtest/gtest.h>

#include <tbb/global_control.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <sstream>
#include <unistd.h>

namespace fs = std::filesystem;
using namespace specbake;

namespace {

std::string read_text(const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

std::string quote(const std::string& s) {
    std::string q = "'";
    for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return q + "'";
}

size_t count_of(const std::string& text, const std::string& needle) {
    size_t n = 0;
    for (size_t at = text.find(needle); at != std::string::npos; at = text.find(needle, at + 1)) ++n;
    return n;
}

std::map<std::string, std::string> tree(const fs::path& root) {
    std::map<std::string, std::string> files;
    for (const auto& e : fs::recursive_directory_iterator(root))
        if (e.is_regular_file()) files[fs::relative(e.path(), root).generic_string()] = read_text(e.path());
    return files;
}

constexpr int kScenes = 6;

class ManyScenes : public ::testing::Test {
protected:
    void SetUp() override {
        dir_ = fs::temp_directory_path() / ("specbake_many_" + std::to_string(::getpid()));
        fs::remove_all(dir_);
        fs::create_directories(dir_ / "lib");
        ASSERT_EQ(run({"texture", "--demo", "-q", "-o", (dir_ / "lib/demo").string()}).code, 0);
        // Copies of a textured quad, each its own asset (all reference the demo maps).
        const std::string quad = read_text(fs::path(SPECBAKE_SOURCE_DIR) / "tests/consumer/quad.gltf");
        for (int i = 0; i < kScenes; ++i) {
            scenes_.push_back((dir_ / "lib" / ("q" + std::to_string(i) + ".gltf")).string());
            std::ofstream(scenes_.back()) << quad;
        }
    }
    void TearDown() override { fs::remove_all(dir_); }

    struct Result {
        int code = -1;
        std::string out, err;
    };
    Result run(const std::vector<std::string>& args, const std::string& wrap = "") {
        std::string cmd = quote(SPECBAKE_EXE);
        for (const std::string& a : args) cmd += " " + quote(a);
        if (!wrap.empty()) cmd = wrap + " " + quote(cmd) + " /dev/null";
        const fs::path out = dir_ / "stdout.txt", err = dir_ / "stderr.txt";
        cmd += " >" + quote(out.string()) + " 2>" + quote(err.string()) + " </dev/null";
        Result r;
        const int status = std::system(cmd.c_str());
        r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
        r.out = read_text(out);
        r.err = read_text(err);
        return r;
    }
    std::vector<std::string> bake_args(const std::string& out) const {
        std::vector<std::string> a{"bake"};
        a.insert(a.end(), scenes_.begin(), scenes_.end());
        a.insert(a.end(), {"-o", (dir_ / out).string()});
        return a;
    }

    fs::path dir_;
    std::vector<std::string> scenes_;
};

}  // namespace

TEST_F(ManyScenes, OutputsAreTheSameBytesWhateverJobs) {
    auto a1 = bake_args("j1"), a2 = bake_args("j2");
    a1.insert(a1.begin(), {"-j", "1", "-q"});
    a2.insert(a2.begin(), {"-j", "2", "-q"});
    ASSERT_EQ(run(a1).code, 0);
    ASSERT_EQ(run(a2).code, 0);
    const auto one = tree(dir_ / "j1"), two = tree(dir_ / "j2");
    EXPECT_GE(one.size(), size_t(kScenes) * 6);
    EXPECT_TRUE(one == two) << "-j 1 and -j 2 differ";
    for (int i = 0; i < kScenes; ++i) EXPECT_TRUE(one.count("q" + std::to_string(i) + "/q" + std::to_string(i) + ".gltf"));
}

TEST_F(ManyScenes, AtMostOneScenePerThreadInFlight) {
    tbb::global_control two(tbb::global_control::max_allowed_parallelism, 2);
    SceneJob job;
    for (const std::string& s : scenes_) job.scenes.emplace_back(s);
    job.output_dir = dir_ / "lib_out";
    std::mutex m;
    int in_flight = 0, most = 0, finished = 0;
    // "reading <scene>" is the first line of a scene's bake; scene_finished its last event.
    job.progress = [&](const std::string& line) {
        if (line.rfind("reading ", 0) != 0) return;
        std::lock_guard lock(m);
        most = std::max(most, ++in_flight);
    };
    job.scene_finished = [&](size_t, const std::string& error) {
        EXPECT_EQ(error, "");
        std::lock_guard lock(m);
        --in_flight;
        ++finished;
    };
    auto outcome = run_scene_job(job);
    ASSERT_TRUE(outcome.ok()) << outcome.error().message;
    EXPECT_EQ(finished, kScenes);
    EXPECT_GE(most, 1);
    EXPECT_LE(most, 2) << "more scenes in memory than threads";
    ASSERT_EQ(outcome->plans.size(), size_t(kScenes));
    for (int i = 0; i < kScenes; ++i) EXPECT_EQ(outcome->plans[size_t(i)].scene, scenes_[size_t(i)]) << "input order";
}

TEST_F(ManyScenes, PlainLinesWhenNotATerminalAndNothingWithQuiet) {
    Result r = run(bake_args("plain"));
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_EQ(count_of(r.err, "\r"), 0u) << "no redrawn line into a file";
    for (int i = 1; i <= kScenes; ++i)
        EXPECT_EQ(count_of(r.err, "[" + std::to_string(i) + "/" + std::to_string(kScenes) + "] done "), 1u) << r.err;
    EXPECT_EQ(count_of(r.err, " elapsed"), size_t(kScenes)) << r.err;
    EXPECT_EQ(count_of(r.err, " left)"), size_t(kScenes - 1)) << "every line but the last has a remaining time\n"
                                                               << r.err;
    EXPECT_EQ(count_of(r.out, ": curvature on "), size_t(kScenes)) << "the summary is unchanged";

    auto quiet = bake_args("quiet");
    quiet.push_back("-q");
    Result q = run(quiet);
    EXPECT_EQ(q.code, 0);
    EXPECT_EQ(q.err + q.out, "");

    // A bad input among them: the others complete, one error line names it, exit 1.
    std::ofstream(dir_ / "lib/broken.gltf") << "{ not glTF";
    auto bad = bake_args("bad");
    bad.insert(bad.begin() + 1, (dir_ / "lib/broken.gltf").string());
    Result b = run(bad);
    EXPECT_EQ(b.code, 1);
    EXPECT_EQ(count_of(b.err, "specbake: error:"), 1u) << b.err;
    EXPECT_NE(b.err.find("broken.gltf"), std::string::npos) << b.err;
    EXPECT_EQ(count_of(b.err, "FAILED"), 1u) << b.err;
    EXPECT_EQ(tree(dir_ / "bad").size(), tree(dir_ / "plain").size()) << "the others complete";
}

TEST_F(ManyScenes, OneRedrawnLineOnATerminal) {
    if (std::system("script --version >/dev/null 2>&1") != 0) GTEST_SKIP() << "util-linux script not installed";
    // script(1) runs the command on a pseudo-terminal and copies what it wrote to our stdout.
    Result r = run(bake_args("tty"), "script -qfec");
    ASSERT_EQ(r.code, 0) << r.out << r.err;
    EXPECT_NE(r.out.find("\r["), std::string::npos) << r.out;
    EXPECT_NE(r.out.find(std::to_string(kScenes) + "/" + std::to_string(kScenes) + " scenes"), std::string::npos)
        << r.out;
    EXPECT_NE(r.out.find(" elapsed"), std::string::npos) << r.out;
    EXPECT_EQ(count_of(r.out, "] done "), 0u) << "no plain lines on a terminal\n" << r.out;
    EXPECT_EQ(count_of(r.out, ": curvature on "), size_t(kScenes));

    auto quiet = bake_args("ttyq");
    quiet.push_back("-q");
    Result q = run(quiet, "script -qfec");
    EXPECT_EQ(q.code, 0);
    EXPECT_EQ(q.out.find("\r["), std::string::npos) << "nothing with -q\n" << q.out;
}

TEST(ProgressDisplay, LinesCountDoneAndTotal) {
    testing::internal::CaptureStderr();
    {
        ProgressDisplay p(3, ProgressMode::lines, "assets");
        p.status("a", "reading a");  // a batch prints finished items, not activity
        p.finished("a", "done");
        p.finished("b", "up to date");
        p.finished("c", "FAILED");
    }
    const std::string err = testing::internal::GetCapturedStderr();
    EXPECT_EQ(err.find("reading"), std::string::npos) << err;
    EXPECT_NE(err.find("[1/3] done a ("), std::string::npos) << err;
    EXPECT_NE(err.find("[2/3] up to date b ("), std::string::npos) << err;
    EXPECT_NE(err.find("[3/3] FAILED c ("), std::string::npos) << err;
    EXPECT_EQ(count_of(err, "\n"), 3u) << err;
}

TEST(ProgressDisplay, SingleItemPrintsItsStepsAndOffPrintsNothing) {
    testing::internal::CaptureStderr();
    {
        ProgressDisplay p(1, ProgressMode::lines, "maps");
        p.status("n.png", "baking 4096x4096 n.png");
        p.fraction(0.5);
        p.finished("n.png", "done");
    }
    EXPECT_EQ(testing::internal::GetCapturedStderr(), "specbake: baking 4096x4096 n.png\n");
    testing::internal::CaptureStderr();
    {
        ProgressDisplay p(2, ProgressMode::off, "maps");
        p.status("n.png", "baking");
        p.finished("n.png", "done");
        p.finished("m.png", "done");
    }
    EXPECT_EQ(testing::internal::GetCapturedStderr(), "");
}

TEST(ProgressDisplay, BarIsRedrawnAroundOtherLinesAndClearedAtTheEnd) {
    testing::internal::CaptureStderr();
    {
        ProgressDisplay p(4, ProgressMode::bar, "assets");
        p.status("first.gltf", "reading first.gltf");
        p.finished("first.gltf", "done");
        print_line(stderr, "specbake: warning: something");
        p.finished("second.gltf", "done");
        p.finished("third.gltf", "done");
        p.finished("fourth.gltf", "done");
    }
    const std::string err = testing::internal::GetCapturedStderr();
    EXPECT_NE(err.find("\r[>                   ] 0/4 assets  first.gltf: reading first.gltf  0:00 elapsed"),
              std::string::npos) << err;
    // The warning is on a line of its own: the bar is cleared before it and drawn again after it.
    EXPECT_NE(err.find("\r\x1b[Kspecbake: warning: something\n\r[=====>"), std::string::npos) << err;
    EXPECT_NE(err.find("] 4/4 assets"), std::string::npos) << err;
    EXPECT_EQ(err.substr(err.size() - 4), "\r\x1b[K") << "the line is cleared when done";
}
