// The material at a point of a field: up to four materials with weights summing to one (smooth
// blends and morphs mix materials, as in Keinert et al. 2014, §4: CSG operators that also
// propagate material information). Plain data, shared by the CPU and device evaluators
// (field/tape_view.h).
#pragma once

#include "sdftrace/core/macros.h"
#include "sdftrace/math/vec.h"

namespace sdft {

struct MaterialBlend {
    static constexpr int kMax = 4;
    int id[kMax] = {-1, -1, -1, -1};
    float weight[kMax] = {0, 0, 0, 0};
    // Per entry, for textures: the point in the frame of the node that assigned the material
    // (inside that object's own transforms), and texture coordinates where the surface comes
    // from a grid that stores them (Liktor 2008, §5.5.2).
    Vec3 local[kMax];
    float u[kMax] = {0, 0, 0, 0}, v[kMax] = {0, 0, 0, 0};
    bool hasUv[kMax] = {false, false, false, false};
    int count = 0;

    SDFT_HOST_DEVICE static MaterialBlend single(int material, Vec3 local = Vec3(0.0f)) {
        MaterialBlend b;
        b.id[0] = material;
        b.weight[0] = 1;
        b.local[0] = local;
        b.count = 1;
        return b;
    }

    // (1-t) * a + t * b, keeping the kMax heaviest entries; entries of one material average
    // their points and coordinates.
    SDFT_HOST_DEVICE static MaterialBlend mix(const MaterialBlend& a, const MaterialBlend& b,
                                              float t) {
        if (t <= 0) return a;
        if (t >= 1) return b;
        Entry e[2 * kMax];
        int n = 0;
        for (int i = 0; i < a.count; ++i) n = add(e, n, a, i, a.weight[i] * (1 - t));
        for (int i = 0; i < b.count; ++i) n = add(e, n, b, i, b.weight[i] * t);
        // Keep the heaviest kMax entries, renormalized.
        MaterialBlend out;
        float total = 0;
        for (int slot = 0; slot < kMax && slot < n; ++slot) {
            int best = slot;
            for (int i = slot + 1; i < n; ++i)
                if (e[i].w > e[best].w) best = i;
            const Entry x = e[best];
            e[best] = e[slot];
            e[slot] = x;
            out.id[slot] = x.id;
            out.weight[slot] = x.w;
            out.local[slot] = x.w > 0 ? x.local / x.w : Vec3(0.0f);
            out.hasUv[slot] = x.uvWeight > 0;
            if (out.hasUv[slot]) {
                out.u[slot] = x.u / x.uvWeight;
                out.v[slot] = x.v / x.uvWeight;
            }
            total += x.w;
            out.count = slot + 1;
        }
        for (int i = 0; i < out.count; ++i) out.weight[i] /= total;
        return out;
    }

  private:
    struct Entry {
        int id;
        float w;
        Vec3 local;
        float u, v, uvWeight;
    };
    // Adds entry i of m with weight w to e[0..n), merging entries of one material; returns the
    // new count.
    SDFT_HOST_DEVICE static int add(Entry* e, int n, const MaterialBlend& m, int i, float w) {
        const float uw = m.hasUv[i] ? w : 0.0f;
        for (int j = 0; j < n; ++j) {
            if (e[j].id == m.id[i]) {
                e[j].local += m.local[i] * w;
                e[j].u += m.u[i] * uw;
                e[j].v += m.v[i] * uw;
                e[j].uvWeight += uw;
                e[j].w += w;
                return n;
            }
        }
        e[n] = {m.id[i], w, m.local[i] * w, m.u[i] * uw, m.v[i] * uw, uw};
        return n + 1;
    }
};

}  // namespace sdft
