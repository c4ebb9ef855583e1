// Where the surface seen at a pixel was one frame earlier (issue 16), for RTSDF §2.5.2's temporal
// accumulation of moving scenes: per-object motion from the scene's top-level objects'
// placements (their outer translate / rotate / scale chains) at two instants. An animated scene
// keeps its structure from frame to frame (keyframes replace values only), so object k of one
// frame is object k of the next. Deforming objects (mesh sequences, keyframed radii, morphs) have
// no rigid motion: their points stay where they are and the history is left to the rejection
// tests of temporal.h.
#pragma once

#include <vector>

#include "sdftrace/field/node.h"
#include "sdftrace/field/tape.h"
#include "sdftrace/math/camera.h"

namespace sdft {

// Object to world: the chain of transform nodes above an object's shape, outermost first.
struct Placement {
    struct Step {
        NodeKind kind;  // Translate, Rotate or Scale
        float k[9];     // offset, row-major rotation, or factors (Node::params)
    };
    std::vector<Step> steps;

    // Adds a Translate, Rotate or Scale node as the next (inner) step.
    void append(const Node& n);
    Vec3 toLocal(Vec3 world) const;
    Vec3 toWorld(Vec3 local) const;
    // A local surface normal in world space (the inverse transpose), unit length.
    Vec3 normalToWorld(Vec3 local) const;
    bool sameShape(const Placement& other) const;  // the same kinds in the same order
};

bool isPlacementKind(NodeKind kind);  // Translate, Rotate or Scale

// The outer transform chain of `n` (and the node below it).
Placement placementOf(const NodePtr& n, NodePtr* shape = nullptr);

struct MovingObject {
    Tape field;    // the object's own field now, to tell which object a point lies on
    float box[6];  // its bounds, lo then hi (xform::boxDistance's layout)
    bool boundsDominate = false;  // the field is at least the distance to `bounds` outside them
    Placement now, before;
    bool rigid = false;  // `before` matches `now` in shape: points move with the placement
};

// The top-level objects of a scene (the root union's children, or the root) now and one frame
// earlier.
class SceneMotion {
  public:
    SceneMotion() = default;
    // `previousRoot` may be a described scene whose assets are still pending: only its placements
    // are read. Roots of different structure give objects without motion.
    SceneMotion(const NodePtr& previousRoot, const NodePtr& currentRoot);

    // The object whose surface p lies on (the smallest field value, as the union chooses); -1
    // when there is none.
    int objectAt(Vec3 p) const;
    // Where the point p of object `object` was one frame earlier (p itself for -1 or a
    // non-rigid object).
    Vec3 previousPosition(int object, Vec3 p) const;
    size_t size() const { return m_objects.size(); }
    const MovingObject& object(size_t i) const { return m_objects[i]; }

  private:
    std::vector<MovingObject> m_objects;
};

// Per-pixel motion of a rendered frame (2 floats per pixel: where the pixel's surface point was
// in the previous camera's image minus where its sample lies now, in pixels; zero on a miss, so
// jitter alone moves nothing) and the object each pixel shows (-1: a miss; 0 for every hit when
// there is no SceneMotion). `depth`, `now` and `jitter` are the frame's: primary rays through
// (x + 0.5 + jitter, y + 0.5 + jitter).
struct MotionVectors {
    std::vector<float> motion;       // 2 per pixel
    std::vector<int> objects;        // 1 per pixel
    std::vector<float> depthBefore;  // distance from the previous eye to the point's old position
    std::vector<uint8_t> visibleBefore;  // the old position was in front of the previous camera
};
MotionVectors motionVectors(const std::vector<float>& depth, const CameraDesc& now,
                            const float jitter[2], const CameraDesc& before,
                            const SceneMotion* motion);

}  // namespace sdft
