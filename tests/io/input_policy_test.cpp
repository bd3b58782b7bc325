// The path policy of io/files/input_policy.h on a real folder tree: what resolve_in_folder accepts and refuses
// when symbolic links lie on the way (to a file, to a folder, inside or outside the scene's folder), when
// the named file does not exist, and when the scene's folder is itself named through a link. The expected
// answers come from the tree's layout, written out here.
#include "io/files/input_policy.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

namespace fs = std::filesystem;
using specbake::io::InputPolicy;
using specbake::io::resolve_in_folder;

namespace {

// ROOT/scene/{mesh.obj, sub/inside.mtl, file_link -> ../outside/secret.mtl, dir_link -> ../outside,
// alias -> sub, absolute_alias -> ROOT/scene/sub}, ROOT/outside/secret.mtl, ROOT/scene_link -> scene.
class InputPolicyTree : public ::testing::Test {
protected:
    void SetUp() override {
        root_ = fs::temp_directory_path() / ("specbake_input_policy_" + std::to_string(::getpid()));
        fs::remove_all(root_);
        fs::create_directories(scene() / "sub");
        fs::create_directories(root_ / "outside");
        std::ofstream(scene() / "mesh.obj") << "v 0 0 0\n";
        std::ofstream(scene() / "sub" / "inside.mtl") << "newmtl m\n";
        std::ofstream(root_ / "outside" / "secret.mtl") << "newmtl m\n";
        fs::create_symlink("../outside/secret.mtl", scene() / "file_link");
        fs::create_symlink("../outside", scene() / "dir_link");
        fs::create_directory_symlink("sub", scene() / "alias");
        fs::create_directory_symlink(scene() / "sub", scene() / "absolute_alias");
        fs::create_directory_symlink("scene", root_ / "scene_link");
    }
    void TearDown() override { fs::remove_all(root_); }

    fs::path scene() const { return root_ / "scene"; }

    // The message of a refusal, "" when the reference is accepted (then the path must be folder / reference).
    static std::string refusal(const fs::path& folder, const std::string& reference) {
        const auto r = resolve_in_folder(folder, reference, InputPolicy{});
        if (!r) return r.error().message;
        EXPECT_EQ(*r, folder / fs::path(reference).lexically_normal()) << reference;
        return "";
    }

    fs::path root_;
};

TEST_F(InputPolicyTree, NamesBelowTheFolderWithoutLinksAreAcceptedWhetherOrNotTheyExist) {
    EXPECT_EQ(refusal(scene(), "mesh.obj"), "");
    EXPECT_EQ(refusal(scene(), "sub/inside.mtl"), "");
    EXPECT_EQ(refusal(scene(), "missing.mtl"), "");
    EXPECT_EQ(refusal(scene(), "sub/missing/deeper.mtl"), "");
    EXPECT_EQ(refusal(scene(), "mesh.obj/under_a_file.mtl"), "");  // ENOTDIR: nothing exists below it
}

TEST_F(InputPolicyTree, ALinkLeadingOutIsRefusedEvenWhenTheNameBelowItDoesNotExist) {
    EXPECT_NE(refusal(scene(), "file_link").find("symbolic link"), std::string::npos);
    EXPECT_NE(refusal(scene(), "dir_link/secret.mtl").find("symbolic link"), std::string::npos);
    EXPECT_NE(refusal(scene(), "dir_link/missing.mtl").find("symbolic link"), std::string::npos);
    EXPECT_NE(refusal(scene(), "dir_link/missing/deeper.mtl").find("symbolic link"), std::string::npos);
}

TEST_F(InputPolicyTree, ALinkThatStaysInsideIsAccepted) {
    EXPECT_EQ(refusal(scene(), "alias/inside.mtl"), "");
    EXPECT_EQ(refusal(scene(), "alias/missing.mtl"), "");
    EXPECT_EQ(refusal(scene(), "absolute_alias/inside.mtl"), "");
}

TEST_F(InputPolicyTree, AFolderNamedThroughALinkKeepsItsOwnFiles) {
    const fs::path folder = root_ / "scene_link";
    EXPECT_EQ(refusal(folder, "sub/inside.mtl"), "");
    EXPECT_EQ(refusal(folder, "missing.mtl"), "");
    EXPECT_NE(refusal(folder, "dir_link/secret.mtl").find("symbolic link"), std::string::npos);
}

TEST_F(InputPolicyTree, ALinkLeadingOutIsAcceptedInsideAnAllowedRoot) {
    InputPolicy policy;
    ASSERT_TRUE(specbake::io::add_allowed_root(policy, root_ / "outside"));
    EXPECT_TRUE(resolve_in_folder(scene(), "dir_link/secret.mtl", policy));
    EXPECT_TRUE(resolve_in_folder(scene(), "file_link", policy));
}

TEST_F(InputPolicyTree, NamesLeavingTheFolderLexicallyAreRefused) {
    EXPECT_NE(refusal(scene(), "../outside/secret.mtl").find("outside the scene's folder"), std::string::npos);
    EXPECT_NE(refusal(scene(), "sub/../../outside/secret.mtl").find("outside the scene's folder"), std::string::npos);
}

}  // namespace
