#include "sdftrace/bake/lbvh.h"

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <atomic>

#include "sdftrace/core/error.h"
#include "sdftrace/exec/thread_arena.h"

namespace sdft {

LbvhFrame lbvhFrame(const TriangleMesh& mesh) {
    Bounds3 b;
    for (const auto& t : mesh.triangles)
        for (uint32_t v : t) b.include(mesh.positions[v]);
    LbvhFrame f;
    f.lo = b.lo;
    const Vec3 e = b.extent();
    for (int axis = 0; axis < 3; ++axis) f.invExtent[axis] = e[axis] > 0 ? 1.0f / e[axis] : 0.0f;
    return f;
}

Lbvh::Lbvh(const TriangleMesh& mesh, int threads) {
    if (mesh.triangles.size() > static_cast<size_t>(kMaxLbvhTriangles))
        throw InputError("mesh: " + std::to_string(mesh.triangles.size()) +
                         " triangles; the LBVH takes at most " + std::to_string(kMaxLbvhTriangles));
    const int n = static_cast<int>(mesh.triangles.size());
    if (n == 0) return;
    const LbvhFrame frame = lbvhFrame(mesh);
    ThreadArena arena(threads);
    arena.execute([&] {
        // Keys, sorted (they are unique, so any sort gives the GPU's radix-sorted order).
        std::vector<uint64_t> keys(n);
        tbb::parallel_for(0, n, [&](int t) {
            const auto& tri = mesh.triangles[t];
            keys[t] =
                lbvhKey(mesh.positions[tri[0]], mesh.positions[tri[1]], mesh.positions[tri[2]],
                        frame.lo, frame.invExtent, static_cast<uint32_t>(t));
        });
        tbb::parallel_sort(keys.begin(), keys.end());
        m_triangles.resize(n);
        tbb::parallel_for(0, n, [&](int i) {
            const uint32_t id = static_cast<uint32_t>(keys[i] & 0xFFFFFFFFu);
            const auto& tri = mesh.triangles[id];
            m_triangles[i] = {mesh.positions[tri[0]], mesh.positions[tri[1]],
                              mesh.positions[tri[2]], id};
        });
        if (n == 1) return;
        // Internal nodes, each on its own (Karras §4), and every node's parent.
        m_nodes.resize(n - 1);
        std::vector<int32_t> parentOfNode(n - 1, -1), parentOfLeaf(n, -1);
        tbb::parallel_for(0, n - 1, [&](int i) {
            const LbvhChildren c = lbvhInternalNode(keys.data(), n, i);
            m_nodes[i].left = c.left;
            m_nodes[i].right = c.right;
            for (int32_t child : {c.left, c.right})
                (child < 0 ? parentOfLeaf[~child] : parentOfNode[child]) = i;
        });
        // Boxes bottom-up: from each leaf, climb while this thread is the second to reach the
        // parent (the first one's child box is then written); Karras §4's atomic counters.
        std::vector<int> visits(n - 1, 0);
        auto box = [&](int32_t child, Vec3& lo, Vec3& hi) {
            if (child < 0) {
                const LbvhTriangle& t = m_triangles[~child];
                lo = min(t.a, min(t.b, t.c));
                hi = max(t.a, max(t.b, t.c));
            } else {
                lo = m_nodes[child].lo;
                hi = m_nodes[child].hi;
            }
        };
        tbb::parallel_for(0, n, [&](int leaf) {
            int32_t node = parentOfLeaf[leaf];
            while (node >= 0) {
                if (std::atomic_ref<int>(visits[node]).fetch_add(1, std::memory_order_acq_rel) == 0)
                    return;
                Vec3 llo, lhi, rlo, rhi;
                box(m_nodes[node].left, llo, lhi);
                box(m_nodes[node].right, rlo, rhi);
                m_nodes[node].lo = min(llo, rlo);
                m_nodes[node].hi = max(lhi, rhi);
                std::atomic_thread_fence(std::memory_order_release);
                node = parentOfNode[node];
            }
        });
    });
}

int Lbvh::depth() const {
    if (m_triangles.empty()) return 0;
    if (m_nodes.empty()) return 1;
    int deepest = 0;
    std::vector<std::pair<int32_t, int>> stack{{0, 1}};
    while (!stack.empty()) {
        auto [node, level] = stack.back();
        stack.pop_back();
        for (int32_t child : {m_nodes[node].left, m_nodes[node].right}) {
            if (child < 0)
                deepest = std::max(deepest, level + 1);
            else
                stack.push_back({child, level + 1});
        }
    }
    return deepest;
}

}  // namespace sdft
