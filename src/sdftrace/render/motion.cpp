#include "sdftrace/render/motion.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

#include "sdftrace/field/transforms.h"

namespace sdft {

namespace {

// The top-level objects: the root union's children, or the root itself.
std::vector<NodePtr> topLevel(const NodePtr& root) {
    if (!root) return {};
    if (root->kind == NodeKind::Union) return root->children;
    return {root};
}

// A Rotate step's matrix (row-major, as Node::params).
Mat3 rotationOf(const Placement::Step& s) {
    Mat3 r;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) r.m[i][j] = s.k[3 * i + j];
    return r;
}

}  // namespace

bool isPlacementKind(NodeKind k) {
    return k == NodeKind::Translate || k == NodeKind::Rotate || k == NodeKind::Scale;
}

void Placement::append(const Node& n) {
    Step s{n.kind, {}};
    std::copy(n.params.begin(), n.params.begin() + std::min<size_t>(9, n.params.size()), s.k);
    steps.push_back(s);
}

// A node's params are its forward transform (node.h): world = offset + local, R local, s * local.
Vec3 Placement::toLocal(Vec3 p) const {
    for (const Step& s : steps) {
        switch (s.kind) {
            case NodeKind::Translate:
                p = p - Vec3(s.k[0], s.k[1], s.k[2]);
                break;
            case NodeKind::Rotate:
                p = rotationOf(s).transposed() * p;
                break;
            default:  // Scale
                p = p / Vec3(s.k[0], s.k[1], s.k[2]);
        }
    }
    return p;
}

Vec3 Placement::toWorld(Vec3 p) const {
    for (auto it = steps.rbegin(); it != steps.rend(); ++it) {
        const Step& s = *it;
        switch (s.kind) {
            case NodeKind::Translate:
                p = p + Vec3(s.k[0], s.k[1], s.k[2]);
                break;
            case NodeKind::Rotate:
                p = rotationOf(s) * p;
                break;
            default:
                p = p * Vec3(s.k[0], s.k[1], s.k[2]);
        }
    }
    return p;
}

Vec3 Placement::normalToWorld(Vec3 n) const {
    for (auto it = steps.rbegin(); it != steps.rend(); ++it) {
        const Step& s = *it;
        if (s.kind == NodeKind::Rotate) {
            n = rotationOf(s) * n;
        } else if (s.kind == NodeKind::Scale) {
            n = n / Vec3(s.k[0], s.k[1], s.k[2]);
        }
    }
    return normalize(n);
}

bool Placement::sameShape(const Placement& o) const {
    if (steps.size() != o.steps.size()) return false;
    for (size_t i = 0; i < steps.size(); ++i)
        if (steps[i].kind != o.steps[i].kind) return false;
    return true;
}

Placement placementOf(const NodePtr& n, NodePtr* shape) {
    Placement pl;
    NodePtr cur = n;
    while (cur && isPlacementKind(cur->kind) && cur->children.size() == 1) {
        pl.append(*cur);
        cur = cur->children[0];
    }
    if (shape) *shape = cur;
    return pl;
}

SceneMotion::SceneMotion(const NodePtr& previousRoot, const NodePtr& currentRoot) {
    const std::vector<NodePtr> now = topLevel(currentRoot), before = topLevel(previousRoot);
    const bool matched = now.size() == before.size();
    for (size_t i = 0; i < now.size(); ++i) {
        MovingObject o;
        o.field = compileTape(now[i]);
        const Bounds3 b = nodeBounds(*now[i]);
        o.boundsDominate = dominatesBounds(*now[i]) && b.finite();
        const float box[6] = {b.lo.x, b.lo.y, b.lo.z, b.hi.x, b.hi.y, b.hi.z};
        std::copy(box, box + 6, o.box);
        o.now = placementOf(now[i]);
        if (matched) {
            o.before = placementOf(before[i]);
            o.rigid = o.before.sameShape(o.now) && !o.now.steps.empty();
        }
        m_objects.push_back(std::move(o));
    }
}

int SceneMotion::objectAt(Vec3 p) const {
    if (m_objects.size() == 1) return 0;
    int best = -1;
    float bestValue = INFINITY;
    for (size_t i = 0; i < m_objects.size(); ++i) {
        const MovingObject& o = m_objects[i];
        if (o.boundsDominate && xform::boxDistance(p, o.box) >= bestValue) continue;
        const float v = o.field.eval(p);
        if (v < bestValue) {
            bestValue = v;
            best = static_cast<int>(i);
        }
    }
    return best;
}

Vec3 SceneMotion::previousPosition(int object, Vec3 p) const {
    if (object < 0 || static_cast<size_t>(object) >= m_objects.size()) return p;
    const MovingObject& o = m_objects[static_cast<size_t>(object)];
    if (!o.rigid) return p;
    return o.before.toWorld(o.now.toLocal(p));
}

MotionVectors motionVectors(const std::vector<float>& depth, const CameraDesc& nowDesc,
                            const float jitter[2], const CameraDesc& beforeDesc,
                            const SceneMotion* motion) {
    const int w = nowDesc.width, h = nowDesc.height;
    const size_t n = static_cast<size_t>(w) * h;
    MotionVectors mv;
    mv.motion.assign(2 * n, 0.0f);
    mv.objects.assign(n, -1);
    mv.depthBefore.assign(n, INFINITY);
    mv.visibleBefore.assign(n, 1);
    const Camera now(nowDesc), before(beforeDesc);
    tbb::parallel_for(tbb::blocked_range<int>(0, h), [&](const tbb::blocked_range<int>& rows) {
        for (int y = rows.begin(); y != rows.end(); ++y)
            for (int x = 0; x < w; ++x) {
                const size_t i = static_cast<size_t>(y) * w + x;
                if (!std::isfinite(depth[i])) continue;  // a miss: the background stays put
                const Vec3 p =
                    now.rayThrough(x + 0.5f + jitter[0], y + 0.5f + jitter[1]).at(depth[i]);
                const int k = motion ? motion->objectAt(p) : 0;
                mv.objects[i] = k;
                const Vec3 q = motion ? motion->previousPosition(k, p) : p;
                float px = 0, py = 0;
                if (!before.project(q, px, py)) {
                    mv.visibleBefore[i] = 0;
                    continue;
                }
                // From the sample's own position, so a still camera gives zero motion whatever
                // the jitter: the history is an image of pixel centres.
                mv.motion[2 * i] = px - (x + 0.5f + jitter[0]);
                mv.motion[2 * i + 1] = py - (y + 0.5f + jitter[1]);
                mv.depthBefore[i] = length(q - beforeDesc.eye);
            }
    });
    return mv;
}

}  // namespace sdft
