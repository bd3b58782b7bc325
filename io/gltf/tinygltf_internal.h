// Private to io/gltf/: <tiny_gltf.h> as specbake configures it (no stb image code, no external image loading).
// Every io file includes tinygltf through here, so that all of them see the same TinyGLTF class.
#pragma once

#define TINYGLTF_NO_STB_IMAGE
#define TINYGLTF_NO_STB_IMAGE_WRITE
#define TINYGLTF_NO_EXTERNAL_IMAGE
#include <tiny_gltf.h>
