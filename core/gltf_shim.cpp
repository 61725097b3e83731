// fovea: C API over Debian's tinygltf (libtinygltf.so holds the implementation, so
// TINYGLTF_IMPLEMENTATION is not defined here; the declarations need no json/stb headers).
// tinygltf parses; everything it does not check (accessor bounds, component types, index
// ranges, node graph shape, finiteness) is checked here, because the data it hands back is
// untrusted. Any failure becomes a one-line message; no exception escapes.
#include "gltf_shim.h"
#include "base/pngcheck.h"

#include <tiny_gltf.h>

#include <sys/stat.h>
#include <climits>
#include <cstdlib>

#include <cerrno>
#include <cfloat>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <new>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

// Caps that keep a hostile file from asking for absurd allocations.
constexpr size_t kMaxFileBytes = 0x7fffffff;  // tinygltf takes lengths as int/unsigned
constexpr size_t kMaxCount = size_t(1) << 28; // elements per accessor
constexpr size_t kMaxZeroCount = size_t(1) << 22; // elements of an accessor without a bufferView
constexpr int kMaxImageSide = 16384;
constexpr size_t kMaxImageTexels = size_t(1) << 26; // as scene.c accepts
constexpr int kMaxJsonDepth = 100;            // tinygltf converts extras/extensions recursively

struct Fail : std::runtime_error {
    explicit Fail(const std::string &s) : std::runtime_error(s) {}
};

std::string str(size_t v) { return std::to_string(v); }
std::string str(int v) { return std::to_string(v); }

// ---- files --------------------------------------------------------------------------

bool read_file(const std::string &path, std::vector<unsigned char> *out, std::string *err)
{
    struct stat st;
    if (stat(path.c_str(), &st) != 0) {
        *err = std::strerror(errno);
        return false;
    }
    if (!S_ISREG(st.st_mode)) {
        *err = "not a regular file";
        return false;
    }
    if (uint64_t(st.st_size) > kMaxFileBytes) {
        *err = "file larger than 2 GiB";
        return false;
    }
    FILE *f = std::fopen(path.c_str(), "rb");
    if (!f) {
        *err = std::strerror(errno);
        return false;
    }
    out->resize(size_t(st.st_size));
    size_t got = out->empty() ? 0 : std::fread(out->data(), 1, out->size(), f);
    std::fclose(f);
    if (got != out->size()) {
        *err = "short read";
        return false;
    }
    return true;
}

// tinygltf's filesystem hooks: regular files only, same size cap, and only inside the scene's
// folder tree (or --asset-root's). tinygltf has already percent-decoded the URI and joined it to
// the scene's folder (and, failing that, to the current directory); realpath() then removes
// every `..` and symbolic link, so the check is on the file that would really be opened. A
// downloaded scene must not make the renderer read the user's other files.
struct FsCtx {
    std::string dir;       // the scene file's folder as tinygltf joins URIs to it
    std::string root;      // canonical folder files must lie in ("" = no confinement)
    std::string refusal;   // the first refused URI's message, reported instead of tinygltf's
};

bool inside_root(const FsCtx &c, const std::string &path)
{
    if (c.root.empty()) return true;
    char *real = realpath(path.c_str(), nullptr);
    if (!real) return false;
    const std::string r(real);
    std::free(real);
    return r.size() > c.root.size() && r.compare(0, c.root.size(), c.root) == 0 &&
           (c.root.back() == '/' || r[c.root.size()] == '/');
}

bool fs_exists(const std::string &path, void *u)
{
    struct stat st;
    if (stat(path.c_str(), &st) != 0 || !S_ISREG(st.st_mode)) return false;
    FsCtx &c = *static_cast<FsCtx *>(u);
    if (inside_root(c, path)) return true;
    if (c.refusal.empty())
        c.refusal = "'" + path + "' is outside the scene's folder " + c.root + " (--asset-root DIR allows another)";
    return false;
}

bool fs_read(std::vector<unsigned char> *out, std::string *err, const std::string &path, void *u)
{
    std::string e;
    if (!inside_root(*static_cast<FsCtx *>(u), path)) e = "outside the scene's folder";
    else if (read_file(path, out, &e)) return true;
    if (err) *err += e;
    return false;
}

// Absolute paths and URI schemes other than data: (which tinygltf decodes itself and never
// passes here) are refused outright, before any lookup.
std::string fs_expand(const std::string &path, void *u)
{
    FsCtx &c = *static_cast<FsCtx *>(u);
    // tinygltf joined the URI to the scene's folder or to "."; look at the URI part only
    std::string uri = path;
    for (const std::string &pre : {c.dir + "/", std::string("./")})
        if (!c.dir.empty() && uri.compare(0, pre.size(), pre) == 0) {
            uri = uri.substr(pre.size());
            break;
        }
    if (uri.find("://") != std::string::npos || (!uri.empty() && uri[0] == '/')) {
        if (c.refusal.empty())
            c.refusal = "'" + path + "': absolute paths and URI schemes other than data: are not allowed";
        return std::string();
    }
    return path;
}

bool fs_write(std::string *err, const std::string &, const std::vector<unsigned char> &, void *)
{
    if (err) *err += "writing is not supported";
    return false;
}

// Rejects JSON nested deeper than kMaxJsonDepth before tinygltf recurses into it.
bool json_depth_ok(const unsigned char *s, size_t n)
{
    int depth = 0;
    bool in_str = false, esc = false;
    for (size_t i = 0; i < n; i++) {
        unsigned char c = s[i];
        if (in_str) {
            if (esc) esc = false;
            else if (c == '\\') esc = true;
            else if (c == '"') in_str = false;
        } else if (c == '"') {
            in_str = true;
        } else if (c == '[' || c == '{') {
            if (++depth > kMaxJsonDepth) return false;
        } else if (c == ']' || c == '}') {
            depth--;
        }
    }
    return true;
}

// Image loader hook: keep the encoded bytes (decoded later, only for base colour images)
// and bounds-check bufferView images, which tinygltf itself does not.
struct ImageHookCtx {
    const tinygltf::Model *model;
};

bool keep_encoded_image(tinygltf::Image *image, const int image_idx, std::string *err,
                        std::string *, int, int, const unsigned char *bytes, int size, void *user)
{
    const ImageHookCtx *ctx = static_cast<const ImageHookCtx *>(user);
    if (image->bufferView >= 0) {
        const tinygltf::Model &m = *ctx->model;
        const size_t bvi = size_t(image->bufferView);
        bool ok = bvi < m.bufferViews.size();
        if (ok) {
            const tinygltf::BufferView &bv = m.bufferViews[bvi];
            ok = bv.buffer >= 0 && size_t(bv.buffer) < m.buffers.size();
            if (ok) {
                const size_t have = m.buffers[size_t(bv.buffer)].data.size();
                ok = bv.byteOffset <= have && bv.byteLength <= have - bv.byteOffset && bv.byteLength > 0;
            }
        }
        if (!ok) {
            if (err) *err += "image " + str(image_idx) + ": bufferView out of bounds of its buffer";
            return false;
        }
    }
    if (size <= 0 || !bytes) {
        if (err) *err += "image " + str(image_idx) + ": no data";
        return false;
    }
    image->image.assign(bytes, bytes + size);
    image->as_is = true;
    return true;
}

// ---- accessors ----------------------------------------------------------------------

size_t component_bytes(int ct)
{
    switch (ct) {
    case TINYGLTF_COMPONENT_TYPE_BYTE:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return 1;
    case TINYGLTF_COMPONENT_TYPE_SHORT:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: return 2;
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
    case TINYGLTF_COMPONENT_TYPE_FLOAT: return 4;
    default: return 0; // INT and DOUBLE are not glTF 2.0 accessor types
    }
}

int type_components(int type)
{
    switch (type) {
    case TINYGLTF_TYPE_SCALAR: return 1;
    case TINYGLTF_TYPE_VEC2: return 2;
    case TINYGLTF_TYPE_VEC3: return 3;
    case TINYGLTF_TYPE_VEC4: return 4;
    case TINYGLTF_TYPE_MAT2: return 4;
    case TINYGLTF_TYPE_MAT3: return 9;
    case TINYGLTF_TYPE_MAT4: return 16;
    default: return 0;
    }
}

// Start and length of a bufferView inside its buffer, checked.
const unsigned char *view_bytes(const tinygltf::Model &m, int bvi, size_t *len, const std::string &what)
{
    if (bvi < 0 || size_t(bvi) >= m.bufferViews.size())
        throw Fail(what + ": bufferView " + str(bvi) + " does not exist");
    const tinygltf::BufferView &bv = m.bufferViews[size_t(bvi)];
    if (bv.buffer < 0 || size_t(bv.buffer) >= m.buffers.size())
        throw Fail(what + ": bufferView " + str(bvi) + " names missing buffer " + str(bv.buffer));
    const std::vector<unsigned char> &b = m.buffers[size_t(bv.buffer)].data;
    if (bv.byteOffset > b.size() || bv.byteLength > b.size() - bv.byteOffset)
        throw Fail(what + ": bufferView " + str(bvi) + " (offset " + str(bv.byteOffset) + ", length " +
                   str(bv.byteLength) + ") exceeds buffer " + str(bv.buffer) + " (" + str(b.size()) +
                   " bytes)");
    *len = bv.byteLength;
    return b.data() + bv.byteOffset;
}

// Checks that count elements of elem bytes at offset with stride fit in len bytes.
bool span_fits(size_t offset, size_t stride, size_t count, size_t elem, size_t len)
{
    if (count == 0) return true;
    if (offset > len || len - offset < elem) return false;
    return count - 1 <= (len - offset - elem) / stride;
}

// Calls fn(i, element bytes) for every element of accessor ai, sparse substitutions
// included; every byte touched has been bounds-checked.
template <class Fn>
void for_each_element(const tinygltf::Model &m, int ai, int want_comps, const std::string &what, Fn fn)
{
    if (ai < 0 || size_t(ai) >= m.accessors.size())
        throw Fail(what + ": accessor " + str(ai) + " does not exist");
    const tinygltf::Accessor &a = m.accessors[size_t(ai)];
    const std::string at = what + ": accessor " + str(ai);
    const int comps = type_components(a.type);
    if (comps != want_comps)
        throw Fail(at + ": has " + str(comps) + " components per element, expected " + str(want_comps));
    const size_t cb = component_bytes(a.componentType);
    if (cb == 0) throw Fail(at + ": invalid componentType " + str(a.componentType));
    if (a.count == 0 || a.count > kMaxCount) throw Fail(at + ": invalid count " + str(a.count));
    const size_t elem = cb * size_t(comps);

    if (a.bufferView >= 0) {
        size_t len;
        const unsigned char *base = view_bytes(m, a.bufferView, &len, at);
        const size_t vstride = m.bufferViews[size_t(a.bufferView)].byteStride;
        const size_t stride = vstride ? vstride : elem;
        if (stride < elem) throw Fail(at + ": byteStride " + str(stride) + " < element size " + str(elem));
        if (!span_fits(a.byteOffset, stride, a.count, elem, len))
            throw Fail(at + ": " + str(a.count) + " elements at offset " + str(a.byteOffset) +
                       " exceed bufferView " + str(a.bufferView) + " (" + str(len) + " bytes)");
        for (size_t i = 0; i < a.count; i++) fn(i, base + a.byteOffset + i * stride);
    } else {
        // No bufferView: all zeros (spec), usually sparse. Not backed by file bytes, so a tiny
        // file could ask for gigabytes; cap it lower.
        if (a.count > kMaxZeroCount) throw Fail(at + ": count " + str(a.count) + " without a bufferView");
        static const unsigned char zeros[64] = {0};
        for (size_t i = 0; i < a.count; i++) fn(i, zeros);
    }

    if (!a.sparse.isSparse) return;
    const int n = a.sparse.count;
    if (n < 1 || size_t(n) > a.count) throw Fail(at + ": invalid sparse count " + str(n));
    const int ict = a.sparse.indices.componentType;
    const size_t icb = component_bytes(ict);
    if (ict != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE && ict != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
        ict != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT)
        throw Fail(at + ": invalid sparse index componentType " + str(ict));
    if (a.sparse.indices.byteOffset < 0 || a.sparse.values.byteOffset < 0)
        throw Fail(at + ": negative sparse byteOffset");
    size_t ilen, vlen;
    const unsigned char *ib = view_bytes(m, a.sparse.indices.bufferView, &ilen, at + " sparse indices");
    const unsigned char *vb = view_bytes(m, a.sparse.values.bufferView, &vlen, at + " sparse values");
    const size_t ioff = size_t(a.sparse.indices.byteOffset), voff = size_t(a.sparse.values.byteOffset);
    if (!span_fits(ioff, icb, size_t(n), icb, ilen) || !span_fits(voff, elem, size_t(n), elem, vlen))
        throw Fail(at + ": sparse data exceeds its bufferViews");
    for (size_t k = 0; k < size_t(n); k++) {
        const unsigned char *p = ib + ioff + k * icb;
        uint32_t idx;
        if (icb == 1) idx = p[0];
        else if (icb == 2) { uint16_t v; std::memcpy(&v, p, 2); idx = v; }
        else std::memcpy(&idx, p, 4);
        if (idx >= a.count) throw Fail(at + ": sparse index " + str(size_t(idx)) + " >= count " + str(a.count));
        fn(idx, vb + voff + k * elem);
    }
}

float component_to_float(const unsigned char *p, int ct, bool normalized)
{
    switch (ct) {
    case TINYGLTF_COMPONENT_TYPE_FLOAT: { float f; std::memcpy(&f, p, 4); return f; }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return normalized ? p[0] / 255.0f : float(p[0]);
    case TINYGLTF_COMPONENT_TYPE_BYTE: {
        int8_t v; std::memcpy(&v, p, 1);
        return normalized ? std::fmax(v / 127.0f, -1.0f) : float(v);
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
        uint16_t v; std::memcpy(&v, p, 2);
        return normalized ? v / 65535.0f : float(v);
    }
    case TINYGLTF_COMPONENT_TYPE_SHORT: {
        int16_t v; std::memcpy(&v, p, 2);
        return normalized ? std::fmax(v / 32767.0f, -1.0f) : float(v);
    }
    default: { uint32_t v; std::memcpy(&v, p, 4); return float(v); } // UNSIGNED_INT
    }
}

std::vector<float> read_floats(const tinygltf::Model &m, int ai, int comps, const std::string &what)
{
    std::vector<float> out;
    const tinygltf::Accessor *a = (ai >= 0 && size_t(ai) < m.accessors.size()) ? &m.accessors[size_t(ai)] : nullptr;
    if (a && a->count <= kMaxCount) out.resize(a->count * size_t(comps));
    const size_t cb = a ? component_bytes(a->componentType) : 0;
    for_each_element(m, ai, comps, what, [&](size_t i, const unsigned char *p) {
        for (int c = 0; c < comps; c++)
            out[i * size_t(comps) + size_t(c)] = component_to_float(p + size_t(c) * cb, a->componentType, a->normalized);
    });
    for (size_t i = 0; i < out.size(); i++)
        if (!std::isfinite(out[i]))
            throw Fail(what + ": accessor " + str(ai) + ": element " + str(i / size_t(comps)) + " is not finite");
    return out;
}

std::vector<uint32_t> read_indices(const tinygltf::Model &m, int ai, size_t vertex_count, const std::string &what,
                                   bool triangles = true)
{
    if (ai < 0 || size_t(ai) >= m.accessors.size())
        throw Fail(what + ": index accessor " + str(ai) + " does not exist");
    const tinygltf::Accessor &a = m.accessors[size_t(ai)];
    const int ct = a.componentType;
    if (ct != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE && ct != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
        ct != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT)
        throw Fail(what + ": index accessor " + str(ai) + ": componentType " + str(ct) +
                   " is not an unsigned byte/short/int");
    if (triangles && a.count % 3 != 0)
        throw Fail(what + ": index accessor " + str(ai) + ": count " + str(a.count) + " is not a multiple of 3");
    std::vector<uint32_t> out;
    if (a.count <= kMaxCount) out.resize(a.count);
    for_each_element(m, ai, 1, what + " indices", [&](size_t i, const unsigned char *p) {
        uint32_t v;
        if (ct == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE) v = p[0];
        else if (ct == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT) { uint16_t s; std::memcpy(&s, p, 2); v = s; }
        else std::memcpy(&v, p, 4);
        out[i] = v;
    });
    for (size_t i = 0; i < out.size(); i++)
        if (out[i] >= vertex_count)
            throw Fail(what + ": index accessor " + str(ai) + ": index " + str(size_t(out[i])) + " at " + str(i) +
                       " out of range (vertex count " + str(vertex_count) + ")");
    return out;
}

// ---- transforms ---------------------------------------------------------------------

void mat_mul(const double a[16], const double b[16], double out[16]) // column-major out = a*b
{
    for (int c = 0; c < 4; c++)
        for (int r = 0; r < 4; r++) {
            double s = 0;
            for (int k = 0; k < 4; k++) s += a[k * 4 + r] * b[c * 4 + k];
            out[c * 4 + r] = s;
        }
}

void node_local(const tinygltf::Node &n, size_t ni, double out[16])
{
    const std::string at = "node " + str(ni);
    auto finite = [&](const std::vector<double> &v, const char *name) {
        for (double d : v)
            if (!std::isfinite(d)) throw Fail(at + ": " + name + " is not finite");
    };
    if (!n.matrix.empty()) {
        if (n.matrix.size() != 16) throw Fail(at + ": matrix needs 16 numbers");
        finite(n.matrix, "matrix");
        for (int i = 0; i < 16; i++) out[i] = n.matrix[size_t(i)];
        return;
    }
    double t[3] = {0, 0, 0}, q[4] = {0, 0, 0, 1}, s[3] = {1, 1, 1};
    if (!n.translation.empty()) {
        if (n.translation.size() != 3) throw Fail(at + ": translation needs 3 numbers");
        finite(n.translation, "translation");
        for (int i = 0; i < 3; i++) t[i] = n.translation[size_t(i)];
    }
    if (!n.rotation.empty()) {
        if (n.rotation.size() != 4) throw Fail(at + ": rotation needs 4 numbers");
        finite(n.rotation, "rotation");
        double len = 0;
        for (int i = 0; i < 4; i++) len += n.rotation[size_t(i)] * n.rotation[size_t(i)];
        len = std::sqrt(len);
        if (!(len > 1e-12)) throw Fail(at + ": rotation quaternion has zero length");
        for (int i = 0; i < 4; i++) q[i] = n.rotation[size_t(i)] / len; // exporters round; renormalise
    }
    if (!n.scale.empty()) {
        if (n.scale.size() != 3) throw Fail(at + ": scale needs 3 numbers");
        finite(n.scale, "scale");
        for (int i = 0; i < 3; i++) s[i] = n.scale[size_t(i)];
    }
    const double x = q[0], y = q[1], z = q[2], w = q[3];
    const double r[9] = {// column-major rotation
                         1 - 2 * (y * y + z * z), 2 * (x * y + z * w), 2 * (x * z - y * w),
                         2 * (x * y - z * w), 1 - 2 * (x * x + z * z), 2 * (y * z + x * w),
                         2 * (x * z + y * w), 2 * (y * z - x * w), 1 - 2 * (x * x + y * y)};
    for (int c = 0; c < 3; c++) {
        for (int rr = 0; rr < 3; rr++) out[c * 4 + rr] = r[c * 3 + rr] * s[c];
        out[c * 4 + 3] = 0;
    }
    out[12] = t[0], out[13] = t[1], out[14] = t[2], out[15] = 1;
}

float to_float(double d, const std::string &what)
{
    if (!std::isfinite(d) || std::fabs(d) > double(FLT_MAX)) throw Fail(what + " is not a finite float");
    return float(d);
}

// Light index from a node's KHR_lights_punctual extension, or -1.
int node_light(const tinygltf::Node &n, size_t ni, size_t light_count)
{
    auto it = n.extensions.find("KHR_lights_punctual");
    if (it == n.extensions.end()) return -1;
    const tinygltf::Value &ext = it->second;
    if (!ext.IsObject() || !ext.Has("light")) throw Fail("node " + str(ni) + ": malformed KHR_lights_punctual");
    const tinygltf::Value &l = ext.Get("light");
    const double d = l.IsNumber() ? l.GetNumberAsDouble() : -1.0;
    if (!(d >= 0 && d < double(light_count) && d == std::floor(d)))
        throw Fail("node " + str(ni) + ": KHR_lights_punctual light index out of range");
    return int(d);
}

// ---- the model ----------------------------------------------------------------------

struct Holder {
    fv_gltf_model pub{};
    std::vector<std::vector<float>> floats;
    std::vector<std::vector<uint32_t>> uints;
    std::vector<std::vector<uint8_t>> pixels;
    std::vector<fv_gltf_prim> prims;
    std::vector<size_t> mesh_first_prim;
    std::vector<fv_gltf_mesh> meshes;
    std::vector<fv_gltf_node> nodes;
    std::vector<fv_gltf_material> materials;
    std::vector<fv_gltf_image> images;
    std::vector<fv_gltf_light> lights;
    std::vector<int> material_texcoord; // TEXCOORD_n set of each material's textures
    size_t skipped_prims = 0;           // points and lines
    std::string warning;
};

const float *keep(Holder &h, std::vector<float> &&v)
{
    h.floats.push_back(std::move(v)); // moving a vector keeps its heap buffer
    return h.floats.back().data();
}

void convert_materials(const tinygltf::Model &m, Holder &h, std::vector<char> *image_used)
{
    for (size_t i = 0; i < m.materials.size(); i++) {
        const std::string at = "material " + str(i);
        const tinygltf::PbrMetallicRoughness &pbr = m.materials[i].pbrMetallicRoughness;
        fv_gltf_material mat{}; // wrap 0 (REPEAT), no transform, single-sided
        for (int c = 0; c < 4; c++) mat.base_color[c] = 1.0f;
        mat.image = mat.mr_image = mat.occlusion_image = mat.emissive_image = mat.normal_image = -1;
        mat.metallic = mat.roughness = mat.specular = 1.0f;
        mat.occlusion_strength = 1.0f, mat.normal_scale = 1.0f;
        for (float *x : mat.uvx) x[0] = 1.0f, x[4] = 1.0f;
        const tinygltf::Material &mt = m.materials[i];
        auto unit = [&](double d, const char *name) {
            const float f = to_float(d, at + " " + name);
            if (!(f >= 0.0f && f <= 1.0f)) throw Fail(at + ": " + name + " " + std::to_string(d) + " is outside [0, 1]");
            return f;
        };
        mat.metallic = unit(pbr.metallicFactor, "metallicFactor");
        mat.roughness = unit(pbr.roughnessFactor, "roughnessFactor");
        float strength = 1.0f;
        auto ext_number = [&](const char *ext, const char *key, float *out) {
            auto it = mt.extensions.find(ext);
            if (it == mt.extensions.end() || !it->second.IsObject() || !it->second.Has(key)) return;
            const tinygltf::Value &v = it->second.Get(key);
            if (!v.IsNumber()) throw Fail(at + ": " + ext + " " + key + " is not a number");
            *out = to_float(v.GetNumberAsDouble(), at + " " + ext + " " + key);
        };
        ext_number("KHR_materials_emissive_strength", "emissiveStrength", &strength);
        if (!(strength >= 0.0f)) throw Fail(at + ": negative emissiveStrength");
        ext_number("KHR_materials_specular", "specularFactor", &mat.specular);
        if (!(mat.specular >= 0.0f && mat.specular <= 1.0f)) throw Fail(at + ": specularFactor is outside [0, 1]");
        if (!mt.emissiveFactor.empty()) {
            if (mt.emissiveFactor.size() != 3) throw Fail(at + ": emissiveFactor needs 3 numbers");
            for (int c = 0; c < 3; c++) {
                mat.emissive[c] = unit(mt.emissiveFactor[size_t(c)], "emissiveFactor") * strength;
                if (!std::isfinite(mat.emissive[c])) throw Fail(at + ": emissive strength overflows");
            }
        }
        if (!pbr.baseColorFactor.empty()) {
            if (pbr.baseColorFactor.size() != 4) throw Fail(at + ": baseColorFactor needs 4 numbers");
            for (int c = 0; c < 4; c++) mat.base_color[c] = to_float(pbr.baseColorFactor[size_t(c)], at + " baseColorFactor");
        }
        int texcoord = -1; // the first texture's set; a map on another set is left out
        auto wrap_of = [](int gl) { return gl == 33071 ? 1 : gl == 33648 ? 2 : 0; }; // CLAMP_TO_EDGE, MIRRORED
        // KHR_texture_transform: uv' = T(offset) R(rotation) S(scale) uv; its texCoord overrides
        auto transform = [&](int slot, const tinygltf::ExtensionMap &ext, int *tc) {
            auto it = ext.find("KHR_texture_transform");
            if (it == ext.end() || !it->second.IsObject()) return;
            const tinygltf::Value &t = it->second;
            auto num = [&](const tinygltf::Value &v, const char *what) {
                if (!v.IsNumber()) throw Fail(at + ": KHR_texture_transform " + what + " is not a number");
                return to_float(v.GetNumberAsDouble(), at + " KHR_texture_transform " + what);
            };
            auto pair = [&](const char *key, float *o) {
                if (!t.Has(key)) return;
                const tinygltf::Value &a = t.Get(key);
                if (!a.IsArray() || a.ArrayLen() != 2) throw Fail(at + ": KHR_texture_transform " + key + " needs 2 numbers");
                o[0] = num(a.Get(0), key), o[1] = num(a.Get(1), key);
            };
            float off[2] = {0, 0}, sc[2] = {1, 1}, rot = 0;
            pair("offset", off);
            pair("scale", sc);
            if (t.Has("rotation")) rot = num(t.Get("rotation"), "rotation");
            if (t.Has("texCoord")) *tc = int(num(t.Get("texCoord"), "texCoord"));
            const double c = std::cos(double(rot)), s = std::sin(double(rot));
            float *x = mat.uvx[slot];
            x[0] = float(c * sc[0]), x[1] = float(s * sc[1]), x[2] = off[0];
            x[3] = float(-s * sc[0]), x[4] = float(c * sc[1]), x[5] = off[1];
            mat.has_uvx = 1;
        };
        auto texture = [&](int slot, int ti, int tc, const tinygltf::ExtensionMap &ext, const char *what, int *image) {
            if (ti < 0) return;
            transform(slot, ext, &tc);
            if (size_t(ti) >= m.textures.size()) throw Fail(at + ": " + what + " texture " + str(ti) + " does not exist");
            const int src = m.textures[size_t(ti)].source;
            if (src >= 0 && size_t(src) >= m.images.size())
                throw Fail("texture " + str(ti) + ": image " + str(src) + " does not exist");
            if (tc < 0) throw Fail(at + ": negative texCoord");
            if (src < 0) return; // (e.g. an extension-only source): factor only
            if (texcoord < 0) texcoord = tc;
            if (tc != texcoord) return;
            *image = src;
            (*image_used)[size_t(src)] = 1;
            const int si = m.textures[size_t(ti)].sampler;
            if (si >= 0 && size_t(si) < m.samplers.size()) {
                mat.wrap[slot][0] = wrap_of(m.samplers[size_t(si)].wrapS);
                mat.wrap[slot][1] = wrap_of(m.samplers[size_t(si)].wrapT);
                const int mag = m.samplers[size_t(si)].magFilter, min = m.samplers[size_t(si)].minFilter;
                mat.filter[slot][0] = mag == 9728; // NEAREST (9729 LINEAR, or none: linear)
                // minFilter: 9728 NEAREST, 9729 LINEAR (no mipmaps), 9984 NEAREST_MIPMAP_NEAREST,
                // 9985 LINEAR_MIPMAP_NEAREST, 9986 NEAREST_MIPMAP_LINEAR, 9987 LINEAR_MIPMAP_LINEAR
                mat.filter[slot][1] = min == 9728 || min == 9984 || min == 9986;
                mat.filter[slot][2] = min == 9728 || min == 9729 ? 2 : min == 9984 || min == 9985 ? 1 : 0;
            }
        };
        texture(0, pbr.baseColorTexture.index, pbr.baseColorTexture.texCoord, pbr.baseColorTexture.extensions, "base colour", &mat.image);
        texture(1, pbr.metallicRoughnessTexture.index, pbr.metallicRoughnessTexture.texCoord,
                pbr.metallicRoughnessTexture.extensions, "metallic-roughness",
                &mat.mr_image);
        texture(2, mt.occlusionTexture.index, mt.occlusionTexture.texCoord, mt.occlusionTexture.extensions, "occlusion", &mat.occlusion_image);
        texture(3, mt.emissiveTexture.index, mt.emissiveTexture.texCoord, mt.emissiveTexture.extensions, "emissive", &mat.emissive_image);
        texture(4, mt.normalTexture.index, mt.normalTexture.texCoord, mt.normalTexture.extensions, "normal", &mat.normal_image);
        if (mat.normal_image >= 0) mat.normal_scale = to_float(mt.normalTexture.scale, at + " normalTexture scale");
        if (texcoord < 0) texcoord = 0;
        if (mt.alphaMode == "MASK") mat.alpha_cutoff = unit(mt.alphaCutoff, "alphaCutoff");
        mat.double_sided = mt.doubleSided ? 1 : 0;
        mat.alpha_blend = mt.alphaMode == "BLEND" ? 1 : 0;
        if (mat.occlusion_image >= 0) mat.occlusion_strength = unit(mt.occlusionTexture.strength, "occlusion strength");
        h.materials.push_back(mat);
        h.material_texcoord.push_back(texcoord);
    }
}

void decode_images(const tinygltf::Model &m, Holder &h, const std::vector<char> &used)
{
    h.images.resize(m.images.size());
    h.pixels.resize(m.images.size());
    for (size_t i = 0; i < m.images.size(); i++) {
        h.images[i] = fv_gltf_image{nullptr, 0, 0};
        if (!used[i]) continue;
        const tinygltf::Image &src = m.images[i];
        const std::string at = "image " + str(i) + (src.uri.empty() ? "" : " (" + src.uri + ")");
        if (src.image.empty()) throw Fail(at + ": could not be read");
        if (fv_png_is_png(src.image.data(), src.image.size())) { // stb trusts the chunk lengths
            char why[160];
            if (fv_png_check(src.image.data(), src.image.size(), kMaxImageSide, kMaxImageTexels, nullptr, nullptr, why,
                             sizeof why))
                throw Fail(at + ": " + why);
        }
        tinygltf::Image img;
        img.name = src.name;
        std::string e, w;
        if (!tinygltf::LoadImageData(&img, int(i), &e, &w, 0, 0, src.image.data(), int(src.image.size()), nullptr))
            throw Fail(at + ": cannot decode" + (e.empty() ? "" : ": " + e));
        const size_t bytes_per = img.bits == 16 ? 2 : 1;
        if (img.width < 1 || img.height < 1 || img.width > kMaxImageSide || img.height > kMaxImageSide ||
            size_t(img.width) * size_t(img.height) > kMaxImageTexels || img.component != 4 ||
            (img.bits != 8 && img.bits != 16) ||
            img.image.size() != size_t(img.width) * size_t(img.height) * 4 * bytes_per)
            throw Fail(at + ": unsupported decoded layout");
        std::vector<uint8_t> &px = h.pixels[i];
        px.resize(size_t(img.width) * size_t(img.height) * 4);
        if (bytes_per == 1) {
            std::memcpy(px.data(), img.image.data(), px.size());
        } else { // 16-bit PNG: keep the high byte (stb returns native-endian uint16)
            for (size_t k = 0; k < px.size(); k++) {
                uint16_t v;
                std::memcpy(&v, img.image.data() + 2 * k, 2);
                px[k] = uint8_t(v >> 8);
            }
        }
        h.images[i] = fv_gltf_image{px.data(), img.width, img.height};
    }
}

void convert_meshes(const tinygltf::Model &m, Holder &h)
{
    for (size_t mi = 0; mi < m.meshes.size(); mi++) {
        h.mesh_first_prim.push_back(h.prims.size());
        const std::vector<tinygltf::Primitive> &prims = m.meshes[mi].primitives;
        for (size_t pi = 0; pi < prims.size(); pi++) {
            const tinygltf::Primitive &p = prims[pi];
            const int mode = p.mode == -1 ? TINYGLTF_MODE_TRIANGLES : p.mode;
            if (mode != TINYGLTF_MODE_TRIANGLES && mode != TINYGLTF_MODE_TRIANGLE_STRIP &&
                mode != TINYGLTF_MODE_TRIANGLE_FAN) { // points and lines: nothing a ray can hit
                h.skipped_prims++;
                continue;
            }
            const std::string at = "mesh " + str(mi) + " primitive " + str(pi);
            if (p.material < -1 || (p.material >= 0 && size_t(p.material) >= m.materials.size()))
                throw Fail(at + ": material " + str(p.material) + " does not exist");
            auto pos_it = p.attributes.find("POSITION");
            if (pos_it == p.attributes.end()) throw Fail(at + ": no POSITION attribute");
            fv_gltf_prim out{};
            out.material = p.material;
            std::vector<float> pos = read_floats(m, pos_it->second, 3, at + " POSITION");
            out.vertex_count = pos.size() / 3;
            out.positions = keep(h, std::move(pos));

            auto attr = [&](const std::string &name, int comps) -> const float * {
                auto it = p.attributes.find(name);
                if (it == p.attributes.end()) return nullptr;
                std::vector<float> v = read_floats(m, it->second, comps, at + " " + name);
                if (v.size() / size_t(comps) != out.vertex_count)
                    throw Fail(at + ": " + name + " count " + str(v.size() / size_t(comps)) +
                               " differs from POSITION count " + str(out.vertex_count));
                return keep(h, std::move(v));
            };
            out.normals = attr("NORMAL", 3);
            auto col_it = p.attributes.find("COLOR_0");
            if (col_it != p.attributes.end()) { // VEC3 or VEC4 (float, normalized ubyte/ushort)
                const int ai = col_it->second;
                const int comps = ai >= 0 && size_t(ai) < m.accessors.size() &&
                                  m.accessors[size_t(ai)].type == TINYGLTF_TYPE_VEC4 ? 4 : 3;
                const float *c = attr("COLOR_0", comps);
                std::vector<float> rgb(out.vertex_count * 3);
                for (size_t i = 0; i < out.vertex_count; i++)
                    for (int k = 0; k < 3; k++) rgb[3 * i + size_t(k)] = c[size_t(comps) * i + size_t(k)];
                out.colors = keep(h, std::move(rgb));
            }
            const fv_gltf_material *pm = out.material >= 0 ? &h.materials[size_t(out.material)] : nullptr;
            const int set = pm && (pm->image >= 0 || pm->mr_image >= 0 || pm->occlusion_image >= 0 ||
                                   pm->emissive_image >= 0 || pm->normal_image >= 0)
                                ? h.material_texcoord[size_t(out.material)] : -1;
            out.uvs = set >= 0 ? attr("TEXCOORD_" + str(set), 2) : nullptr;
            out.tangents = pm && pm->normal_image >= 0 ? attr("TANGENT", 4) : nullptr;

            if (mode != TINYGLTF_MODE_TRIANGLES) {
                // strips and fans become an index list, in the specification's vertex order (3.7.2.1):
                // strip triangle i = (v_i, v_{i+1+i%2}, v_{i+2-i%2}), fan triangle i = (v_{i+1}, v_{i+2}, v_0)
                std::vector<uint32_t> seq;
                if (p.indices >= 0) {
                    seq = read_indices(m, p.indices, out.vertex_count, at, /*triangles=*/false);
                } else {
                    seq.resize(out.vertex_count);
                    for (size_t k = 0; k < seq.size(); k++) seq[k] = uint32_t(k);
                }
                if (seq.size() > kMaxCount / 3) throw Fail(at + ": " + str(seq.size()) + " strip or fan vertices, too many");
                if (seq.size() < 3) throw Fail(at + ": a triangle " + (mode == TINYGLTF_MODE_TRIANGLE_FAN ? "fan" : "strip") +
                                                " needs at least 3 vertices, has " + str(seq.size()));
                std::vector<uint32_t> tri;
                tri.reserve(3 * (seq.size() - 2));
                for (size_t k = 0; k + 2 < seq.size(); k++) {
                    if (mode == TINYGLTF_MODE_TRIANGLE_STRIP) {
                        tri.push_back(seq[k]);
                        tri.push_back(seq[k + 1 + k % 2]);
                        tri.push_back(seq[k + 2 - k % 2]);
                    } else {
                        tri.push_back(seq[k + 1]);
                        tri.push_back(seq[k + 2]);
                        tri.push_back(seq[0]);
                    }
                }
                h.uints.push_back(std::move(tri));
                out.indices = h.uints.back().data();
                out.index_count = h.uints.back().size();
            } else if (p.indices >= 0) {
                h.uints.push_back(read_indices(m, p.indices, out.vertex_count, at));
                out.indices = h.uints.back().data();
                out.index_count = h.uints.back().size();
            } else if (out.vertex_count % 3 != 0) {
                throw Fail(at + ": non-indexed vertex count " + str(out.vertex_count) + " is not a multiple of 3");
            }
            h.prims.push_back(out);
        }
    }
    for (size_t mi = 0; mi < m.meshes.size(); mi++) {
        const size_t first = h.mesh_first_prim[mi];
        const size_t end = mi + 1 < m.meshes.size() ? h.mesh_first_prim[mi + 1] : h.prims.size();
        h.meshes.push_back(fv_gltf_mesh{h.prims.data() + first, end - first});
    }
}

void convert_lights(const tinygltf::Model &m, Holder &h, std::vector<char> *supported)
{
    for (size_t i = 0; i < m.lights.size(); i++) {
        const tinygltf::Light &l = m.lights[i];
        const std::string at = "light " + str(i);
        fv_gltf_light out{};
        (*supported)[i] = 1;
        if (l.type == "directional") out.type = 0;
        else if (l.type == "point") out.type = 1;
        else if (l.type == "spot") out.type = 2;
        else (*supported)[i] = 0; // unknown future type: nodes referencing it get no light
        for (int c = 0; c < 3; c++) out.color[c] = 1.0f;
        if (!l.color.empty()) {
            if (l.color.size() != 3) throw Fail(at + ": color needs 3 numbers");
            for (int c = 0; c < 3; c++) out.color[c] = to_float(l.color[size_t(c)], at + " color");
        }
        out.intensity = to_float(l.intensity, at + " intensity");
        out.range = to_float(l.range, at + " range");
        out.inner_cone_rad = to_float(l.spot.innerConeAngle, at + " innerConeAngle");
        out.outer_cone_rad = to_float(l.spot.outerConeAngle, at + " outerConeAngle");
        if (out.intensity < 0 || out.range < 0) throw Fail(at + ": negative intensity or range");
        if (out.type == 2 && !(out.inner_cone_rad >= 0 && out.inner_cone_rad < out.outer_cone_rad &&
                               out.outer_cone_rad <= 1.5707964f))
            throw Fail(at + ": spot cone angles need 0 <= inner < outer <= pi/2");
        h.lights.push_back(out);
    }
}

void convert_nodes(const tinygltf::Model &m, Holder &h, const std::vector<char> &light_ok)
{
    const size_t n = m.nodes.size();
    std::vector<double> local(n * 16);
    std::vector<char> has_parent(n, 0);
    for (size_t i = 0; i < n; i++) {
        const tinygltf::Node &nd = m.nodes[i];
        const std::string at = "node " + str(i);
        if (nd.mesh < -1 || (nd.mesh >= 0 && size_t(nd.mesh) >= m.meshes.size()))
            throw Fail(at + ": mesh " + str(nd.mesh) + " does not exist");
        if (nd.camera < -1 || (nd.camera >= 0 && size_t(nd.camera) >= m.cameras.size()))
            throw Fail(at + ": camera " + str(nd.camera) + " does not exist");
        for (int c : nd.children) {
            if (c < 0 || size_t(c) >= n) throw Fail(at + ": child " + str(c) + " does not exist");
            if (has_parent[size_t(c)]) throw Fail("node " + str(c) + " has more than one parent");
            has_parent[size_t(c)] = 1;
        }
        node_local(nd, i, &local[i * 16]);
    }

    std::vector<int> roots;
    if (m.defaultScene >= 0) {
        if (size_t(m.defaultScene) >= m.scenes.size())
            throw Fail("default scene " + str(m.defaultScene) + " does not exist");
        roots = m.scenes[size_t(m.defaultScene)].nodes;
    } else {
        for (size_t i = 0; i < n; i++)
            if (!has_parent[i]) roots.push_back(int(i));
    }

    // Iterative depth-first walk: deep chains cannot overflow the stack, and a node seen
    // twice (cycle, or listed as root and as child) is an error instead of a hang.
    struct Item {
        int node;
        size_t parent; // index into h.nodes, or SIZE_MAX for roots
    };
    std::vector<char> seen(n, 0);
    std::vector<Item> stack;
    for (size_t r = roots.size(); r-- > 0;) stack.push_back(Item{roots[r], SIZE_MAX});
    static const double identity[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    while (!stack.empty()) {
        const Item it = stack.back();
        stack.pop_back();
        if (it.node < 0 || size_t(it.node) >= n) throw Fail("scene root node " + str(it.node) + " does not exist");
        const size_t ni = size_t(it.node);
        if (seen[ni]) throw Fail("node " + str(ni) + " is reached twice (the node graph is not a tree)");
        seen[ni] = 1;
        const tinygltf::Node &nd = m.nodes[ni];
        fv_gltf_node out{};
        const double *parent = it.parent == SIZE_MAX ? identity : h.nodes[it.parent].world;
        mat_mul(parent, &local[ni * 16], out.world);
        for (double d : out.world)
            if (!std::isfinite(d)) throw Fail("node " + str(ni) + ": world transform is not finite");
        out.mesh = nd.mesh;
        out.camera = (nd.camera >= 0 && m.cameras[size_t(nd.camera)].type == "perspective") ? nd.camera : -1;
        const int li = node_light(nd, ni, m.lights.size());
        out.light = (li >= 0 && light_ok[size_t(li)]) ? li : -1;
        h.nodes.push_back(out);
        const size_t self = h.nodes.size() - 1;
        for (size_t c = nd.children.size(); c-- > 0;) stack.push_back(Item{nd.children[c], self});
    }
}

std::string one_line(std::string s)
{
    for (char &c : s) // tinygltf quotes raw file bytes into some messages
        if ((unsigned char)c < 0x20 || c == 0x7f) c = ' ';
    while (!s.empty() && s.back() == ' ') s.pop_back();
    return s.empty() ? std::string("unknown error") : s;
}

void set_err(char *err, size_t err_len, const std::string &msg)
{
    if (!err || err_len == 0) return;
    std::snprintf(err, err_len, "%s", msg.c_str());
}

// A file that is neither GLB nor JSON is refused from its first bytes, before a multi-gigabyte
// read (a zero-filled 2 GiB .gltf took 12 s to fail).
void check_kind(const char *path)
{
    FILE *f = std::fopen(path, "rb");
    if (!f) throw Fail(std::strerror(errno));
    unsigned char head[256];
    const size_t n = std::fread(head, 1, sizeof head, f);
    std::fclose(f);
    if (n >= 4 && std::memcmp(head, "glTF", 4) == 0) return;
    size_t i = 0;
    if (n >= 3 && head[0] == 0xef && head[1] == 0xbb && head[2] == 0xbf) i = 3; // UTF-8 byte order mark
    while (i < n && (head[i] == ' ' || head[i] == '\t' || head[i] == '\r' || head[i] == '\n')) i++;
    if (i < n && head[i] == '{') return;
    throw Fail(i == n && n == sizeof head ? "not a glTF file (only white space in its first bytes)"
                                          : "not a glTF file (neither a GLB header nor a JSON object)");
}

// ---- what the file says it is, before tinygltf parses it -------------------------------
// tinygltf reports a glTF 1.0 file as "asset object not found" and a Draco-compressed one as an
// invalid bufferView; a user needs to hear the version or the extension. A small scan of the
// top-level JSON members finds asset.version and extensionsRequired first.
struct Scan {
    const unsigned char *s;
    size_t n, i;
    void ws() { while (i < n && (s[i] == ' ' || s[i] == '\t' || s[i] == '\r' || s[i] == '\n')) i++; }
    bool str(std::string *out)
    {
        ws();
        if (i >= n || s[i] != '"') return false;
        for (i++; i < n && s[i] != '"'; i++) {
            if (s[i] == '\\' && ++i >= n) return false;
            if (out && out->size() < 256) out->push_back(char(s[i]));
        }
        return i++ < n;
    }
    bool skip() // one value of any kind
    {
        ws();
        if (i < n && s[i] == '"') return str(nullptr);
        int depth = 0;
        for (; i < n; i++) {
            const unsigned char c = s[i];
            if (c == '"') {
                if (!str(nullptr)) return false;
                i--;
            } else if (c == '{' || c == '[') {
                depth++;
            } else if (c == '}' || c == ']') {
                if (depth-- == 0) return true; // the end of the enclosing container
                if (depth == 0) { i++; return true; }
            } else if (depth == 0 && c == ',') {
                return true;
            }
        }
        return depth == 0;
    }
};

struct Declared {
    bool has_asset = false;
    std::string version;
    std::vector<std::string> required;
};

Declared prescan(const unsigned char *s, size_t n)
{
    Declared d;
    Scan sc{s, n, 0};
    sc.ws();
    if (sc.i >= n || s[sc.i] != '{') return d;
    sc.i++;
    for (;;) {
        std::string key;
        if (!sc.str(&key)) return d;
        sc.ws();
        if (sc.i >= n || s[sc.i++] != ':') return d;
        sc.ws();
        if (key == "asset" && sc.i < n && s[sc.i] == '{') {
            d.has_asset = true;
            sc.i++;
            for (;;) {
                std::string k;
                if (!sc.str(&k)) return d;
                sc.ws();
                if (sc.i >= n || s[sc.i++] != ':') return d;
                sc.ws();
                if (k == "version" && sc.i < n && s[sc.i] == '"') sc.str(&d.version);
                else if (!sc.skip()) return d;
                sc.ws();
                if (sc.i < n && s[sc.i] == ',') { sc.i++; continue; }
                if (sc.i < n && s[sc.i] == '}') { sc.i++; break; }
                return d;
            }
        } else if (key == "extensionsRequired" && sc.i < n && s[sc.i] == '[') {
            sc.i++;
            for (;;) {
                sc.ws();
                if (sc.i < n && s[sc.i] == ']') { sc.i++; break; }
                std::string e;
                if (!sc.str(&e)) return d;
                if (d.required.size() < 64) d.required.push_back(e);
                sc.ws();
                if (sc.i < n && s[sc.i] == ',') sc.i++;
            }
        } else if (!sc.skip()) {
            return d;
        }
        sc.ws();
        if (sc.i < n && s[sc.i] == ',') { sc.i++; continue; }
        return d;
    }
}

// Extensions the file cannot be read without: ours, or ones that only refine materials beyond
// this renderer's shading. Anything else (compression, other texture formats) would give
// silently wrong geometry or textures.
bool extension_supported(const std::string &ext)
{
    return ext == "KHR_lights_punctual" || ext == "KHR_mesh_quantization" || ext == "KHR_texture_transform" ||
           ext.rfind("KHR_materials_", 0) == 0;
}

std::string extension_hint(const std::string &ext)
{
    if (ext == "KHR_draco_mesh_compression" || ext == "EXT_meshopt_compression")
        return " (compressed meshes: export the file without mesh compression)";
    if (ext == "KHR_texture_basisu" || ext == "EXT_texture_webp" || ext == "MSFT_texture_dds")
        return " (texture format: export PNG or JPEG textures)";
    return "";
}

void check_declared(const unsigned char *json, size_t n)
{
    const Declared d = prescan(json, n);
    if (!d.version.empty() && d.version[0] != '2')
        throw Fail("glTF " + d.version + " is not supported, only glTF 2.0 (asset.version \"" + d.version +
                   "\"): convert the file to glTF 2.0");
    if (!d.has_asset)
        throw Fail("no asset object: not a glTF 2.0 file (glTF 1.0 files may lack it: convert them to glTF 2.0)");
    for (const std::string &ext : d.required)
        if (!extension_supported(ext)) throw Fail("required extension " + ext + " is not supported" + extension_hint(ext));
}

fv_gltf_model *load(const char *path, const char *asset_root)
{
    std::vector<unsigned char> file;
    std::string e;
    check_kind(path);
    if (!read_file(path, &file, &e)) throw Fail(e);
    const bool glb = file.size() >= 4 && std::memcmp(file.data(), "glTF", 4) == 0;
    if (glb) {
        uint32_t json_len = 0;
        if (file.size() >= 20) std::memcpy(&json_len, file.data() + 12, 4);
        if (file.size() >= 20 && json_len <= file.size() - 20) {
            if (!json_depth_ok(file.data() + 20, json_len)) throw Fail("JSON nested too deeply");
            check_declared(file.data() + 20, json_len);
        }
    } else {
        if (!json_depth_ok(file.data(), file.size())) throw Fail("JSON nested too deeply");
        check_declared(file.data(), file.size());
    }

    std::string dir(path);
    const size_t slash = dir.find_last_of('/');
    dir = slash == std::string::npos ? std::string() : dir.substr(0, slash);

    FsCtx fsc;
    {
        const std::string root = asset_root ? std::string(asset_root) : (dir.empty() ? std::string(".") : dir);
        char *real = realpath(root.c_str(), nullptr);
        if (!real) throw Fail((asset_root ? "--asset-root " : "scene folder ") + root + ": " + std::strerror(errno));
        fsc.root = real;
        fsc.dir = dir;
        std::free(real);
    }
    tinygltf::Model model;
    tinygltf::TinyGLTF loader;
    loader.SetFsCallbacks(tinygltf::FsCallbacks{&fs_exists, &fs_expand, &fs_read, &fs_write, &fsc});
    ImageHookCtx ictx{&model};
    loader.SetImageLoader(&keep_encoded_image, &ictx);
    std::string terr, twarn;
    const bool ok = glb ? loader.LoadBinaryFromMemory(&model, &terr, &twarn, file.data(), unsigned(file.size()), dir)
                        : loader.LoadASCIIFromString(&model, &terr, &twarn, reinterpret_cast<const char *>(file.data()),
                                                     unsigned(file.size()), dir);
    if (!ok && !fsc.refusal.empty()) throw Fail(fsc.refusal);
    if (!ok) throw Fail("tinygltf: " + (terr.empty() ? std::string("parse failed") : terr));
    file.clear();
    file.shrink_to_fit();

    for (const std::string &ext : model.extensionsRequired) // (the pre-scan saw them already)
        if (!extension_supported(ext)) throw Fail("required extension " + ext + " is not supported" + extension_hint(ext));

    std::unique_ptr<Holder> h(new Holder);
    std::vector<char> image_used(model.images.size(), 0), light_ok(model.lights.size(), 0);
    convert_materials(model, *h, &image_used);
    decode_images(model, *h, image_used);
    convert_meshes(model, *h);
    convert_lights(model, *h, &light_ok);
    convert_nodes(model, *h, light_ok);

    fv_gltf_model &p = h->pub;
    if (h->skipped_prims)
        h->warning = "skipped " + str(h->skipped_prims) + " point or line primitive" + (h->skipped_prims > 1 ? "s" : "") +
                     " (only triangles are rendered)";
    p.warning = h->warning.c_str();
    p.meshes = h->meshes.data(), p.mesh_count = h->meshes.size();
    p.nodes = h->nodes.data(), p.node_count = h->nodes.size();
    p.materials = h->materials.data(), p.material_count = h->materials.size();
    p.images = h->images.data(), p.image_count = h->images.size();
    p.lights = h->lights.data(), p.light_count = h->lights.size();
    p.impl = h.get();
    return &h.release()->pub;
}

} // namespace

extern "C" fv_gltf_model *fv_gltf_load(const char *path, const char *asset_root, char *err, size_t err_len)
{
    set_err(err, err_len, "");
    std::string msg;
    try {
        if (!path) throw Fail("no path");
        return load(path, asset_root);
    } catch (const std::bad_alloc &) {
        msg = "out of memory";
    } catch (const std::exception &ex) {
        msg = ex.what();
    } catch (...) {
        msg = "unknown exception";
    }
    set_err(err, err_len, one_line(msg));
    return nullptr;
}

extern "C" void fv_gltf_free(fv_gltf_model *m)
{
    if (m) delete static_cast<Holder *>(m->impl);
}
