// A static HTTP/1.1 file server on one socket, for `specbake view`: GET requests are answered from fixed
// bodies or from the files under a few folders (nothing outside them), one connection at a time, each
// closed after its response; a POST goes to a handler, which can end the serving.
#pragma once

#include "core/result.h"

#include <filesystem>
#include <functional>
#include <map>
#include <string>
#include <vector>

namespace specbake::cli {

struct WebFolder {
    std::string prefix;           // URL path prefix ending in '/', e.g. "/three/"
    std::filesystem::path folder; // the files it serves
};

struct WebServerOptions {
    std::string host = "127.0.0.1";
    int port = 0;                                // 0: a free port the system picks
    std::map<std::string, std::string> fixed;    // URL path -> body, served as its extension's type
    std::vector<WebFolder> folders;
    // Receives the URL path and body of each POST; returns true to stop serving.
    std::function<bool(const std::string& path, const std::string& body)> on_post;
    // Called once listening, with the port bound.
    std::function<void(int port)> on_listening;
};

// Serves until on_post returns true or the process is interrupted; an error when the socket cannot be
// bound (the message names the host and port).
Result<void> serve_web(const WebServerOptions& options);

}  // namespace specbake::cli
