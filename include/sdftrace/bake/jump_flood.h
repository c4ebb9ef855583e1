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

}  // namespace sdft
