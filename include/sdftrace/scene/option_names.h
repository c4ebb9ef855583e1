// Names of enumerated render options, shared by the scene file and the CLI so both accept the same
// words. Each parse returns false for an unknown name; `*Names` lists the accepted ones.
#pragma once

#include <string>

#include "sdftrace/scene/scene.h"

namespace sdft {

inline bool parseGridTracer(const std::string& s, GridTracerKind& out) {
    if (s == "dda") return out = GridTracerKind::Dda, true;
    if (s == "sphere") return out = GridTracerKind::SphereTrace, true;
    return false;
}
inline const char* gridTracerNames() { return "dda, sphere"; }

inline bool parseCellIntersection(const std::string& s, CellIntersection& out) {
    if (s == "midpoint") return out = CellIntersection::Midpoint, true;
    if (s == "false-position") return out = CellIntersection::FalsePosition, true;
    return false;
}
inline const char* cellIntersectionNames() { return "midpoint, false-position"; }

inline bool parseGridNormal(const std::string& s, GridNormal& out) {
    if (s == "analytic") return out = GridNormal::AnalyticTrilinear, true;
    if (s == "difference-of-interpolations")
        return out = GridNormal::DifferenceOfInterpolations, true;
    if (s == "interpolation-of-differences")
        return out = GridNormal::InterpolationOfDifferences, true;
    return false;
}
inline const char* gridNormalNames() {
    return "analytic, difference-of-interpolations, interpolation-of-differences";
}

inline bool parseShadowMethod(const std::string& s, ShadowMethod& out) {
    if (s == "hard") return out = ShadowMethod::Hard, true;
    if (s == "soft") return out = ShadowMethod::Soft, true;
    if (s == "distributed") return out = ShadowMethod::Distributed, true;
    if (s == "pcf") return out = ShadowMethod::Pcf, true;
    if (s == "evsm") return out = ShadowMethod::Evsm, true;
    return false;
}
inline const char* shadowMethodNames() { return "hard, soft, distributed, pcf, evsm"; }

}  // namespace sdft
