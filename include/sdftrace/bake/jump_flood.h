// Mesh to SDF by 3D jump flooding (Tan et al. 2022, RTSDF §2.2; Rong and Tan 2006): grid vertices
// near a triangle become seeds holding their closest point on it (a conservative voxelization);
// passes with offsets N/2, N/4, ..., 1 let every vertex adopt the nearest seed point among its 27
// neighbours at the current offset. The distance is to that point; the sign comes from the
// generalized winding number (better than the paper's beta shell, which leaves interiors hollow).
#pragma once

#include "sdftrace/bake/exact_bake.h"

namespace sdft {

enum class JfaVariant {
    Plain,       // offsets N/2 ... 1
    OnePlusJfa,  // an extra offset-1 pass first (Rong and Tan's 1+JFA)
    JfaPlusTwo,  // two extra passes, offsets 2 and 1, at the end (JFA+2)
};

struct JfaStats {
    int passes = 0;
    double seconds = 0;
};

std::vector<float> bakeJumpFloodSamples(const TriangleMesh& mesh, const GridShape& shape,
                                        JfaVariant variant, int threads = 0,
                                        JfaStats* stats = nullptr);

// The conservative voxelization both propagation methods start from: every vertex within half a
// cell diagonal of a triangle holds its closest point on the nearest such triangle; others hold
// kNoSeed in x.
constexpr float kNoSeed = 1e30f;
std::vector<Vec3> seedClosestPoints(const TriangleMesh& mesh, const GridShape& shape);

// Signed distances from propagated seed points (kNoSeed: unreached), signed by the winding number.
std::vector<float> signedFromSeeds(const TriangleMesh& mesh, const GridShape& shape,
                                   const std::vector<Vec3>& seeds, int threads);

// Liktor 2008, §3.2: Danielsson's vector distance transform in 3D: a forward raster sweep in which
// each vertex adopts the nearest seed point among its 13 already-visited neighbours, then the same
// sweep backward over the other 13. Two passes, linear time; "approximately right" distances.
std::vector<float> bakeDanielssonSamples(const TriangleMesh& mesh, const GridShape& shape,
                                         int threads = 0);

}  // namespace sdft
