// Closing films: the signs of an open mesh at the cost of a closed one's.
//
// The boundary of a triangle mesh M, as a chain, is its directed edges net of their reverses (with
// multiplicity): zero for a watertight mesh, the hole rims of a scan. Coning each connected piece
// of this rim from one apex, oriented against it, gives a small film F (one triangle per rim edge)
// with M + F a 2-cycle, whose winding number W is an integer everywhere: it changes only by the
// signed crossings of M and F, so it is carried from one sample to the next exactly. The
// generalized winding number of M (Jacobson et al. 2013) is then w_M = W - w_F, with w_F a sum over
// the few film triangles.
//
// Even that sum is needed only now and then: w_M jumps by the signed crossings of M and is
// otherwise smooth, its gradient being the Biot-Savart integral over the rim, |grad w_M(p)| <=
// (1/4 pi) * integral over the rim of dl / |p - l|^2. A step of length s changes it by at most s
// times that bound, so a carried value is trusted while it stays farther than its accumulated
// error from 1/2. Each rim piece is a closed loop, so from afar its field falls off like a
// dipole's: with the loop in a ball of radius R at distance g and of length L, the integral is at
// most 2 L R / g^3 (the integrand's variation over the ball, as the loop integral of dl is 0).
// Many loops (a scan's holes) are grouped by a tree: a group far from p is bounded at once by
// 2 sum(L_i R_i) / g^3, g its ball's distance, so the bound costs about log(loops) where most are
// far.
#pragma once

#include <vector>

#include "sdftrace/bake/segment_crossing.h"
#include "sdftrace/bake/triangle_mesh.h"

namespace sdft {

class ClosingFilm {
  public:
    explicit ClosingFilm(const TriangleMesh& mesh);  // mesh must outlive the film

    bool empty() const { return m_films.empty(); }  // M is already a 2-cycle (watertight)
    // M's triangles followed by the films' (the apexes appended to M's positions); M itself
    // when it is watertight (no copy: M must outlive the films).
    const TriangleMesh& closedMesh() const { return m_films.empty() ? *m_source : m_closed; }
    const std::vector<CrossingTriangle>& filmTriangles() const { return m_films; }
    size_t components() const { return m_cones.size(); }  // connected pieces of the rim

    // w_F(p): the films' winding number, summing exact solid angles.
    double winding(Vec3 p) const;
    // The same in float with a polynomial atan2: within fastError() of winding(p) (but within a
    // hair of a film triangle's plane, where no carried count is trusted either).
    // With `slack`: cones so far from p that they subtend less than 0.01 are only bounded (a
    // triangle subtends at most its area over the squared distance), their bounds added to it.
    float windingFast(Vec3 p, float* slack = nullptr) const;
    float fastError() const { return 1e-4f + 1e-6f * static_cast<float>(m_films.size()); }
    // An upper bound of |grad w_M| over the box [lo, hi] (+infinity when it touches the rim).
    double gradientBound(Vec3 lo, Vec3 hi) const;
    // A first-order model of w_F about `centre` for the ball of radius `half` around it, which no
    // film triangle may meet (the caller checks, trianglesNear): for p in the ball,
    // |w_F(p) - value - dot(gradient, p - centre)| <= error + quadratic * |p - centre|^2.
    // Cones whose films together subtend less than 0.01 from every point of the ball are only
    // bounded (in error); the others are summed at the centre, their gradient the Biot-Savart
    // integral over their rims, their Hessian bounded by it (|H| <= integral 2 dl / |p - l|^3).
    // `valid` is false where the ball reaches the rim.
    struct Taylor {
        float value = 0, error = 0;
        Vec3 gradient;
        float quadratic = 0;
        bool valid = false;
    };
    Taylor taylor(Vec3 centre, float half) const;
    // The film triangles (indices into filmTriangles()) whose bounds meet the box [lo, hi] grown
    // by eps: those a segment inside the box may cross. Found through the loops' tree.
    void trianglesNear(Vec3 lo, Vec3 hi, float eps, std::vector<uint32_t>& out) const;

  private:
    struct Edge {
        Vec3 a, b;
    };
    // A binary tree over the rim edges for the gradient bound: a node's edges lie in its ball.
    struct Node {
        Vec3 centre;
        float radius = 0;
        float length = 0;  // of its edges
        int left = -1, right = -1;
        int first = 0, count = 0;  // a leaf's edges in m_edges
    };
    int build(int first, int count);
    // A binary tree over the loops (the rim's pieces), for the bound's far ones.
    struct Group {
        Vec3 centre;
        float radius = 0;        // a ball holding its loops' balls
        float length = 0;        // sum of its loops' lengths L_i
        float lengthRadius = 0;  // sum of L_i R_i, R_i the radius of loop i's ball
        float area = 0;          // of its cones, which lie in its ball
        int left = -1, right = -1;
        int cone = -1;  // a leaf's loop
    };
    int buildGroups(int* cones, int count);

    const TriangleMesh* m_source;
    TriangleMesh m_closed;  // empty when M is watertight
    std::vector<CrossingTriangle> m_films;
    // Per rim piece, its apex and film triangles; their other corners as arrays for windingFast.
    struct Cone {
        Vec3 apex;
        size_t first = 0, count = 0;  // its triangles in m_films, its edges in m_edges
        int root = -1;                // its edges' tree in m_nodes
        float radius = 0;             // the ball around the apex holding the cone
        float area = 0;               // of the cone
    };
    std::vector<Cone> m_cones;
    std::vector<float> m_corners[6];  // b.x, b.y, b.z, c.x, c.y, c.z
    std::vector<Edge> m_edges;
    std::vector<Node> m_nodes;
    std::vector<Group> m_groups;
    double coneGradientBound(const Cone& cone, Vec3 centre, double half) const;
    float coneWinding(const Cone& cone, Vec3 p) const;  // times 4 pi / 2
    bool addCone(const Cone& cone, Vec3 centre, float half, Taylor& t) const;
    double rimSum(const Cone& cone, Vec3 centre, double half, int power) const;
};

}  // namespace sdft
