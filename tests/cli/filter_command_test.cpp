// specbake filter: the JSON output reproduces bake/methods.h on the same input; bad input is a usage error.
#include "bake/methods.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <array>
#include <cstdio>
#include <string>
#include <sys/wait.h>

namespace {

struct CommandRun {
    int exit_code;
    std::string out;
};

CommandRun run_specbake(const std::string& args) {
    const std::string cmd = std::string(SPECBAKE_EXE) + " " + args + " 2>/dev/null";
    FILE* p = popen(cmd.c_str(), "r");
    std::string out;
    std::array<char, 4096> buf{};
    while (size_t n = fread(buf.data(), 1, buf.size(), p)) out.append(buf.data(), n);
    const int status = pclose(p);
    return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, out};
}

TEST(FilterCommand, JsonMatchesLibrary) {
    const CommandRun r = run_specbake(
        "filter --json --alpha 0.1,0.05 --h 0.6,0,0.8 --h-dx 0.64,0,0.768 --h-dy 0.6,0.03,0.7994 "
        "--n 0,0,1 --n-dx 0.03,0,0.99955 --n-dy 0,0.01,0.99995 --kappa 0.2 --pixel-size 0.02 --curvature 2");
    ASSERT_EQ(r.exit_code, 0);
    const nlohmann::json j = nlohmann::json::parse(r.out);
    specbake::FilterInput<double> in;
    in.alpha = {0.1, 0.05};
    in.h = specbake::normalize(specbake::Vec3<double>{0.6, 0, 0.8});
    in.h_dx = specbake::normalize(specbake::Vec3<double>{0.64, 0, 0.768});
    in.h_dy = specbake::normalize(specbake::Vec3<double>{0.6, 0.03, 0.7994});
    in.n = {0, 0, 1};
    in.n_dx = specbake::normalize(specbake::Vec3<double>{0.03, 0, 0.99955});
    in.n_dy = specbake::normalize(specbake::Vec3<double>{0, 0.01, 0.99995});
    in.kappa = 0.2;
    in.pixel_size = 0.02;
    in.curvature = 2;
    const auto methods = specbake::filter_methods();
    ASSERT_EQ(j["results"].size(), methods.size());
    for (size_t k = 0; k < methods.size(); ++k) {
        const auto& e = j["results"][k];
        EXPECT_EQ(e["method"], std::string(methods[k].name));
        EXPECT_EQ(e["source"], std::string(methods[k].source));
        const specbake::Sym2<double> A = specbake::evaluate(methods[k], in);
        EXPECT_DOUBLE_EQ(e["A"][0][0].get<double>(), A.xx) << methods[k].name;
        EXPECT_DOUBLE_EQ(e["A"][0][1].get<double>(), A.xy) << methods[k].name;
        EXPECT_DOUBLE_EQ(e["A"][1][0].get<double>(), A.xy) << methods[k].name;
        EXPECT_DOUBLE_EQ(e["A"][1][1].get<double>(), A.yy) << methods[k].name;
    }
}

TEST(FilterCommand, DefaultsPrintATableOfEveryMethod) {
    const CommandRun r = run_specbake("filter");
    ASSERT_EQ(r.exit_code, 0);
    for (const auto& m : specbake::filter_methods())
        EXPECT_NE(r.out.find(std::string(m.name) + " "), std::string::npos) << m.name;
}

TEST(FilterCommand, BadInputIsAUsageError) {
    EXPECT_EQ(run_specbake("filter --alpha 1.5").exit_code, 2);
    EXPECT_EQ(run_specbake("filter --h 0,0,0").exit_code, 2);
    EXPECT_EQ(run_specbake("filter --method nonsense").exit_code, 2);
    EXPECT_EQ(run_specbake("filter --sigma2 -1").exit_code, 2);
}

}  // namespace
