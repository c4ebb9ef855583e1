// Inside or outside of a possibly open mesh M by its generalized winding number (Jacobson et al.
// 2013), decided the way the exact bakes decide it (closing_film.h): W, the integer winding number
// of M closed by its films, from the hierarchical sum over M + F, rounded; then w_M = W - w_F from
// the few film triangles, in float with a bound on its error, summed exactly where that bound
// reaches 1/2. A view of the film and of the closed mesh's winding tree, both owned elsewhere.
#pragma once

#include <cmath>
#include <cstdint>

#include "sdftrace/bake/closing_film.h"
#include "sdftrace/bake/winding_number.h"

namespace sdft {

class WindingSign {
  public:
    // `closed` is the WindingNumber of film.closedMesh().
    WindingSign(const ClosingFilm& film, const WindingNumber& closed)
        : m_film(film), m_closed(closed) {}

    // The winding numbers at a point: W of the mesh closed by its films, exact; the mesh's own,
    // w_M = W - w_F, within `error`.
    struct Carried {
        int32_t closed = 0;
        float winding = 0, error = 0;
        bool inside() const { return winding > 0.5f; }
        // Whether the value can decide the sign.
        bool decided() const { return std::fabs(winding - 0.5f) > error; }
    };

    // From scratch: W is the hierarchical sum of mesh and films at a coarse beta (1.5), rounded
    // (at the tree's own beta where that lands within 0.3 of a half).
    Carried evaluate(Vec3 p) const {
        double w = m_closed.fast(p, 1.5);
        if (std::fabs(w - std::round(w)) > 0.2) w = m_closed.fast(p);
        return refresh(m_film, p, static_cast<int32_t>(std::lround(w)));
    }
    // With W known: w_M from the films' float sum, or their exact one when that is within its
    // error of 1/2 (reads only the films).
    static Carried refresh(const ClosingFilm& film, Vec3 p, int32_t closed) {
        if (film.empty()) return {closed, static_cast<float>(closed), 0.0f};
        // Far cones only bounded first, then all summed, then the exact sum.
        float slack = 0;
        const float near = film.windingFast(p, &slack);
        Carried c{closed, static_cast<float>(closed) - near, film.fastError() + slack};
        if (!c.decided() && slack > 0)
            c = {closed, static_cast<float>(closed) - film.windingFast(p), film.fastError()};
        if (!c.decided()) c = {closed, static_cast<float>(closed - film.winding(p)), 1e-6f};
        return c;
    }
    // w_M itself (not only its side of 1/2): W - w_F with the films summed exactly.
    double winding(Vec3 p) const {
        const Carried c = evaluate(p);
        return m_film.empty() ? static_cast<double>(c.closed) : c.closed - m_film.winding(p);
    }

  private:
    const ClosingFilm& m_film;
    const WindingNumber& m_closed;
};

}  // namespace sdft
