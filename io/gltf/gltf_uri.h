// Private to io/gltf_*.cpp: the URIs of a glTF file (data URIs, remote URIs, RFC 3986 percent-encoding of
// relative file paths) and the base64 of data URIs.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace specbake::io::gltf {

bool is_data_uri(const std::string& uri);
// A URI with a scheme ("https:", "file:") rather than a relative path; a drive letter is not a scheme.
bool is_remote_uri(const std::string& uri);
// RFC 3986 percent-decoding of a relative URI into a file path, and the encoding back.
std::string percent_decode(const std::string& uri);
std::string percent_encode(const std::string& path);
std::string base64_encode(const uint8_t* data, size_t size);
std::vector<uint8_t> base64_decode(const std::string& text);

}  // namespace specbake::io::gltf
