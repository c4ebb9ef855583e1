#include "sdftrace/io/mesh_animation.h"

#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <algorithm>
#include <assimp/Importer.hpp>
#include <cmath>
#include <filesystem>
#include <map>

#include "sdftrace/core/error.h"
#include "sdftrace/core/macros.h"
#include "sdftrace/io/mesh_readers.h"

namespace sdft {

namespace {

template <class Key>
double keyTime(const Key& k) {
    return k.mTime;
}

// The pair of keys around `tick` and the blend between them (clamped at the ends).
template <class Key>
void bracket(const std::vector<Key>& keys, double tick, size_t& a, size_t& b, float& u) {
    a = b = 0;
    u = 0;
    if (keys.size() < 2 || tick <= keyTime(keys.front())) return;
    if (tick >= keyTime(keys.back())) {
        a = b = keys.size() - 1;
        return;
    }
    auto it = std::upper_bound(keys.begin(), keys.end(), tick,
                               [](double t, const Key& k) { return t < keyTime(k); });
    // Key times are finite and increasing (readClip); the clamp keeps a and b keys regardless.
    b = std::clamp<size_t>(static_cast<size_t>(it - keys.begin()), 1, keys.size() - 1);
    a = b - 1;
    const double span = keyTime(keys[b]) - keyTime(keys[a]);
    u = span > 0 ? static_cast<float>((tick - keyTime(keys[a])) / span) : 0.0f;
}

struct NodeChannel {
    int node = -1;
    std::vector<aiVectorKey> positions, scalings;
    std::vector<aiQuatKey> rotations;
};

struct MorphKey {
    double mTime = 0;
    std::vector<std::pair<unsigned, double>> weights;  // (target, weight)
};

struct MorphChannel {
    std::string node;  // assimp names a morph channel after the node holding the mesh
    std::vector<MorphKey> keys;
};

struct Clip {
    MeshClip info;
    double ticksPerSecond = 25;
    std::vector<NodeChannel> channels;
    std::vector<MorphChannel> morphs;
};

struct Bone {
    int node = -1;  // -1: the file names a joint it does not have (it stays in its bind pose)
    aiMatrix4x4 offset;
    std::vector<std::pair<unsigned, float>> weights;  // (vertex, weight)
};

struct Mesh {
    std::vector<aiVector3D> positions;
    std::vector<std::array<uint32_t, 3>> triangles;
    std::vector<Bone> bones;
    std::vector<std::vector<aiVector3D>> targets;  // morph targets' absolute positions
    std::vector<float> targetWeights;              // without a morph channel
};

struct Node {
    std::string name;
    int parent = -1;  // before this node in `nodes`
    aiMatrix4x4 local;
    std::vector<unsigned> meshes;
};

}  // namespace

struct AnimatedMesh::Impl {
    std::string path;
    std::vector<Node> nodes;  // parents first
    std::vector<Mesh> meshes;
    std::vector<Clip> clips;
    std::vector<MeshClip> infos;
};

namespace {

void addNodes(const aiNode* n, int parent, std::vector<Node>& out) {
    Node node;
    node.name = n->mName.C_Str();
    node.parent = parent;
    node.local = n->mTransformation;
    node.meshes.assign(n->mMeshes, n->mMeshes + n->mNumMeshes);
    out.push_back(std::move(node));
    const int self = static_cast<int>(out.size()) - 1;
    for (unsigned i = 0; i < n->mNumChildren; ++i) addNodes(n->mChildren[i], self, out);
}

int findNode(const std::vector<Node>& nodes, const std::string& name) {
    for (size_t i = 0; i < nodes.size(); ++i)
        if (nodes[i].name == name) return static_cast<int>(i);
    return -1;
}

void checkFinite(const aiVector3D& p, const std::string& path, const std::string& what) {
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
        throw InputError(path + ": " + what + " is not finite");
}

Mesh readMesh(const aiMesh* m, const std::vector<Node>& nodes, const std::string& path) {
    Mesh mesh;
    mesh.positions.assign(m->mVertices, m->mVertices + m->mNumVertices);
    for (unsigned v = 0; v < m->mNumVertices; ++v)
        checkFinite(mesh.positions[v], path, "vertex " + std::to_string(v));
    for (unsigned f = 0; f < m->mNumFaces; ++f) {
        const aiFace& face = m->mFaces[f];
        if (face.mNumIndices != 3 || !face.mIndices) continue;  // points and lines
        for (int k = 0; k < 3; ++k)
            if (face.mIndices[k] >= m->mNumVertices)
                throw InputError(path + ": face " + std::to_string(f) + " uses vertex " +
                                 std::to_string(face.mIndices[k]) + " of " +
                                 std::to_string(m->mNumVertices));
        mesh.triangles.push_back({face.mIndices[0], face.mIndices[1], face.mIndices[2]});
    }
    for (unsigned b = 0; b < m->mNumBones; ++b) {
        const aiBone* bone = m->mBones[b];
        Bone out;
        out.node = findNode(nodes, bone->mName.C_Str());
        out.offset = bone->mOffsetMatrix;
        for (unsigned w = 0; w < bone->mNumWeights; ++w) {
            const aiVertexWeight& vw = bone->mWeights[w];
            if (vw.mVertexId < m->mNumVertices && std::isfinite(vw.mWeight) && vw.mWeight > 0)
                out.weights.emplace_back(vw.mVertexId, vw.mWeight);
        }
        mesh.bones.push_back(std::move(out));
    }
    for (unsigned a = 0; a < m->mNumAnimMeshes; ++a) {
        const aiAnimMesh* am = m->mAnimMeshes[a];
        std::vector<aiVector3D> target = mesh.positions;
        if (am->mVertices && am->mNumVertices == m->mNumVertices) {
            target.assign(am->mVertices, am->mVertices + am->mNumVertices);
            for (unsigned v = 0; v < am->mNumVertices; ++v)
                checkFinite(target[v], path,
                            "morph target " + std::to_string(a) + " vertex " + std::to_string(v));
        }
        mesh.targets.push_back(std::move(target));
        mesh.targetWeights.push_back(std::isfinite(am->mWeight) ? am->mWeight : 0.0f);
    }
    return mesh;
}

// Key times must be finite and never decrease (glTF requires increasing ones; assimp passes
// what the file holds): sampling looks keys up by binary search.
template <class Key>
void checkKeyTimes(const Key* keys, unsigned count, const std::string& path,
                   const std::string& what) {
    if (!keys && count) throw InputError(path + ": " + what + ": keys missing");
    for (unsigned k = 0; k < count; ++k) {
        const double t = keyTime(keys[k]);
        if (!std::isfinite(t) || (k > 0 && t < keyTime(keys[k - 1])))
            throw InputError(
                path + ": " + what + ": key " + std::to_string(k) + "'s time " + std::to_string(t) +
                (std::isfinite(t) ? " comes before the key's before it" : " is not finite") +
                " (accepted: finite, increasing times)");
    }
}

Clip readClip(const aiAnimation* a, const std::vector<Node>& nodes, const std::string& path) {
    Clip clip;
    clip.info.name = a->mName.C_Str();
    // assimp leaves the rate 0 where a format stores none; 25 ticks per second is its convention.
    clip.ticksPerSecond = a->mTicksPerSecond > 0 ? a->mTicksPerSecond : 25.0;
    clip.info.duration = std::max(0.0, a->mDuration / clip.ticksPerSecond);
    for (unsigned c = 0; c < a->mNumChannels; ++c) {
        const aiNodeAnim* ch = a->mChannels[c];
        NodeChannel out;
        out.node = findNode(nodes, ch->mNodeName.C_Str());
        if (out.node < 0) continue;  // animates a node the file does not have
        const std::string what = "animation '" + std::string(a->mName.C_Str()) + "', node '" +
                                 ch->mNodeName.C_Str() + "'";
        checkKeyTimes(ch->mPositionKeys, ch->mNumPositionKeys, path, what + " translation");
        checkKeyTimes(ch->mRotationKeys, ch->mNumRotationKeys, path, what + " rotation");
        checkKeyTimes(ch->mScalingKeys, ch->mNumScalingKeys, path, what + " scale");
        out.positions.assign(ch->mPositionKeys, ch->mPositionKeys + ch->mNumPositionKeys);
        out.rotations.assign(ch->mRotationKeys, ch->mRotationKeys + ch->mNumRotationKeys);
        out.scalings.assign(ch->mScalingKeys, ch->mScalingKeys + ch->mNumScalingKeys);
        clip.channels.push_back(std::move(out));
    }
    for (unsigned c = 0; c < a->mNumMorphMeshChannels; ++c) {
        const aiMeshMorphAnim* ch = a->mMorphMeshChannels[c];
        MorphChannel out;
        out.node = ch->mName.C_Str();
        checkKeyTimes(ch->mKeys, ch->mNumKeys, path,
                      "animation '" + std::string(a->mName.C_Str()) + "', morph weights of '" +
                          out.node + "'");
        for (unsigned k = 0; k < ch->mNumKeys; ++k) {
            const aiMeshMorphKey& key = ch->mKeys[k];
            MorphKey mk;
            mk.mTime = key.mTime;
            for (unsigned i = 0; i < key.mNumValuesAndWeights; ++i)
                mk.weights.emplace_back(key.mValues[i], key.mWeights[i]);
            out.keys.push_back(std::move(mk));
        }
        clip.morphs.push_back(std::move(out));
    }
    clip.info.morph = !clip.morphs.empty();
    return clip;
}

aiVector3D sampleVector(const std::vector<aiVectorKey>& keys, double tick, aiVector3D fallback) {
    if (keys.empty()) return fallback;
    size_t a = 0, b = 0;
    float u = 0;
    bracket(keys, tick, a, b, u);
    return keys[a].mValue + (keys[b].mValue - keys[a].mValue) * u;
}

aiQuaternion sampleRotation(const std::vector<aiQuatKey>& keys, double tick,
                            aiQuaternion fallback) {
    if (keys.empty()) return fallback;
    size_t a = 0, b = 0;
    float u = 0;
    bracket(keys, tick, a, b, u);
    aiQuaternion q;
    aiQuaternion::Interpolate(q, keys[a].mValue, keys[b].mValue, u);  // slerp
    return q.Normalize();
}

// The morph weights of a mesh held by `node` at `tick`, or its static weights.
std::vector<float> morphWeights(const Clip& clip, const Mesh& mesh, const std::string& node,
                                double tick) {
    std::vector<float> w = mesh.targetWeights;
    for (const MorphChannel& ch : clip.morphs) {
        if (ch.node != node || ch.keys.empty()) continue;
        size_t a = 0, b = 0;
        float u = 0;
        bracket(ch.keys, tick, a, b, u);
        std::fill(w.begin(), w.end(), 0.0f);
        for (const auto& [t, v] : ch.keys[a].weights)
            if (t < w.size()) w[t] += static_cast<float>(v) * (1 - u);
        for (const auto& [t, v] : ch.keys[b].weights)
            if (t < w.size()) w[t] += static_cast<float>(v) * u;
    }
    return w;
}

}  // namespace

AnimatedMesh AnimatedMesh::load(const std::string& path) {
    if (!std::filesystem::exists(path))
        throw InputError(path + ": cannot open mesh file (does it exist?)");
    precheckForAssimp(path);
    Assimp::Importer importer;
    // Triangulated; the hierarchy kept (no pre-transformed vertices): joints and animated nodes
    // move parts of it. Joint weights beyond 4 per vertex are kept as the file has them.
    // The scene validated first (counts, indices, pointers) as loadMesh's is.
    const aiScene* scene =
        importer.ReadFile(path, aiProcess_ValidateDataStructure | aiProcess_Triangulate);
    if (!scene || !scene->mRootNode || (scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE)) {
        std::string why = importer.GetErrorString();
        std::replace(why.begin(), why.end(), '\n', ' ');
        throw InputError(path + ": cannot read mesh (" + why +
                         "); animated meshes: glTF, Collada, FBX, DirectX .x");
    }
    auto impl = std::make_shared<Impl>();
    impl->path = path;
    addNodes(scene->mRootNode, -1, impl->nodes);
    for (unsigned m = 0; m < scene->mNumMeshes; ++m)
        impl->meshes.push_back(readMesh(scene->mMeshes[m], impl->nodes, path));
    for (unsigned a = 0; a < scene->mNumAnimations; ++a) {
        Clip clip = readClip(scene->mAnimations[a], impl->nodes, path);
        // Skeletal when it moves nodes (joints, or nodes holding meshes) of this file.
        clip.info.skeletal = !clip.channels.empty();
        if (!clip.info.skeletal && !clip.info.morph) continue;  // animates cameras or lights
        impl->infos.push_back(clip.info);
        impl->clips.push_back(std::move(clip));
    }
    AnimatedMesh out;
    out.m_impl = std::move(impl);
    return out;
}

const std::vector<MeshClip>& AnimatedMesh::clips() const { return m_impl->infos; }

int AnimatedMesh::clipIndex(const std::string& name) const {
    for (size_t i = 0; i < m_impl->infos.size(); ++i)
        if (m_impl->infos[i].name == name) return static_cast<int>(i);
    return -1;
}

std::string AnimatedMesh::clipList() const {
    std::string s;
    for (size_t i = 0; i < m_impl->infos.size(); ++i) {
        if (i) s += ", ";
        s += std::to_string(i) +
             (m_impl->infos[i].name.empty() ? " (unnamed)" : " '" + m_impl->infos[i].name + "'");
    }
    return s;
}

TriangleMesh AnimatedMesh::pose(int clipIndex, double seconds, MeshReport* report) const {
    const Impl& im = *m_impl;
    SDFT_CHECK(clipIndex >= 0 && static_cast<size_t>(clipIndex) < im.clips.size());
    const Clip& clip = im.clips[static_cast<size_t>(clipIndex)];
    const double tick = std::clamp(seconds, 0.0, clip.info.duration) * clip.ticksPerSecond;
    // Node transforms: the animated ones sampled (translation, rotation, scale), then composed
    // from the root down.
    std::vector<aiMatrix4x4> local(im.nodes.size()), global(im.nodes.size());
    for (size_t i = 0; i < im.nodes.size(); ++i) local[i] = im.nodes[i].local;
    for (const NodeChannel& ch : clip.channels) {
        aiVector3D s, t;
        aiQuaternion r;
        im.nodes[static_cast<size_t>(ch.node)].local.Decompose(s, r, t);
        local[static_cast<size_t>(ch.node)] =
            aiMatrix4x4(sampleVector(ch.scalings, tick, s), sampleRotation(ch.rotations, tick, r),
                        sampleVector(ch.positions, tick, t));
    }
    for (size_t i = 0; i < im.nodes.size(); ++i)
        global[i] = im.nodes[i].parent < 0
                        ? local[i]
                        : global[static_cast<size_t>(im.nodes[i].parent)] * local[i];

    std::vector<Vec3> positions;
    std::vector<std::array<uint32_t, 3>> triangles;
    for (size_t n = 0; n < im.nodes.size(); ++n) {
        for (unsigned m : im.nodes[n].meshes) {
            if (m >= im.meshes.size()) continue;
            const Mesh& mesh = im.meshes[m];
            std::vector<aiVector3D> v = mesh.positions;
            // Morph targets first (glTF 2.0 §3.7.2.2), then the skin.
            const std::vector<float> w = morphWeights(clip, mesh, im.nodes[n].name, tick);
            for (size_t t = 0; t < mesh.targets.size(); ++t)
                if (w[t] != 0)
                    for (size_t i = 0; i < v.size(); ++i)
                        v[i] += (mesh.targets[t][i] - mesh.positions[i]) * w[t];
            std::vector<aiVector3D> out(v.size(), aiVector3D(0, 0, 0));
            if (mesh.bones.empty()) {
                for (size_t i = 0; i < v.size(); ++i) out[i] = global[n] * v[i];
            } else {
                std::vector<float> total(v.size(), 0.0f);
                for (const Bone& b : mesh.bones) {
                    // A joint the hierarchy lacks stays where it was bound.
                    const aiMatrix4x4 skin =
                        b.node < 0 ? aiMatrix4x4() : global[static_cast<size_t>(b.node)] * b.offset;
                    for (const auto& [vi, wt] : b.weights) {
                        out[vi] += (skin * v[vi]) * wt;
                        total[vi] += wt;
                    }
                }
                // Weights normalised per vertex; a vertex no joint holds moves with the node.
                for (size_t i = 0; i < v.size(); ++i)
                    out[i] = total[i] > 0 ? out[i] / total[i] : global[n] * v[i];
            }
            const uint32_t base = static_cast<uint32_t>(positions.size());
            for (const aiVector3D& p : out) {
                checkFinite(p, im.path, "a posed vertex");
                positions.push_back({p.x, p.y, p.z});
            }
            for (const auto& t : mesh.triangles)
                triangles.push_back({base + t[0], base + t[1], base + t[2]});
        }
    }
    MeshReport unused;
    MeshReport& r = report ? *report : unused;
    if (std::string problem = meshRangeProblem({positions, triangles}); !problem.empty())
        throw InputError(im.path + ": posed at " + std::to_string(seconds) + " s: " + problem);
    TriangleMesh mesh = cleanMesh(positions, triangles, r);
    if (mesh.triangles.empty())
        throw InputError(im.path + ": the mesh has no (non-degenerate) triangles");
    return mesh;
}

}  // namespace sdft
