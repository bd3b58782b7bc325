// Accessor data read from the buffer bytes: every component type, normalisation, byte stride and sparse
// substitution resolved to float attributes and uint32 indices, each range checked against its buffer.
#include "io/gltf/gltf_internal.h"

#include "core/huge_pages.h"

#include <algorithm>
#include <cstring>

namespace specbake::io::gltf {

namespace {

size_t component_size(int component_type) {
    switch (component_type) {
        case TINYGLTF_COMPONENT_TYPE_BYTE:
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return 1;
        case TINYGLTF_COMPONENT_TYPE_SHORT:
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: return 2;
        case TINYGLTF_COMPONENT_TYPE_INT:
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
        case TINYGLTF_COMPONENT_TYPE_FLOAT: return 4;
        case TINYGLTF_COMPONENT_TYPE_DOUBLE: return 8;
        default: return 0;
    }
}

int component_count(int type) {
    switch (type) {
        case TINYGLTF_TYPE_SCALAR: return 1;
        case TINYGLTF_TYPE_VEC2: return 2;
        case TINYGLTF_TYPE_VEC3: return 3;
        case TINYGLTF_TYPE_VEC4: return 4;
        default: return 0;  // matrices are never vertex attributes specbake reads
    }
}

// One component as double. Normalised integers map to [0,1] / [-1,1] as the glTF spec defines
// (signed: max(c / (2^(n-1) - 1), -1)).
double decode_component(const uint8_t* p, int component_type, bool normalized) {
    switch (component_type) {
        case TINYGLTF_COMPONENT_TYPE_BYTE: {
            int8_t v;
            std::memcpy(&v, p, 1);
            return normalized ? std::max(v / 127.0, -1.0) : double(v);
        }
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return normalized ? p[0] / 255.0 : double(p[0]);
        case TINYGLTF_COMPONENT_TYPE_SHORT: {
            int16_t v;
            std::memcpy(&v, p, 2);
            return normalized ? std::max(v / 32767.0, -1.0) : double(v);
        }
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
            uint16_t v;
            std::memcpy(&v, p, 2);
            return normalized ? v / 65535.0 : double(v);
        }
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: {
            uint32_t v;
            std::memcpy(&v, p, 4);
            return normalized ? v / 4294967295.0 : double(v);
        }
        case TINYGLTF_COMPONENT_TYPE_INT: {
            int32_t v;
            std::memcpy(&v, p, 4);
            return double(v);
        }
        case TINYGLTF_COMPONENT_TYPE_FLOAT: {
            float v;
            std::memcpy(&v, p, 4);
            return double(v);
        }
        default: {
            double v;
            std::memcpy(&v, p, 8);
            return v;
        }
    }
}

}  // namespace

Result<StridedView> view_of(const tinygltf::Model& m, const Payloads& payloads, int buffer_view, size_t byte_offset,
                            size_t count, size_t element_size, size_t element_stride_default,
                            const std::string& what) {
    if (buffer_view < 0 || size_t(buffer_view) >= m.bufferViews.size())
        return make_error(what + ": bufferView " + std::to_string(buffer_view) + " does not exist");
    const tinygltf::BufferView& bv = m.bufferViews[size_t(buffer_view)];
    if (bv.buffer < 0 || size_t(bv.buffer) >= payloads.size())
        return make_error(what + ": buffer " + std::to_string(bv.buffer) + " does not exist");
    const std::vector<unsigned char>& data = payloads[size_t(bv.buffer)];
    if (bv.byteOffset > data.size() || bv.byteLength > data.size() - bv.byteOffset)
        return make_error(what + ": bufferView " + std::to_string(buffer_view) + " lies outside its buffer");
    const size_t stride = bv.byteStride ? bv.byteStride : element_stride_default;
    if (count > 0) {
        // Compared without overflow: a count near 2^64 must not wrap around into range.
        const bool fits = byte_offset <= bv.byteLength && element_size <= bv.byteLength - byte_offset &&
                          (count == 1 || (stride > 0 && count - 1 <= (bv.byteLength - byte_offset - element_size) / stride));
        if (!fits)
            return make_error(what + ": accessor count " + std::to_string(count) + " runs past the end of bufferView " +
                              std::to_string(buffer_view) + " (" + std::to_string(bv.byteLength) + " bytes)");
    }
    return StridedView{data.data() + bv.byteOffset + byte_offset, stride};
}

namespace {

// Dense copy of an accessor's values as doubles (count * components), sparse substitution applied.
Result<std::vector<double>> read_accessor(const tinygltf::Model& m, const Payloads& payloads, int index,
                                          const std::string& what, const InputLimits& limits) {
    if (index < 0 || size_t(index) >= m.accessors.size())
        return make_error(what + ": accessor " + std::to_string(index) + " does not exist");
    const tinygltf::Accessor& a = m.accessors[size_t(index)];
    const int nc = component_count(a.type);
    const size_t cs = component_size(a.componentType);
    if (nc == 0 || cs == 0) return make_error(what + ": accessor " + std::to_string(index) + " has an unsupported type");
    // The count is checked against the bytes of the bufferView, or against the limit when there is none
    // (all zeros plus sparse values), before anything is allocated.
    Result<StridedView> view = StridedView{};
    if (a.bufferView >= 0) {
        view = view_of(m, payloads, a.bufferView, a.byteOffset, a.count, cs * size_t(nc), cs * size_t(nc), what);
        if (!view) return view.error();
    } else if (const uint64_t limit = limits.accessor_elements; a.count > limit) {
        return make_error(what + ": accessor " + std::to_string(index) + " without a bufferView: element count " +
                          over_limit("accessor-elements", a.count, limit));
    }
    std::vector<double> out(a.count * size_t(nc), 0.0);
    if (a.bufferView >= 0) {
        if (view->stride % cs != 0) return make_error(what + ": byteStride is not a multiple of the component size");
        if (a.componentType == TINYGLTF_COMPONENT_TYPE_FLOAT) {  // the common case, without per-component dispatch
            float f[4];
            for (size_t i = 0; i < a.count; ++i) {
                std::memcpy(f, view->base + i * view->stride, 4 * size_t(nc));
                for (int c = 0; c < nc; ++c) out[i * nc + c] = f[c];
            }
        } else if (a.componentType == TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT && nc == 1) {
            for (size_t i = 0; i < a.count; ++i) {
                uint32_t v;
                std::memcpy(&v, view->base + i * view->stride, 4);
                out[i] = a.normalized ? v / 4294967295.0 : double(v);
            }
        } else {
            for (size_t i = 0; i < a.count; ++i) {
                const uint8_t* p = view->base + i * view->stride;
                for (int c = 0; c < nc; ++c)
                    out[i * nc + c] = decode_component(p + c * cs, a.componentType, a.normalized);
            }
        }
    }
    if (a.sparse.isSparse) {
        const size_t n = size_t(std::max(a.sparse.count, 0));
        const int ict = a.sparse.indices.componentType;
        const size_t ics = component_size(ict);
        // glTF 2.0 Sec. 3.6.2.3: sparse indices are unsigned byte, short or int.
        if (ict != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE && ict != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
            ict != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT)
            return make_error(what + ": sparse indices have an invalid component type");
        auto iv = view_of(m, payloads, a.sparse.indices.bufferView, size_t(std::max(a.sparse.indices.byteOffset, 0)), n, ics, ics, what);
        if (!iv) return iv.error();
        auto vv = view_of(m, payloads, a.sparse.values.bufferView, size_t(std::max(a.sparse.values.byteOffset, 0)), n,
                          cs * size_t(nc), cs * size_t(nc), what);
        if (!vv) return vv.error();
        for (size_t s = 0; s < n; ++s) {
            // Sparse index and value arrays are tightly packed (glTF 2.0 Sec. 3.6.2.3).
            const double target = decode_component(iv->base + s * ics, ict, false);
            if (!(target >= 0 && target < double(a.count)))
                return make_error(what + ": sparse index " + std::to_string(target) + " out of range");
            const uint8_t* p = vv->base + s * cs * size_t(nc);
            for (int c = 0; c < nc; ++c)
                out[size_t(target) * nc + c] = decode_component(p + c * cs, a.componentType, a.normalized);
        }
    }
    return out;
}

}  // namespace

// Float attribute with exactly `components` per element (TEXCOORD/NORMAL/...).
Result<std::vector<float>> read_attribute(const tinygltf::Model& m, const Payloads& payloads, int index,
                                          int components, const std::string& what, const InputLimits& limits) {
    const tinygltf::Accessor& a = m.accessors.at(size_t(index));
    if (component_count(a.type) != components)
        return make_error(what + ": expected " + std::to_string(components) + " components per element");
    if (a.componentType == TINYGLTF_COMPONENT_TYPE_FLOAT && !a.sparse.isSparse && a.bufferView >= 0) {
        // The common case, copied without the detour through doubles.
        const size_t element = 4 * size_t(components);
        auto view = view_of(m, payloads, a.bufferView, a.byteOffset, a.count, element, element, what);
        if (!view) return view.error();
        // A mesh's attribute arrays are tens of MB: faulted in as huge pages where the kernel has them.
        std::vector<float> out;
        detail::reserve_huge_pages(out, a.count * size_t(components));
        out.resize(a.count * size_t(components));
        if (view->stride == element) {
            if (!out.empty()) std::memcpy(out.data(), view->base, out.size() * sizeof(float));
        } else {
            for (size_t i = 0; i < a.count; ++i) std::memcpy(&out[i * size_t(components)], view->base + i * view->stride, element);
        }
        return out;
    }
    auto values = read_accessor(m, payloads, index, what, limits);
    if (!values) return values.error();
    std::vector<float> out(values->size());
    for (size_t i = 0; i < out.size(); ++i) out[i] = float((*values)[i]);
    return out;
}

// An index accessor (unsigned byte, short or int scalars) as uint32, read directly when not sparse.
Result<std::vector<uint32_t>> read_indices(const tinygltf::Model& m, const Payloads& payloads, int index,
                                           const std::string& what, const InputLimits& limits) {
    const tinygltf::Accessor& a = m.accessors.at(size_t(index));
    const size_t cs = component_size(a.componentType);
    if (!a.sparse.isSparse && a.bufferView >= 0 && cs > 0) {
        auto view = view_of(m, payloads, a.bufferView, a.byteOffset, a.count, cs, cs, what);
        if (!view) return view.error();  // before allocating: the count is within the view's bytes
        std::vector<uint32_t> out;
        detail::reserve_huge_pages(out, a.count);
        out.resize(a.count);
        if (cs == 4 && view->stride == 4) {
            if (!out.empty()) std::memcpy(out.data(), view->base, out.size() * 4);
        } else {
            for (size_t i = 0; i < a.count; ++i) {
                const uint8_t* p = view->base + i * view->stride;
                if (cs == 1) {
                    out[i] = p[0];
                } else if (cs == 2) {
                    uint16_t v;
                    std::memcpy(&v, p, 2);
                    out[i] = v;
                } else {
                    std::memcpy(&out[i], p, 4);
                }
            }
        }
        return out;
    }
    auto values = read_accessor(m, payloads, index, what, limits);
    if (!values) return values.error();
    std::vector<uint32_t> out(values->size());
    for (size_t i = 0; i < out.size(); ++i) out[i] = uint32_t((*values)[i]);
    return out;
}

}  // namespace specbake::io::gltf
