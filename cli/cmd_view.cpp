// specbake view: serves the before/after viewer (web/three/viewer/) on 127.0.0.1 for the baked scenes in a
// folder: three.js with specbake's plugin, filtering off on the left and on on the right, orbiting slowly,
// with the frame time of each half. Offline: three.js comes from --three, ./node_modules/three,
// specbake's install, or the copy the consumer tests pin (tests/consumers/package-lock.json), and the
// command says which; without any, it fails saying where it looked.
#include "cli/command.h"
#include "cli/run_settings.h"
#include "cli/web_server.h"
#include "io/files/atomic_write.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

namespace specbake::cli {
namespace {
namespace fs = std::filesystem;

struct ViewOptions {
    std::string out;
    std::string three;
    std::string host = "127.0.0.1";
    int port = 8137;
    std::string report;
};

// The folder `to` relative to the running executable's own folder, or empty.
fs::path beside_executable(const char* to) {
    std::error_code ec;
    const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
    return ec ? fs::path() : (exe.parent_path() / to).lexically_normal();
}

bool is_three_package(const fs::path& dir) {
    std::error_code ec;
    return fs::is_regular_file(dir / "build/three.module.js", ec) &&
           fs::is_regular_file(dir / "examples/jsm/loaders/GLTFLoader.js", ec) &&
           fs::is_regular_file(dir / "examples/jsm/loaders/KTX2Loader.js", ec);
}

std::string package_version(const fs::path& dir) {
    std::ifstream in(dir / "package.json");
    const nlohmann::json j = nlohmann::json::parse(in, nullptr, false);
    return j.is_object() ? j.value("version", "") : "";
}

struct ThreeFound {
    fs::path folder;
    std::string source;  // which of the places it came from
};

// The three.js package the viewer serves, in this order: --three (the package or a node_modules holding
// it), ./node_modules/three, specbake's install, the consumer tests' pinned copy.
Result<ThreeFound> find_three(const std::string& given) {
    if (!given.empty()) {
        for (const fs::path& dir : {fs::path(given), fs::path(given) / "three", fs::path(given) / "node_modules/three"})
            if (is_three_package(dir)) return ThreeFound{fs::absolute(dir).lexically_normal(), "--three"};
        return make_error("--three " + given + ": no three.js package there (expected " + given +
                          "/build/three.module.js and examples/jsm/loaders/GLTFLoader.js; e.g. --three node_modules/three "
                          "after `npm install three@0.187`)");
    }
    const std::vector<ThreeFound> places = {
        {fs::absolute("node_modules/three"), "./node_modules/three"},
        {beside_executable(SPECBAKE_WEB_FROM_BINDIR "/vendor/three"), "specbake's install"},
        {fs::path(SPECBAKE_THREE_PINNED), "the copy tests/consumers/package-lock.json pins in specbake's source tree"},
    };
    std::string looked;
    for (const ThreeFound& p : places) {
        if (is_three_package(p.folder)) return ThreeFound{p.folder.lexically_normal(), p.source};
        looked += (looked.empty() ? "" : ", ") + p.folder.string();
    }
    return make_error("no three.js found (looked in " + looked +
                      "); install it where you run this (`npm install three@0.187`) or pass --three DIR");
}

// The viewer's own files (index.html, the plugin): beside the installed executable, else the source tree.
Result<fs::path> find_web() {
    for (const fs::path& dir : {beside_executable(SPECBAKE_WEB_FROM_BINDIR "/three"), fs::path(SPECBAKE_WEB_SOURCE "/three")}) {
        std::error_code ec;
        if (fs::is_regular_file(dir / "viewer/index.html", ec) && fs::is_regular_file(dir / "specbake-three.js", ec))
            return dir.lexically_normal();
    }
    return make_error("the viewer's files are missing: neither " +
                      beside_executable(SPECBAKE_WEB_FROM_BINDIR "/three").string() + " nor " SPECBAKE_WEB_SOURCE
                      "/three holds viewer/index.html (reinstall specbake)");
}

// The .gltf / .glb files under `root` (three folders deep, as `specbake bake -o OUT` lays them out), sorted.
std::vector<std::string> scenes_under(const fs::path& root) {
    std::vector<std::string> found;
    std::error_code ec;
    for (auto it = fs::recursive_directory_iterator(root, fs::directory_options::skip_permission_denied, ec);
         !ec && it != fs::recursive_directory_iterator(); it.increment(ec)) {
        if (it.depth() > 3) {
            it.disable_recursion_pending();
            continue;
        }
        const std::string ext = it->path().extension().string();
        if (it->is_regular_file(ec) && (ext == ".gltf" || ext == ".glb"))
            found.push_back(fs::relative(it->path(), root, ec).generic_string());
    }
    std::sort(found.begin(), found.end());
    return found;
}

int run_view(const ViewOptions& o) {
    std::error_code ec;
    if (!fs::exists(o.out, ec)) {
        print_error(o.out + ": no such file or folder (give the folder `specbake bake -o` wrote, or a .gltf/.glb)");
        return kExitFailed;
    }
    const bool is_file = fs::is_regular_file(o.out, ec);
    const fs::path root = fs::absolute(is_file ? fs::path(o.out).parent_path() : fs::path(o.out)).lexically_normal();
    const std::vector<std::string> scenes =
        is_file ? std::vector<std::string>{fs::path(o.out).filename().string()} : scenes_under(root);
    if (scenes.empty()) {
        print_error(o.out + ": no .gltf or .glb files in it (bake one first: specbake bake SCENE -o " + o.out + ")");
        return kExitFailed;
    }
    const auto three = find_three(o.three);
    if (!three) {
        print_error(three.error().message);
        return kExitFailed;
    }
    const auto web = find_web();
    if (!web) {
        print_error(web.error().message);
        return kExitFailed;
    }
    const std::string version = package_version(three->folder);
    print_info("three.js " + (version.empty() ? std::string("(no version in its package.json)") : version) + " from " +
               three->folder.string() + " (" + three->source + ")");
    if (version.rfind("0.187.", 0) != 0)
        print_warning("the three.js plugin is tested with three 0.187 (r187) only; where this version changed the "
                      "shader lines it patches, the right half is drawn as three.js draws it (the page says so)");
    const nlohmann::json config = {{"scenes", scenes},
                                   {"three", {{"version", version}, {"folder", three->folder.string()}, {"source", three->source}}}};
    WebServerOptions server;
    server.host = o.host;
    server.port = o.port;
    server.fixed["/viewer.json"] = config.dump();
    std::ifstream index(*web / "viewer/index.html", std::ios::binary);
    std::ostringstream html;
    html << index.rdbuf();
    server.fixed["/"] = html.str();
    server.fixed["/index.html"] = html.str();
    server.folders = {{"/specbake/", *web}, {"/three/", three->folder}, {"/scene/", root}};
    bool report_failed = false;
    server.on_post = [&](const std::string& path, const std::string& body) {
        if (path != "/report" || o.report.empty()) return false;
        if (auto written = io::write_file_atomic(o.report, body); !written) {
            print_error(written.error().message);
            report_failed = true;
        }
        return true;
    };
    server.on_listening = [&](int port) {
        print_info(std::to_string(scenes.size()) + (scenes.size() == 1 ? " scene" : " scenes") + " in " + root.string() +
                   (o.report.empty() ? "; Ctrl-C stops the viewer" : "; stops after the page's first report"));
        std::printf("http://%s:%d/\n", o.host.c_str(), port);
        std::fflush(stdout);
    };
    if (auto served = serve_web(server); !served) {
        print_error(served.error().message);
        return kExitFailed;
    }
    return report_failed ? kExitFailed : kExitOk;
}

}  // namespace

void add_view_command(CLI::App& app, std::function<int()>& run) {
    auto* sub = app.add_subcommand(
        "view", "Open baked scenes in a before/after three.js viewer in your browser: filtering off (left) and on "
                "(right), orbiting slowly, with each half's frame time");
    auto o = std::make_shared<ViewOptions>();
    sub->add_option("out", o->out, "The folder `specbake bake -o` wrote (every .gltf/.glb in it), or one baked .gltf/.glb")
        ->required();
    sub->add_option("--three", o->three,
                    "The three.js package to use (a folder with build/three.module.js, or a node_modules holding "
                    "three); default: ./node_modules/three, else the one installed with specbake, else the consumer "
                    "tests' pinned copy in the source tree");
    sub->add_option("--port", o->port, "Port to serve on (0: any free port)")->capture_default_str()->check(CLI::Range(0, 65535));
    sub->add_option("--host", o->host, "IPv4 address to serve on (127.0.0.1: this machine only)")->capture_default_str();
    sub->add_option("--report", o->report,
                    "Write the page's first report (frame times and pixel statistics of each half, JSON; the page "
                    "sends it when opened with ?report=FRAMES) to FILE and stop: for automated checks");
    sub->footer(
        "The page loads each scene twice with three.js's GLTFLoader and specbake's plugin (web/three/): left with\n"
        "every material as three.js draws it, right with specbake's filtering; the camera orbits slowly (drag to\n"
        "turn, wheel to zoom, space pauses) and each half shows its median frame time over the last 60 frames.\n"
        "Nothing is fetched from the network. Details: web/three/README.md#viewer.\n"
        "Examples:\n"
        "  specbake bake Helmet.gltf -o baked/ && specbake view baked/\n"
        "      then open the printed http://127.0.0.1:8137/ in a browser\n"
        "  specbake view baked/Helmet/Helmet.gltf --three ~/game/node_modules/three\n"
        "  specbake view baked/ --port 0          (any free port; the URL is printed)");
    sub->callback([&run, o] { run = [o] { return run_view(*o); }; });
}

}  // namespace specbake::cli
