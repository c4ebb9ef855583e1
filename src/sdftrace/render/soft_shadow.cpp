#include "sdftrace/render/soft_shadow.h"

namespace sdft {

SoftShadowResult softShadow(const Tape& tape, Vec3 origin, Vec3 dir, float tMin, float tMax,
                            float tanRadius, const SoftShadowOptions& o, float jitter01) {
    return softShadowTape(tape.view(), origin, dir, tMin, tMax, tanRadius, o, jitter01);
}

void softShadowPacket(const Tape& tape, const std::vector<SoftShadowRay>& rays,
                      const SoftShadowOptions& o, std::vector<SoftShadowResult>& out,
                      SoftShadowScratch& s) {
    const int n = static_cast<int>(rays.size());
    s.marches.resize(n);
    s.live.clear();
    for (int i = 0; i < n; ++i) {
        const SoftShadowRay& r = rays[i];
        s.marches[i].start(r.origin, r.dir, r.tMin, r.tMax, r.tanRadius, o, r.jitter01,
                           softShadowEnd(tape.bounds(), r.origin, r.dir, r.tMin, r.tMax, o.bias));
        if (s.marches[i].active()) s.live.push_back(i);
    }
    const float invL = 1.0f / tape.lipschitz();
    while (!s.live.empty()) {
        const int m = static_cast<int>(s.live.size());
        s.x.resize(m);
        s.y.resize(m);
        s.z.resize(m);
        s.f.resize(m);
        for (int j = 0; j < m; ++j) {
            const Vec3 p = s.marches[s.live[j]].point();
            s.x[j] = p.x;
            s.y[j] = p.y;
            s.z[j] = p.z;
        }
        tape.evalBatch(s.x.data(), s.y.data(), s.z.data(), s.f.data(), m, s.batch);
        int kept = 0;
        for (int j = 0; j < m; ++j) {
            if (s.marches[s.live[j]].step(s.f[j] * invL - o.bias, o)) s.live[kept++] = s.live[j];
        }
        s.live.resize(kept);
    }
    out.resize(n);
    for (int i = 0; i < n; ++i) out[i] = s.marches[i].result();
}

}  // namespace sdft
