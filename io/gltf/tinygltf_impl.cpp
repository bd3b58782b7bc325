// The tinygltf implementation, compiled in this one translation unit; every other io file includes
// tinygltf for its declarations only (io/gltf/tinygltf_internal.h, through io/gltf/gltf_internal.h).
//
// It is compiled here, from the installed header, instead of being taken from Debian's libtinygltf.so:
// that library's TinyGLTF class does not match the layout its header declares (the loader sees the
// filesystem callbacks as null, and destroying a TinyGLTF frees a bad pointer). specbake decodes images
// itself (io/image/image_io.h) and never lets tinygltf read image files.
#define TINYGLTF_IMPLEMENTATION
#include "io/gltf/tinygltf_internal.h"
