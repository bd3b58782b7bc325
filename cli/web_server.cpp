#include "cli/web_server.h"

#include "io/files/file_read.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cctype>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <sstream>

namespace specbake::cli {
namespace {
namespace fs = std::filesystem;

std::string content_type(const std::string& path) {
    const std::string ext = fs::path(path).extension().string();
    if (ext == ".html" || path.back() == '/') return "text/html; charset=utf-8";
    if (ext == ".js" || ext == ".mjs") return "text/javascript";
    if (ext == ".json" || ext == ".gltf") return "application/json";
    if (ext == ".wasm") return "application/wasm";
    if (ext == ".png") return "image/png";
    if (ext == ".jpg" || ext == ".jpeg") return "image/jpeg";
    if (ext == ".ktx2") return "image/ktx2";
    return "application/octet-stream";
}

bool send_all(int fd, const std::string& data) {
    size_t sent = 0;
    while (sent < data.size()) {
        const ssize_t n = ::send(fd, data.data() + sent, data.size() - sent, MSG_NOSIGNAL);
        if (n <= 0) return false;
        sent += size_t(n);
    }
    return true;
}

void respond(int fd, int status, const std::string& reason, const std::string& type, const std::string& body) {
    std::ostringstream head;
    head << "HTTP/1.1 " << status << ' ' << reason << "\r\nContent-Length: " << body.size()
         << "\r\nCache-Control: no-store\r\nConnection: close\r\n";
    if (!type.empty()) head << "Content-Type: " << type << "\r\n";
    head << "\r\n";
    send_all(fd, head.str() + body);
}

std::string percent_decoded(const std::string& s) {
    std::string out;
    for (size_t i = 0; i < s.size(); ++i) {
        if (s[i] == '%' && i + 2 < s.size() && std::isxdigit(static_cast<unsigned char>(s[i + 1])) &&
            std::isxdigit(static_cast<unsigned char>(s[i + 2]))) {
            out += char(std::stoi(s.substr(i + 1, 2), nullptr, 16));
            i += 2;
        } else {
            out += s[i];
        }
    }
    return out;
}

// The file `path` names under one of the folders, or empty when it names none (or escapes its folder).
fs::path file_for(const WebServerOptions& options, const std::string& path) {
    for (const WebFolder& f : options.folders) {
        if (path.compare(0, f.prefix.size(), f.prefix) != 0) continue;
        std::error_code ec;
        const fs::path root = fs::weakly_canonical(f.folder, ec);
        const fs::path file = fs::weakly_canonical(root / fs::path(path.substr(f.prefix.size())), ec);
        if (ec) return {};
        const std::string r = root.string() + "/";
        if (file.string().compare(0, r.size(), r) != 0 || !fs::is_regular_file(file, ec)) return {};
        return file;
    }
    return {};
}

// Handles one connection; true when the server should stop.
bool handle(int fd, const WebServerOptions& options) {
    std::string request;
    char buffer[65536];
    size_t header_end = std::string::npos;
    while ((header_end = request.find("\r\n\r\n")) == std::string::npos) {
        const ssize_t n = ::recv(fd, buffer, sizeof buffer, 0);
        if (n <= 0 || request.size() > (1u << 20)) return false;
        request.append(buffer, size_t(n));
    }
    std::istringstream line(request.substr(0, request.find("\r\n")));
    std::string method, target;
    line >> method >> target;
    const std::string path = percent_decoded(target.substr(0, target.find('?')));
    if (method == "POST") {
        size_t length = 0;
        std::string lower = request.substr(0, header_end);
        for (char& c : lower) c = char(std::tolower(static_cast<unsigned char>(c)));
        if (const size_t at = lower.find("content-length:"); at != std::string::npos)
            length = std::strtoull(lower.c_str() + at + 15, nullptr, 10);
        if (length > (64u << 20)) return respond(fd, 413, "Payload Too Large", "", ""), false;
        std::string body = request.substr(header_end + 4);
        while (body.size() < length) {
            const ssize_t n = ::recv(fd, buffer, sizeof buffer, 0);
            if (n <= 0) return false;
            body.append(buffer, size_t(n));
        }
        respond(fd, 204, "No Content", "", "");
        return options.on_post && options.on_post(path, body);
    }
    if (method != "GET" && method != "HEAD") return respond(fd, 405, "Method Not Allowed", "", ""), false;
    if (const auto it = options.fixed.find(path); it != options.fixed.end()) {
        respond(fd, 200, "OK", content_type(path), method == "HEAD" ? "" : it->second);
        return false;
    }
    const fs::path file = file_for(options, path);
    if (file.empty()) return respond(fd, 404, "Not Found", "text/plain", "not found: " + path + "\n"), false;
    // Read as every input is: a regular file only, without blocking on a FIFO put there since the check.
    const auto bytes = io::read_file(file);
    if (!bytes) return respond(fd, 404, "Not Found", "text/plain", bytes.error().message + "\n"), false;
    respond(fd, 200, "OK", content_type(file.string()),
            method == "HEAD" ? "" : std::string(bytes->begin(), bytes->end()));
    return false;
}

}  // namespace

Result<void> serve_web(const WebServerOptions& options) {
    const std::string where = options.host + ":" + std::to_string(options.port);
    const int listener = ::socket(AF_INET, SOCK_STREAM, 0);
    if (listener < 0) return make_error(std::string("cannot open a socket: ") + std::strerror(errno));
    const int yes = 1;
    ::setsockopt(listener, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes);
    sockaddr_in address{};
    address.sin_family = AF_INET;
    address.sin_port = htons(uint16_t(options.port));
    if (::inet_pton(AF_INET, options.host.c_str(), &address.sin_addr) != 1) {
        ::close(listener);
        return make_error("--host " + options.host + ": not an IPv4 address");
    }
    if (::bind(listener, reinterpret_cast<sockaddr*>(&address), sizeof address) != 0 || ::listen(listener, 64) != 0) {
        const std::string why = std::strerror(errno);
        ::close(listener);
        return make_error("cannot listen on " + where + ": " + why + (options.port ? " (--port 0 picks a free port)" : ""));
    }
    socklen_t length = sizeof address;
    ::getsockname(listener, reinterpret_cast<sockaddr*>(&address), &length);
    if (options.on_listening) options.on_listening(ntohs(address.sin_port));
    for (;;) {
        const int fd = ::accept(listener, nullptr, nullptr);
        if (fd < 0) {
            if (errno == EINTR) continue;
            const std::string why = std::strerror(errno);
            ::close(listener);
            return make_error("serving on " + where + ": " + why);
        }
        const bool stop = handle(fd, options);
        ::close(fd);
        if (stop) break;
    }
    ::close(listener);
    return {};
}

}  // namespace specbake::cli
