#include "sdftrace/render/ambient_occlusion.h"

namespace sdft {

AmbientOcclusionResult ambientOcclusion(const Tape& tape, Vec3 p, Vec3 n,
                                        const AmbientOcclusionOptions& o) {
    return ambientOcclusionTape(tape.view(), p, n, o);
}

}  // namespace sdft
