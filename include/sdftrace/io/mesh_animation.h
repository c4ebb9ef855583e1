// Meshes that move by themselves (issue 16): skeletal skinning and morph targets as assimp reads
// them from glTF, Collada, FBX, DirectX .x and its other formats with animation, posed at a time
// into the TriangleMesh the bakers take. Skinning is linear blend skinning (each vertex moved by
// the weighted sum of its joints' global transforms times their inverse bind matrices); morph
// targets add their weighted offsets from the base shape before skinning; a mesh without joints
// moves with its node's animated transform.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "sdftrace/io/mesh_io.h"

namespace sdft {

// One animation of a file: assimp's aiAnimation.
struct MeshClip {
    std::string name;                      // may be empty
    double duration = 0;                   // seconds
    bool skeletal = false, morph = false;  // what it animates
};

class AnimatedMesh {
  public:
    // The file's meshes, node hierarchy, joints, morph targets and animations; an unreadable or
    // empty file is an InputError naming it. A file without animation loads with no clips.
    static AnimatedMesh load(const std::string& path);

    const std::vector<MeshClip>& clips() const;
    // The clip of that name, -1 for none.
    int clipIndex(const std::string& name) const;
    // The clips' names for messages: "0 'walk', 1 'run'" ("0 (unnamed)" for an unnamed one).
    std::string clipList() const;

    // Every mesh of the file posed at `seconds` into clip `clip` (clamped to [0, duration]), in
    // the file's world frame, cleaned as loadMesh cleans a file (welded, degenerate triangles
    // dropped).
    TriangleMesh pose(int clip, double seconds, MeshReport* report = nullptr) const;

  private:
    struct Impl;
    std::shared_ptr<const Impl> m_impl;
};

}  // namespace sdft
