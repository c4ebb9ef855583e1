#include <assimp/BaseImporter.h>

#include <algorithm>
#include <assimp/Importer.hpp>
#include <cctype>
#include <cstring>
#include <functional>
#include <nlohmann/json.hpp>
#include <set>
#include <string_view>
#include <vector>

#include "sdftrace/core/error.h"
#include "sdftrace/io/mapped_file.h"
#include "sdftrace/io/mesh_readers.h"

namespace sdft {

namespace {

// assimp picks the importers whose extension ends the file's name; with none, or with several
// that all decline the content by its signature, it tries every importer on the bytes (and some
// read damaged ones out of bounds). So: an importer must claim the extension, and where several
// do, one of them must recognise the content.
void refuseGuessing(const std::string& path) {
    std::string name = path;
    std::transform(name.begin(), name.end(), name.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    Assimp::Importer importer;
    std::vector<Assimp::BaseImporter*> claiming;
    for (size_t i = 0; i < importer.GetImporterCount(); ++i) {
        Assimp::BaseImporter* imp = importer.GetImporter(i);
        std::set<std::string> extensions;
        if (imp) imp->GetExtensionList(extensions);
        for (const std::string& e : extensions) {
            const std::string dotted = "." + e;
            if (name.size() > dotted.size() &&
                name.compare(name.size() - dotted.size(), dotted.size(), dotted) == 0) {
                claiming.push_back(imp);
                break;
            }
        }
    }
    const std::string ext = lowerExtension(path);
    if (claiming.empty())
        throw InputError(path + ": unknown mesh format '" + ext +
                         "' (accepted: .obj, .ply, .stl, .off, .gltf, .glb and the other "
                         "extensions assimp reads, such as .dae, .fbx, .3ds, .x)");
    if (claiming.size() == 1) return;
    for (Assimp::BaseImporter* imp : claiming)
        if (imp->CanRead(path, importer.GetIOHandler(), true)) return;
    throw InputError(path + ": not a readable " + ext +
                     " file: no importer of the extension recognises its content (a damaged "
                     "file?)");
}

// Every index a glTF 2.0 document holds, held to the array it names, and skins given their
// inverse bind matrices: assimp 5.2 dereferences a missing inverseBindMatrices accessor (which
// the format allows) and indices out of range instead of failing. Returns what is wrong, or ""
// (glTF 1.0 documents, whose references are names, are left to assimp).
class GltfReferences {
  public:
    explicit GltfReferences(const nlohmann::json& doc) : m_doc(doc) {}

    std::string problem() {
        if (!m_doc.is_object()) return "the document is not a JSON object";
        const auto asset = m_doc.find("asset");
        if (asset != m_doc.end() && asset->is_object()) {
            const auto v = asset->find("version");
            if (v != asset->end() && v->is_string() && v->get<std::string>().rfind("1", 0) == 0)
                return "";
        }
        const size_t accessors = count("accessors"), nodes = count("nodes");
        field(m_doc, "", "scene", "scenes", count("scenes"));
        each("accessors", [&](const nlohmann::json& a, const std::string& at) {
            field(a, at, "bufferView", "bufferViews", count("bufferViews"));
        });
        each("bufferViews", [&](const nlohmann::json& v, const std::string& at) {
            required(v, at, "buffer");
            field(v, at, "buffer", "buffers", count("buffers"));
        });
        each("meshes", [&](const nlohmann::json& m, const std::string& at) {
            required(m, at, "primitives");
            list(m, at, "primitives", [&](const nlohmann::json& prim, const std::string& pat) {
                field(prim, pat, "indices", "accessors", accessors);
                field(prim, pat, "material", "materials", count("materials"));
                named(prim, pat, "attributes", accessors);
                list(prim, pat, "targets", [&](const nlohmann::json& t, const std::string& tat) {
                    named(t, tat, "", accessors);
                });
            });
        });
        each("nodes", [&](const nlohmann::json& n, const std::string& at) {
            field(n, at, "mesh", "meshes", count("meshes"));
            field(n, at, "skin", "skins", count("skins"));
            field(n, at, "camera", "cameras", count("cameras"));
            indices(n, at, "children", "nodes", nodes);
        });
        each("skins", [&](const nlohmann::json& k, const std::string& at) {
            required(k, at, "joints");
            indices(k, at, "joints", "nodes", nodes);
            field(k, at, "skeleton", "nodes", nodes);
            if (m_problem.empty() && !k.contains("inverseBindMatrices"))
                m_problem = at +
                            " has no inverseBindMatrices (identity matrices by the format, "
                            "but assimp 5.2, which reads glTF here, cannot read such a skin)";
            field(k, at, "inverseBindMatrices", "accessors", accessors);
        });
        each("scenes", [&](const nlohmann::json& sc, const std::string& at) {
            indices(sc, at, "nodes", "nodes", nodes);
        });
        each("animations", [&](const nlohmann::json& a, const std::string& at) {
            required(a, at, "channels");
            required(a, at, "samplers");
            const size_t samplers =
                a.is_object() && a.contains("samplers") && a["samplers"].is_array()
                    ? a["samplers"].size()
                    : 0;
            list(a, at, "samplers", [&](const nlohmann::json& sm, const std::string& sat) {
                required(sm, sat, "input");
                required(sm, sat, "output");
                field(sm, sat, "input", "accessors", accessors);
                field(sm, sat, "output", "accessors", accessors);
            });
            list(a, at, "channels", [&](const nlohmann::json& ch, const std::string& cat) {
                required(ch, cat, "sampler");
                required(ch, cat, "target");
                field(ch, cat, "sampler", "samplers of the animation", samplers);
                if (ch.is_object() && ch.contains("target"))
                    field(ch["target"], cat + "/target", "node", "nodes", nodes);
            });
        });
        return m_problem;
    }

  private:
    using Check = std::function<void(const nlohmann::json&, const std::string&)>;

    size_t count(const char* array) const {
        const auto a = m_doc.find(array);
        return a != m_doc.end() && a->is_array() ? a->size() : 0;
    }
    void value(const nlohmann::json& v, const std::string& at, const char* array, size_t size) {
        if (m_problem.empty() && (!v.is_number_unsigned() || v.get<uint64_t>() >= size))
            m_problem = at + " is " + v.dump().substr(0, 32) + ", not an index of " + array + " (" +
                        std::to_string(size) + " of them)";
    }
    void field(const nlohmann::json& obj, const std::string& at, const char* key, const char* array,
               size_t size) {
        if (!obj.is_object()) return;
        const auto v = obj.find(key);
        if (v != obj.end()) value(*v, at + "/" + key, array, size);
    }
    void required(const nlohmann::json& obj, const std::string& at, const char* key) {
        if (m_problem.empty() && (!obj.is_object() || !obj.contains(key)))
            m_problem = at + " has no " + key;
    }
    // obj[key] (or obj itself when key is empty) maps names to accessor indices.
    void named(const nlohmann::json& obj, const std::string& at, const char* key, size_t size) {
        if (!obj.is_object()) return;
        const nlohmann::json* map = &obj;
        std::string mat = at;
        if (*key) {
            const auto it = obj.find(key);
            if (it == obj.end()) return;
            map = &*it;
            mat += std::string("/") + key;
        }
        if (!map->is_object()) {
            if (m_problem.empty()) m_problem = mat + " is not an object";
            return;
        }
        for (const auto& [name, v] : map->items()) value(v, mat + "/" + name, "accessors", size);
    }
    void indices(const nlohmann::json& obj, const std::string& at, const char* key,
                 const char* array, size_t size) {
        list(obj, at, key,
             [&](const nlohmann::json& v, const std::string& vat) { value(v, vat, array, size); });
    }
    void list(const nlohmann::json& obj, const std::string& at, const char* key, const Check& f) {
        if (!obj.is_object()) return;
        const auto a = obj.find(key);
        if (a == obj.end()) return;
        if (!a->is_array()) {
            if (m_problem.empty()) m_problem = at + "/" + key + " is not an array";
            return;
        }
        for (size_t i = 0; i < a->size() && m_problem.empty(); ++i)
            f((*a)[i], at + "/" + key + "/" + std::to_string(i));
    }
    void each(const char* array, const Check& f) { list(m_doc, "", array, f); }

    const nlohmann::json& m_doc;
    std::string m_problem;
};

void checkGltfDocument(std::string_view json, const std::string& path, const char* format) {
    const nlohmann::json doc = nlohmann::json::parse(json, nullptr, false);
    if (doc.is_discarded())
        throw InputError(path + ": " + format + ": not valid JSON (a damaged file?)");
    const std::string problem = GltfReferences(doc).problem();
    if (!problem.empty()) throw InputError(path + ": " + format + ": " + problem);
}

}  // namespace

void precheckForAssimp(const std::string& path) {
    const std::string ext = lowerExtension(path);
    if (ext != ".glb" && ext != ".gltf") return refuseGuessing(path);
    const MappedFile file(path);
    const char* d = file.data();
    const size_t n = file.size();
    auto fail = [&](const std::string& what) { throw InputError(path + ": " + what); };
    if (ext == ".gltf") {
        checkGltfDocument(std::string_view(d, n), path, "glTF");
        return refuseGuessing(path);
    }
    uint32_t header[3] = {0, 0, 0};
    if (n < 20) fail("GLB: " + std::to_string(n) + " bytes, shorter than a GLB header");
    std::memcpy(header, d, sizeof header);
    if (std::memcmp(d, "glTF", 4) != 0 || header[1] != 2)
        fail("GLB: not a glTF 2.0 binary (no 'glTF' version 2 header)");
    if (header[2] != n)
        fail("GLB: its header says " + std::to_string(header[2]) + " bytes, the file has " +
             std::to_string(n) + " (is it cut short?)");
    size_t at = 12;
    for (int chunk = 0; at < n; ++chunk) {
        uint32_t c[2];
        if (n - at < 8) fail("GLB: a chunk header runs past the end of the file");
        std::memcpy(c, d + at, sizeof c);
        if (c[0] > n - at - 8)
            fail("GLB: chunk " + std::to_string(chunk) + " of " + std::to_string(c[0]) +
                 " bytes runs past the end of the file");
        if (chunk == 0 && c[1] != 0x4E4F534Au) fail("GLB: its first chunk is not JSON");
        if (chunk == 0) checkGltfDocument(std::string_view(d + at + 8, c[0]), path, "GLB");
        at += 8 + static_cast<size_t>(c[0]);
    }
    refuseGuessing(path);
}

}  // namespace sdft
